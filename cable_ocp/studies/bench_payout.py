"""Speed of a line paid out by elements (issue 26), beside the fixed-n model of its longest line.

A 1000 m pay-out at 10 m elements (``n`` from 5 to 105: a model per ``n``, all on one compiled
library of element kernels, :mod:`cable_ocp.model.line_models`), compiled, against the
fixed-length model of the same (largest) ``n`` compiled as the structure's own library, in the
same run. ``--quick``: 200 m. Printed by ``cable-ocp bench --only payout``.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate

SPEED = 1.0  # m/s of pay-out
STEP = 0.05  # s, RK4 step (at 0.1 s the bonds of the longest lines drifted off: unstable)
START = 50.0  # m of line out at the start
ELEMENT = 10.0  # m
RAMP = 10.0  # s, the drum's quintic start
REAL_TIME_GOAL = 50.0


def ramp_angle(speed: float, ramp: float, radius: float):
    """Drum angle paying out at ``speed`` (m/s) after a quintic ramp of ``ramp`` (s)."""

    def angle(t, left=None):
        tau = np.clip(np.asarray(t, dtype=float) / ramp, 0.0, 1.0)
        line = ramp * (2.5 * tau**4 - 3 * tau**5 + tau**6) + np.maximum(t - ramp, 0.0)
        rate = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        acc = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / ramp
        return speed * line / radius, speed * rate / radius, speed * acc / radius

    return angle


def _scenes(models_dir: Path, pay_out: float):
    duration = pay_out / SPEED + RAMP / 2
    common = {
        "top.motion": "fixed",
        "end.payload": {"mass": 2000.0, "volume": 0.256, "drag_area": 1.0},
        "numerics.duration": duration,
        "numerics.step": STEP,
        "numerics.output_every": 5,
        "numerics.constraint_tolerance": 1e-4,
    }
    line = load_scene(
        models_dir / "paper_flat.toml",
        {**common, "cable.length": START,
         "winch.line": {"pay_out_max": pay_out, "element_length": ELEMENT}},
    )  # fmt: skip
    longest = START + pay_out
    elements = int(round((longest - ELEMENT / 2) / ELEMENT))
    fixed = load_scene(
        models_dir / "paper_flat.toml",
        {**common, "cable.length": longest, "model.elements": elements, "winch.top_length_min": 1.0,
         "winch.angle_min": 0.0, "winch.angle_max": 1.0},
    )  # fmt: skip
    return line, fixed, elements


def report(models_dir: Path, quick: bool = False) -> dict[str, float]:
    """Print the pay-out's wall time and real-time factor beside the fixed-n model's."""
    pay_out = 200.0 if quick else 1000.0
    line, fixed, elements = _scenes(models_dir, pay_out)
    angle = ramp_angle(SPEED, RAMP, line.winch.drum_radius)
    simulate(line, winch=angle, compiled=True)  # the kernels compiled or loaded, models built
    started = time.perf_counter()
    run = simulate(line, winch=angle, compiled=True)
    line_wall = time.perf_counter() - started
    simulate(fixed, compiled=True)  # its library compiled or loaded
    started = time.perf_counter()
    simulate(fixed, compiled=True)
    fixed_wall = time.perf_counter() - started
    duration = line.numerics.duration
    counts = run.element_count
    rows = {
        "line_wall": line_wall,
        "line_real_time": duration / line_wall,
        "fixed_wall": fixed_wall,
        "fixed_real_time": duration / fixed_wall,
    }
    print(
        f"pay-out of {pay_out:g} m at {SPEED:g} m/s from {START:g} m, {ELEMENT:g} m elements "
        f"(n = {counts.min()}..{counts.max()}, {len(run.segments)} segments), h = {STEP:g} s, "
        f"{duration:g} s simulated, compiled; same run"
    )
    print(f"{'case':<44}{'wall [s]':>10}{'x real time':>13}")
    print(f"{'variable n (split/merge, shared kernels)':<44}{line_wall:>10.2f}"
          f"{rows['line_real_time']:>13.0f}")  # fmt: skip
    print(f"{f'fixed n = {elements} (its own library)':<44}{fixed_wall:>10.2f}"
          f"{rows['fixed_real_time']:>13.0f}")  # fmt: skip
    goal = "met" if rows["line_real_time"] >= REAL_TIME_GOAL else "NOT met"
    print(f"goal: variable n >= {REAL_TIME_GOAL:g}x real time: {goal}")
    return rows
