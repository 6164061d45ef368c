"""co.hold on a scene file's path, and a line whose joints agree only to rounding (issue 45)."""

import numpy as np
import xarray as xr

import cable_ocp as co

SCENE = """
name = "small_lowering"
[cable]
length = 30.0
diameter = 0.04
density = 7850.0
[model]
elements = 3
[top]
motion = "fixed"
[end.payload]
mass = 1000.0
volume = 0.128
drag_area = 1.0
drag = 1.2
[winch]
drum_radius = 1.0
rate_max = 2.0
acceleration_max = 1.5
[winch.line]
pay_out_max = 30.0
haul_in_max = 0.0
element_length = 10.0
[seabed]
clearance = 5.0
minimum_clearance = 2.0
[seabed.grid]
file = "flat50.nc"
[lowering]
land_time = 60.0
height = 5.0
tension_min = 1000.0
tension_max = 100000.0
[numerics]
duration = 80.0
step = 0.05
output_every = 10
"""


def test_a_hold_takes_a_scene_files_path_and_a_line_out_equal_to_rounding(tmp_path):
    """The reduced model's top joint at 30.000000000000007 m against the plant's
    30.000000000000004 m is the same joint (it was refused as 'beyond' it, after the work)."""
    axis = np.arange(-200.0, 201.0, 5.0)
    flat = xr.Dataset(
        {"elevation": (("x", "y"), np.full((axis.size, axis.size), -50.0))},
        coords={"x": axis, "y": axis},
    )
    flat.to_netcdf(tmp_path / "flat50.nc")  # 50 m deep
    path = tmp_path / "small_lowering.toml"
    path.write_text(SCENE)
    held = co.hold(str(path))
    assert held.success, held.status
    assert held.deviation < 1e-6
    assert co.hold(path, line_out=50.0).success
