"""The parts the synthetic bathymetry grids share (studies/survey_grid.py), and a random site."""

import numpy as np
import pytest

from cable_ocp.studies.random_site import FLAT_UNTIL, ONSET, site_elevation
from cable_ocp.studies.survey_grid import grid_axis, scene_grid, smoothed_noise


def test_a_grid_axis_includes_both_ends_at_its_spacing():
    axis = grid_axis((-30.0, 45.0), 7.5)
    assert axis[0] == -30.0 and axis[-1] == 45.0
    np.testing.assert_allclose(np.diff(axis), 7.5)


def test_the_seeded_relief_is_the_same_for_a_seed_and_another_for_another():
    first, again = smoothed_noise((12, 9), 3), smoothed_noise((12, 9), 3)
    np.testing.assert_array_equal(first, again)
    assert not np.allclose(first, smoothed_noise((12, 9), 4))


def test_a_random_site_is_flat_at_its_base_before_its_features_begin():
    relief = {
        "slope": 0.1, "ridge_height": 4.0, "ridge_x": 300.0, "ridge_angle": 0.2,
        "ridge_width": 15.0, "waves": 0.4, "wavelength": 25.0, "roughness": 0.2, "seed": 8,
    }  # fmt: skip
    start = 35.0
    x, y = grid_axis((0.0, 200.0), 5.0), grid_axis((-20.0, 20.0), 5.0)
    elevation = site_elevation(x, y, relief, base=-250.0, start=start)
    flat = x <= start + FLAT_UNTIL
    np.testing.assert_array_equal(elevation[flat], -250.0)
    assert np.all(elevation[x >= start + FLAT_UNTIL + ONSET] > -250.0 - 1.5)
    assert elevation[~flat].std() > 0.1


@pytest.mark.parametrize("scene", ["survey", "deploy"])
def test_a_scene_grid_names_its_scene_and_seed(scene):
    axes = (grid_axis((0.0, 20.0), 10.0), grid_axis((0.0, 10.0), 10.0))
    grid = scene_grid(scene, axes, np.zeros((3, 2)), 5, ("along", "across"))
    assert grid.attrs["title"] == f"synthetic bathymetry of the cable_ocp {scene} scene"
    assert grid.attrs["source"] == f"cable_ocp.studies.{scene}_grid (seed 5)"
    assert grid["x"].attrs["long_name"] == "along (local metric)"
    assert grid["elevation"].dims == ("x", "y")
