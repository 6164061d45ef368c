"""The synthetic bathymetry grid of the bundled ``deploy`` scene (``models/data/deploy_grid.nc``).

A made-up site, not a real survey: a seabed about 1020 m deep under the vessel, falling gently
down-current (1.5 % along x), with two low mounds and seeded small-scale relief, on a 10 m grid
over x in [-100, 400] m, y in [-150, 150] m. A frame lowered from the vessel drifts down-current
by tens of metres as the line goes out (the sheared current of the scene); the grid covers its
whole path. Every feature is smooth on the grid, so the B-spline through it is the seabed meant.

Regenerate the file (bit for bit, by its seed)::

    python -m cable_ocp.studies.deploy_grid models/data/deploy_grid.nc
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from cable_ocp.studies.survey_grid import grid_axis, scene_grid, smoothed_noise, write_grid

SPACING = 10.0  # m
X_RANGE = (-100.0, 400.0)  # m, down-current
Y_RANGE = (-150.0, 150.0)  # m, across it
BASE = -1020.0  # m, the seabed under the vessel
SEED = 27


def deploy_elevation(x: np.ndarray, y: np.ndarray, seed: int = SEED) -> np.ndarray:
    """Elevation of the deploy site on the grid ``x`` by ``y`` (m, up; shape (nx, ny)).

    Parameters
    ----------
    x, y : array, m
        Strictly increasing axes, :data:`SPACING` apart, down the current and across it.
    seed : int
        Seed of the small-scale relief.
    """
    X, Y = np.meshgrid(x, y, indexing="ij")
    slope = -0.015 * X  # falling down-current
    mounds = 6.0 * np.exp(-(((X - 160.0) / 40.0) ** 2) - ((Y + 40.0) / 30.0) ** 2)
    mounds += 4.0 * np.exp(-(((X - 20.0) / 30.0) ** 2) - ((Y - 70.0) / 40.0) ** 2)
    relief = smoothed_noise(X.shape, seed)
    relief *= 0.3 / relief.std()
    return BASE + slope + mounds + relief


def deploy_grid(seed: int = SEED) -> xr.Dataset:
    """The grid as a Dataset: ``elevation`` (m) over ``x``, ``y`` (m), CF attributes."""
    axes = (grid_axis(X_RANGE, SPACING), grid_axis(Y_RANGE, SPACING))
    return scene_grid("deploy", axes, deploy_elevation(*axes, seed), seed,
                      ("down-current", "across the current"))  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    """Write the grid to the netCDF file named on the command line."""
    return write_grid(deploy_grid, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
