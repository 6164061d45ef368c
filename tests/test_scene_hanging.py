"""A line that cannot hang in still water is refused when the scene is built (issue 45, item 2).

The cases differ from the issue's (a 0.256 m^3 float on the paper's rope or on deploy's): a
60 mm rope 200 m long, a float of 1.5 m^3, an upward end force without a payload.
"""

import math

import numpy as np
import pytest

from cable_ocp.scene.hanging import _drop
from cable_ocp.scene.schema import SceneError, scene_from_dict

ROPE = {"length": 200.0, "diameter": 0.06, "density": 7850.0}
BASE = {
    "cable": ROPE,
    "model": {"elements": 8},
    "top": {},
    "winch": {"top_length_max": 30.0},
    "numerics": {"duration": 1.0, "step": 0.05},
}
WEIGHT = (7850.0 - 1025.0) * math.pi * 0.06**2 / 4 * 9.81  # N/m submerged


def scene(end: dict, **tables):
    return scene_from_dict({**BASE, "end": end, **tables})


def test_a_float_without_a_sideways_pull_is_refused_naming_the_payload_and_the_least_mass():
    with pytest.raises(SceneError) as caught:
        scene({"payload": {"mass": 200.0, "volume": 1.5}})
    message = str(caught.value)
    assert caught.value.path == "end.payload"
    assert "end.payload.volume = 1.5 m^3 with end.payload.mass = 200.0 kg" in message
    assert "slack bight" in message and "rule:" in message
    assert "end.payload.mass >= 1537.5 kg" in message  # its displaced water


def test_an_upward_end_force_on_a_sinking_rope_is_refused_naming_end_force():
    with pytest.raises(SceneError, match=r"^end\.force: .*end\.force\[2\] = 500\.0 N"):
        scene({"force": [0.0, 0.0, 500.0]})


def test_a_float_that_would_lift_the_end_above_the_surface_is_refused_with_the_limit():
    lift = 0.6 * WEIGHT * 200.0  # over half the rope's weight: above the surface
    volume = lift / (1025.0 * 9.81)
    with pytest.raises(SceneError) as caught:
        scene({"force": [3000.0, 0.0, 0.0], "payload": {"mass": 0.0, "volume": volume}})
    message = str(caught.value)
    assert caught.value.path == "end.payload" and "above the sea surface" in message
    # With the top at the surface the limit is half the rope's submerged weight.
    assert f"largest lift that keeps the end under water is {WEIGHT * 100:.4g} N" in message


def test_the_same_float_in_air_or_with_enough_mass_hangs():
    payload = {"mass": 1600.0, "volume": 1.5}
    assert scene({"payload": payload}).end.payload.mass == 1600.0
    dry = {"submerged": False}
    floating = scene({"payload": {"mass": 0.0, "volume": 1.5}}, environment=dry)
    assert not floating.environment.submerged


def test_a_float_under_water_with_a_sideways_pull_is_allowed_and_hangs_where_the_rule_says():
    """The rule's catenary is the model's statics: the end hangs below the surface, bonds pull."""
    from cable_ocp import simulate

    lift = 0.3 * WEIGHT * 200.0
    volume = lift / (1025.0 * 9.81)
    run = simulate(scene({"force": [3000.0, 0.0, 0.0], "payload": {"mass": 0.0, "volume": volume}}))
    expected = -_drop(WEIGHT, 200.0, 3000.0, lift)
    assert run.end[0, 2] < 0
    assert run.end[0, 2] == pytest.approx(expected, abs=0.02 * 200.0)
    assert np.all(run.signed_tensions[0] > 0)
