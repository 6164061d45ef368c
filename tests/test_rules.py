"""One field rule for scene fields and settings fields (cable_ocp.scene.rules, issue 41).

The scene's ``_param`` and the settings' ``Rule`` declare a :class:`FieldRule`; its one check
finds the fault, and each side words it: a scene by the field's path, a settings class by its
attribute.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pytest

from cable_ocp.control.checks import Rule, check_fields, problem
from cable_ocp.scene.rules import Fault, FieldRule
from cable_ocp.scene.schema import Numerics


def test_a_settings_rule_is_a_field_rule():
    rule = Rule("number", low=0, high=1, unit="s")
    assert isinstance(rule, FieldRule)
    assert (rule.kind, rule.ge, rule.le, rule.unit) == ("float", 0, 1, "s")
    with pytest.raises(ValueError, match="Rule kind = 'real': must be one of integer, number"):
        Rule("real")


@pytest.mark.parametrize(
    ("value", "fault"),
    [
        (0.5, None),
        (True, Fault("type", "a number")),
        ("1", Fault("type", "a number")),
        (math.nan, Fault("finite", "finite")),
        (2.0, Fault("range", "<= 1")),
        (-1.0, Fault("range", ">= 0")),
        (None, Fault("missing", "set")),
    ],
)
def test_the_one_check_finds_each_fault(value, fault):
    assert FieldRule("float", ge=0, le=1).fault(value) == fault


def test_the_same_fault_worded_for_a_scene_and_for_settings():
    """A step of -1 s: the scene names its path and whole range, the settings their attribute."""
    with pytest.raises(ValueError, match=r"^numerics\.step = -1\.0 is out of range: must be > 0"):
        Numerics(step=-1.0)

    @dataclass
    class Settings:
        step: float = -1.0

    with pytest.raises(ValueError, match=r"^Settings\.step = -1\.0 s: must be > 0$"):
        check_fields(Settings(), {"step": Rule("number", above=0, unit="s")})


def test_an_integer_too_large_for_a_float_is_judged_by_its_range():
    """10**400 was an OverflowError from math.isfinite in the settings' check."""
    assert problem(Rule("integer", low=1, high=100), 10**400) == "must be <= 100"
    assert problem(Rule("number", low=1), 10**400) == "must be finite"
    assert problem(Rule("choice", choices=("a", "b")), "c") == "must be one of a, b"
