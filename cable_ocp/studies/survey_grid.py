"""The synthetic bathymetry grid of the bundled ``survey`` scene (``models/data/survey_grid.nc``).

A made-up site, not a real survey: a seabed 305 m deep and flat under the end's start (the
300 m cable hangs from the surface with its end about 5 m above it), rising by a gentle slope
along the tow, crossed by a ridge, with sand waves and a scour pit, and seeded small-scale relief
(smoothed noise) such as a multibeam survey shows. Every feature is smooth on the 4 m grid, so the
B-spline through it (CONVENTIONS.md §5) is the seabed the scene means.

Regenerate the file (bit for bit, by its seed)::

    python -m cable_ocp.studies.survey_grid models/data/survey_grid.nc

The parts every synthetic grid is made of (its axes, its seeded relief, the Dataset and the
script's command line) live here, for :mod:`~cable_ocp.studies.deploy_grid`
and :mod:`~cable_ocp.studies.random_site` too.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import numpy as np
import xarray as xr
from scipy.ndimage import gaussian_filter

from cable_ocp.drive.vessel import smoothstep

SPACING = 4.0  # m
X_RANGE = (-60.0, 300.0)  # m, along the tow
Y_RANGE = (-80.0, 120.0)  # m, across it
BASE = -305.0  # m, the flat seabed under the start
SEED = 16


def grid_axis(bounds: tuple[float, float], spacing: float) -> np.ndarray:
    """A grid's axis from ``bounds[0]`` to ``bounds[1]`` (both included), ``spacing`` apart, m."""
    return np.arange(bounds[0], bounds[1] + spacing / 2, spacing)


def smoothed_noise(shape: tuple[int, int], seed: int) -> np.ndarray:
    """A site's small-scale relief before scaling: seeded unit normal noise smoothed over 2 cells.

    Parameters
    ----------
    shape : (int, int)
        The grid's ``(len(x), len(y))``.
    seed : int
        Seed of the noise: the same seed gives the same relief, bit for bit.
    """
    return gaussian_filter(np.random.default_rng(seed).normal(0.0, 1.0, shape), sigma=2.0)


def survey_elevation(x: np.ndarray, y: np.ndarray, seed: int = SEED) -> np.ndarray:
    """Elevation of the survey site on the grid ``x`` by ``y`` (m, up; shape (nx, ny)).

    Parameters
    ----------
    x, y : array, m
        Strictly increasing axes, :data:`SPACING` apart, along and across the tow.
    seed : int
        Seed of the small-scale relief.
    """
    X, Y = np.meshgrid(x, y, indexing="ij")
    onset = smoothstep((X - 20.0) / 40.0)[0]  # flat under the start, features from x = 20 m on
    slope = 0.03 * np.maximum(X - 20.0, 0.0) * onset  # 3 m per 100 m along the tow
    across = (X - 105.0) * np.cos(np.radians(25.0)) + (Y - 20.0) * np.sin(np.radians(25.0))
    ridge = 10.0 * np.exp(-((across / 14.0) ** 2)) * np.exp(-(((Y - 20.0) / 90.0) ** 2))
    waves = 0.6 * np.sin(2 * np.pi * (X * 0.9 + Y * 0.44) / 30.0) * onset
    pit = -2.5 * np.exp(-(((X - 150.0) / 12.0) ** 2) - ((Y - 32.0) / 10.0) ** 2)
    relief = smoothed_noise(X.shape, seed)
    relief *= 0.25 / relief.std() * onset
    return BASE + slope + ridge + waves + pit + relief


def survey_grid(seed: int = SEED) -> xr.Dataset:
    """The grid as a Dataset: ``elevation`` (m) over ``x``, ``y`` (m), CF attributes."""
    axes = (grid_axis(X_RANGE, SPACING), grid_axis(Y_RANGE, SPACING))
    return scene_grid("survey", axes, survey_elevation(*axes, seed), seed,
                      ("along the tow", "across the tow"))  # fmt: skip


def scene_grid(
    scene: str,
    axes: tuple[np.ndarray, np.ndarray],
    elevation: np.ndarray,
    seed: int,
    names: tuple[str, str],
) -> xr.Dataset:
    """The synthetic grid of a bundled scene, titled and sourced after it (:func:`grid_dataset`).

    Parameters
    ----------
    scene : str
        The bundled scene's name; its script is ``cable_ocp.studies.<scene>_grid``.
    axes : (array, array), m
        The grid's ``x`` and ``y`` (:func:`grid_axis`).
    elevation : array (len(x), len(y)), m
        Seabed elevation, up from the sea surface.
    seed : int
        The seed of its small-scale relief, named in the file's source.
    names : (str, str)
        What the x and y axes run along.
    """
    return grid_dataset(
        *axes, elevation, f"synthetic bathymetry of the cable_ocp {scene} scene",
        f"cable_ocp.studies.{scene}_grid (seed {seed})", names,
    )  # fmt: skip


def grid_dataset(
    x: np.ndarray,
    y: np.ndarray,
    elevation: np.ndarray,
    title: str,
    source: str,
    axes: tuple[str, str],
) -> xr.Dataset:
    """A bathymetry grid as the scenes read it: ``elevation`` (m, up) over ``x``, ``y`` (m).

    Parameters
    ----------
    x, y : array, m
        The grid's axes (:func:`grid_axis`).
    elevation : array (len(x), len(y)), m
        Seabed elevation, up from the sea surface.
    title, source : str
        The file's CF attributes.
    axes : (str, str)
        What the x and y axes run along (their long names).
    """
    metres = {"units": "m"}
    return xr.Dataset(
        {
            "elevation": (
                ("x", "y"),
                elevation,
                {**metres, "long_name": "seabed elevation, up from the sea surface"},
            )
        },
        coords={
            "x": ("x", x, {**metres, "long_name": f"{axes[0]} (local metric)"}),
            "y": ("y", y, {**metres, "long_name": f"{axes[1]} (local metric)"}),
        },
        attrs={"title": title, "source": source},
    )


def write_grid(build: Callable[[], xr.Dataset], description: str, argv: list[str] | None) -> int:
    """A grid script's command line: write ``build()`` to the netCDF file named in ``argv``."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("path", type=Path, help="netCDF file to write")
    args = parser.parse_args(argv)
    build().to_netcdf(args.path)
    print(f"wrote {args.path} ({args.path.stat().st_size / 1024:.0f} KiB)")
    return 0


def main(argv: list[str] | None = None) -> int:
    """Write the grid to the netCDF file named on the command line."""
    return write_grid(survey_grid, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
