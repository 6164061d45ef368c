"""Random bathymetry grids for the robustness benchmark: a made-up site drawn from a few numbers.

A site is flat under the end's start (``x < 20 m``) and, from there on (a smoothstep over 40 m),
rises or falls by a slope along the tow, is crossed by a ridge at an angle, carries sand waves and
seeded small-scale relief (smoothed noise, as a multibeam survey shows), like the bundled survey
grid (:mod:`cable_ocp.studies.survey_grid`). Every feature is smooth on the 5 m grid. The grid
covers every end path of the benchmark's tows (x in [-100, 400] m, y in [-150, 200] m) and is
written as netCDF (``elevation`` over ``x``, ``y``, m), the format of ``[seabed.grid]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from cable_ocp.drive.vessel import smoothstep
from cable_ocp.studies.survey_grid import grid_axis, smoothed_noise

SPACING = 5.0  # m
X_RANGE = (-100.0, 400.0)  # m, along the tow
Y_RANGE = (-150.0, 200.0)  # m, across it
FLAT_UNTIL, ONSET = 20.0, 40.0  # m: flat for x < 20 m, the features in full from x = 60 m


def site_elevation(
    x: np.ndarray, y: np.ndarray, relief: dict, base: float, start: float = 0.0
) -> np.ndarray:
    """Elevation (m, up; shape (len(x), len(y))) of a site on the grid ``x`` by ``y`` (m).

    Parameters
    ----------
    x, y : array, m
        Strictly increasing axes, :data:`SPACING` apart.
    relief : dict
        ``slope`` (rise per metre along x), ``ridge_height`` (m), ``ridge_x`` (m, where the ridge
        crosses y = 0), ``ridge_angle`` (rad, from the y axis), ``ridge_width`` (m),
        ``waves`` (m, sand-wave amplitude), ``wavelength`` (m), ``roughness`` (m, standard
        deviation of the small-scale relief) and ``seed`` (of that relief).
    base : float, m
        Elevation of the flat part under the start.
    start : float, m
        Where the end starts along x: the site is flat up to :data:`FLAT_UNTIL` beyond it.
    """
    X, Y = np.meshgrid(x, y, indexing="ij")
    onset = smoothstep((X - start - FLAT_UNTIL) / ONSET)[0]
    slope = relief["slope"] * np.maximum(X - start - FLAT_UNTIL, 0.0) * onset
    angle = relief["ridge_angle"]
    across = (X - relief["ridge_x"]) * np.cos(angle) + Y * np.sin(angle)
    ridge = relief["ridge_height"] * np.exp(-((across / relief["ridge_width"]) ** 2)) * onset
    waves = relief["waves"] * np.sin(2 * np.pi * (X + 0.4 * Y) / relief["wavelength"]) * onset
    rough = smoothed_noise(X.shape, relief["seed"])
    rough *= relief["roughness"] / rough.std() * onset
    return base + slope + ridge + waves + rough


def write_site(
    path: str | Path,
    relief: dict,
    base: float,
    x_range: tuple[float, float] = X_RANGE,
    y_range: tuple[float, float] = Y_RANGE,
    start: float = 0.0,
) -> Path:
    """Write the site's grid to the netCDF file ``path``; returns the path.

    ``relief`` and ``base`` (m) as in :func:`site_elevation`; ``x_range``, ``y_range`` (m) the
    area it covers (by default every end path of the paper_hill variants), ``start`` (m) where
    the end starts along x.
    """
    x, y = grid_axis(x_range, SPACING), grid_axis(y_range, SPACING)
    metres = {"units": "m"}
    grid = xr.Dataset(
        {"elevation": (("x", "y"), site_elevation(x, y, relief, base, start), metres)},
        coords={"x": ("x", x, metres), "y": ("y", y, metres)},
        attrs={"source": f"cable_ocp.studies.random_site {relief}"},
    )
    grid.to_netcdf(path)
    return Path(path)
