"""The lowering benchmark's draws and rows (cable-ocp bench --only lowering)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cable_ocp.studies import bench_lowering as bl


def test_the_draws_are_seeded_and_inside_their_stated_ranges():
    ranges = bl.LoweringRanges()
    cases = bl.lowering_cases(20, seed=4)
    assert cases == bl.lowering_cases(20, seed=4) and cases != bl.lowering_cases(20, seed=5)
    for case in cases:
        assert ranges.depth[0] <= case["seabed.clearance"] <= ranges.depth[1]
        assert ranges.payload_mass[0] - 5 <= case["end.payload"]["mass"] <= ranges.payload_mass[1]
        sea = case.get("top.heave", {}).get("sea_state")
        if sea:
            assert ranges.significant_height[0] <= sea["significant_height"] <= 2.5
        lowering = case["lowering"]
        assert lowering["land_time"] + bl.HOLD == case["numerics.duration"]
        # The line's shortest (3/2 Delta + Delta/2) fits under the start.
        assert case["cable.length"] >= 2 * case["winch.line"]["element_length"]


@pytest.mark.parametrize(("load", "depth"), [(5e3, 200.0), (1.5e5, 2000.0)])
def test_the_rope_is_the_smallest_whose_working_limit_carries_the_lowering(load, depth):
    d = bl.rope_diameter(load, depth, 7850.0)

    def limit(diameter):
        return bl.BREAKING_LOAD_PER_MM2 * (1000 * diameter) ** 2 / bl.SAFETY_FACTOR

    def needed(diameter):
        rope = (7850.0 - bl.WATER) * bl.GRAVITY * math.pi * diameter**2 / 4 * depth
        return 1.3 * (load + rope)

    assert limit(d) >= needed(d)
    assert d == 0.02 or limit(d - 0.001) < needed(d - 0.001)


def test_a_case_lands_and_holds_and_a_bad_case_is_a_row_not_a_raise():
    rng = np.random.default_rng(0)
    case = bl.lowering_case(rng, bl.LoweringRanges(depth=(200.0, 200.0), sea_share=1.0,
                                                   significant_height=(1.0, 1.0)))  # fmt: skip
    row = bl.run_case(case)
    assert row["success"] and row["hold_success"], row
    assert abs(row["landing_error"]) < 0.01 and row["ratio"] > 90.0
    # From the hover: optimised and closed-loop, each landed with every check passed.
    assert row["optimised"] and row["looped"], row
    assert abs(row["optimised_error"]) < 0.1 and abs(row["looped_error"]) < 0.1
    # DNV-RP-H103 on every landing run: the slack criterion held, a heave's amplification.
    for name in bl.LANDINGS:
        assert row[f"{name}_slack"] and row[f"{name}_static_share"] > 0.1, row
        assert 1.0 < row[f"{name}_amplification"] < 3.0, row
    bad = bl.run_case({**case, "lowering": {**case["lowering"], "land_time": 1.0}})
    assert not bad["success"] and "lowering.land_time" in bad["raised"]
    figures = bl.summary([row, bad])
    assert figures["landed"] == 1 and figures["raised"] == 1 and figures["cases"] == 2
    assert figures["optimised"] == 1 and figures["looped"] == 1
    assert figures["dnv_runs"] == 3 and figures["slack_failures"] == 0
    assert figures["amplification_max"] == max(row[f"{n}_amplification"] for n in bl.LANDINGS)
