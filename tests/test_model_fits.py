"""simulate's ``model=``: a model of another scene is refused by name, a reduced one is taken."""

import pytest

import cable_ocp as co
from cable_ocp.model.cable import CableModel


def test_a_model_built_for_another_scene_is_refused_naming_what_differs():
    hanging = co.load_scene("hanging")
    other = CableModel.from_scene(hanging.updated({"cable.diameter": 0.03}))
    with pytest.raises(ValueError, match=r"^model: built for another scene \(.*element"):
        co.simulate(hanging, model=other)


def test_a_reduced_model_of_the_same_scene_is_taken():
    scene = co.load_scene("hanging").updated({"numerics.duration": 1.0})
    run = co.simulate(scene, model=CableModel.from_scene(scene, elements=8))
    assert run.physics.success


def test_a_model_that_is_no_model_is_a_type_error():
    with pytest.raises(TypeError, match="model: expected a CableModel, got str"):
        co.simulate("hanging", model="hanging")
