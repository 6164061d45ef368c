"""Validation of a line paid out and hauled in by elements (issue 26; tests/test_payout.py).

The cases of the issue's acceptance on ``paper_flat``'s rope: a pay-out under the tow and a
sheared current at several element lengths (its convergence, and the reverse haul-in), and the
top tension's jump where an element is split off or merged back. Each function returns its
figures; the slow tests assert them and write the validation rows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import Scene, load_scene
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.run import simulate
from cable_ocp.studies.figures import CHART_DPI

RAMP = 10.0  # s, the drum's quintic start (and turn)
PAYLOAD = {"mass": 2000.0, "volume": 0.256, "drag_area": 1.0}  # 2 t of steel
# A current against the tow, sheared over the water column (m, m/s).
SHEARED_CURRENT = [
    {"z": 0.0, "u": -0.4, "v": 0.1},
    {"z": -200.0, "u": -0.2, "v": 0.0},
    {"z": -800.0, "u": 0.0, "v": 0.0},
]
SAMPLE = 1.0  # s, the grid on which end trajectories are compared
# Acceptance 4: element lengths (m) of the insertion runs, and of the finest, their reference.
TRANSIENT_LENGTHS = (10.0, 5.0, 2.5)
FINEST_TRANSIENT = 1.25
STEP_PER_LENGTH = 0.004  # s/m: the RK4 step scales with the element length (its wave crossing)
LARGEST_STEP = 0.05  # s


def ramped_pay_out(speed: float, ramp: float, radius: float, turn_at: float | None = None):
    """Drum angle ``t -> (phi, phi', phi'')`` paying out at ``speed`` (m/s, < 0 hauls in).

    A quintic ramp of ``ramp`` s starts it; with ``turn_at`` (s) the drum reverses to the same
    speed the other way, by a C2 turn of ``2 ramp`` s.
    """

    def shape(t):
        tau = np.clip(t / ramp, 0.0, 1.0)
        line = ramp * (2.5 * tau**4 - 3 * tau**5 + tau**6) + np.maximum(t - ramp, 0.0)
        rate = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
        acc = (30 * tau**2 - 60 * tau**3 + 30 * tau**4) / ramp
        return np.array([line, rate, acc])

    def angle(t, left=None):
        t = np.asarray(t, dtype=float)
        values = shape(t)
        if turn_at is not None:
            values = values - 2 * np.where(t > turn_at, shape(t - turn_at), 0.0)
        return tuple(speed / radius * values)

    return angle


def step_for(element_length: float) -> float:
    """The RK4 step (s) of a line of ``element_length`` (m) elements, a divisor of 1 s."""
    step = min(LARGEST_STEP, STEP_PER_LENGTH * element_length)
    return 1.0 / np.ceil(1.0 / step)


def output_every(element_length: float, top_length_min: float | None, speed: float) -> int:
    """Steps per output, the most that keep the line's rule between outputs.

    Outputs fall on every whole second, and between two the line moves at most half the
    shorter of ``Delta`` and ``l_min`` (:func:`cable_ocp.simulation.line_run.check_line`).
    """
    per_second = round(1.0 / step_for(element_length))
    shortest = element_length / 2 if top_length_min is None else top_length_min
    allowed = min(element_length, shortest) / 2
    return max(
        k for k in range(1, per_second + 1)
        if per_second % k == 0 and k * speed / per_second <= allowed
    )  # fmt: skip


def on_whole_seconds(run: LineTrajectory) -> np.ndarray:
    """The end's positions (k, 3), m, at the run's whole seconds."""
    whole = np.isclose(run.time, np.round(run.time), rtol=0.0, atol=1e-9)
    return run.end[whole]


def tow_scene(start: float, change: float, element_length: float, speed: float,
              top_length_min: float | None = None) -> Scene:  # fmt: skip
    """``paper_flat``'s tow over a sheared current, ``start`` m of line out, payload at the end.

    The drum pays out ``change`` m (< 0: hauls in) at ``speed`` m/s after a ramp.
    """
    duration = abs(change) / speed + RAMP / 2
    line = {"element_length": element_length, "top_length_min": top_length_min}
    line.update({"pay_out_max": max(change, 0.0) + 1.0, "haul_in_max": max(-change, 0.0) + 1.0})
    return load_scene(
        scene_path("paper_flat"),
        {
            "cable.length": start,
            "end.payload": PAYLOAD,
            "environment.current_profile": SHEARED_CURRENT,
            "top.tow.sway_period": duration,
            "numerics.duration": duration,
            "numerics.step": step_for(element_length),
            "numerics.output_every": output_every(element_length, top_length_min, speed),
            "winch.line": {k: v for k, v in line.items() if v is not None},
        },
    )


def tow_run(start: float, change: float, element_length: float, speed: float,
            top_length_min: float | None = None) -> LineTrajectory:  # fmt: skip
    """Simulate :func:`tow_scene` (compiled) with its drum."""
    scene = tow_scene(start, change, element_length, speed, top_length_min)
    angle = ramped_pay_out(np.sign(change) * speed, RAMP, scene.winch.drum_radius)
    return simulate(scene, winch=angle, compiled=True)


@dataclass(frozen=True)
class Convergence:
    """End trajectories at several element lengths against the finest.

    Attributes
    ----------
    element_lengths : tuple of float, m
        Coarse to fine; the last is the reference.
    differences : tuple of float, m
        Largest distance of each coarser run's end from the finest's over the run.
    order : float
        Observed order ``log2(d(2 Delta) / d(Delta))`` of the two finest differences that are
        halvings apart (against the reference).
    finest_two : float, m
        The difference between the two finest runs.
    changes : int
        Splits and merges of the finest run.
    """

    element_lengths: tuple[float, ...]
    differences: tuple[float, ...]
    order: float
    finest_two: float
    changes: int


def convergence(
    start: float, change: float, element_lengths: tuple[float, ...], speed: float
) -> Convergence:
    """The end's trajectory of :func:`tow_run` at each element length, against the finest."""
    runs = [tow_run(start, change, length, speed) for length in element_lengths]
    ends = [on_whole_seconds(run) for run in runs]
    reference = ends[-1]
    differences = tuple(float(np.linalg.norm(e - reference, axis=1).max()) for e in ends[:-1])
    order = float(np.log2(differences[-2] / differences[-1]))
    return Convergence(
        element_lengths=tuple(element_lengths),
        differences=differences,
        order=order,
        finest_two=differences[-1],
        changes=int(np.abs(np.diff(runs[-1].element_count)).sum()),
    )


def tension_jumps(run: LineTrajectory) -> np.ndarray:
    """The top tension's jump at each change of ``n`` (N): after less before, same instant."""
    return np.array(
        [
            after.top_tension[0] - before.top_tension[-1]
            for before, after in zip(run.segments[:-1], run.segments[1:], strict=True)
        ]
    )


def static_top_tension(scene: Scene, line_out: np.ndarray) -> np.ndarray:
    """Submerged weight (N) of the payload and of ``line_out`` (m) of the scene's rope."""
    cable, water = scene.cable, scene.environment
    area = cable.cross_section_area
    rope = (cable.density - water.water_density) * area * water.gravity * line_out
    return scene.end.payload.weight_in(water) + rope


@dataclass(frozen=True)
class Transient:
    """The top tension across the changes of ``n`` of one run.

    Attributes
    ----------
    new_top_length : float, m
        The top element just after a split (``l_min + Delta / 2``), or just after a merge.
    jump : float
        Largest ``|T_after - T_before|`` at a change, over the static top tension there.
    against_finest : float
        Largest change, across a change of ``n``, of the run's top tension less the finest
        run's (interpolated to the same times), over the static top tension; from the last
        output before to the first after.
    changes : int
        How many times the run changed its number of elements.
    """

    new_top_length: float
    jump: float
    against_finest: float
    changes: int


def transient(run: LineTrajectory, finest: LineTrajectory) -> Transient:
    """The top tension's jumps at the changes of ``run``, raw and against ``finest``."""
    scene = run.scene
    starts = np.array([s.time[0] for s in run.segments[1:]])
    static = static_top_tension(scene, np.array([s.line_out[0] for s in _views(run)[1:]]))
    jumps = np.abs(tension_jumps(run)) / static
    difference = [
        (after.top_tension[1] - np.interp(after.time[1], finest.time, finest.top_tension))
        - (before.top_tension[-2] - np.interp(before.time[-2], finest.time, finest.top_tension))
        for before, after in zip(run.segments[:-1], run.segments[1:], strict=True)
    ]
    return Transient(
        new_top_length=float(run.segments[1].top_length[0]),
        jump=float(jumps.max()),
        against_finest=float(np.max(np.abs(difference) / static)),
        changes=int(starts.size),
    )


def _views(run: LineTrajectory) -> list[LineTrajectory]:
    """Each segment of ``run`` as a one-segment run (its line out and top tension)."""
    return [LineTrajectory([s], run.element_length) for s in run.segments]


def insertion_runs(
    lengths: tuple[float, ...] = TRANSIENT_LENGTHS,
) -> tuple[dict[float, LineTrajectory], LineTrajectory]:
    """Acceptance 4's runs: 0.5 m/s from 100 m to 200 m under the tow, the shortest top 5 cm.

    Returns the runs by element length (m) and the finest (:data:`FINEST_TRANSIENT`).
    """
    finest = tow_run(100.0, 100.0, FINEST_TRANSIENT, 0.5, top_length_min=0.05)
    return {d: tow_run(100.0, 100.0, d, 0.5, top_length_min=0.05) for d in lengths}, finest


def transient_chart(runs: dict[float, LineTrajectory], finest: LineTrajectory, path=None):
    """The top tension's departure from the static one (% of it) against time, per run.

    One line per element length (its new top element's length after a split in the legend),
    the finest run's dashed, the splits of each run marked; saved to ``path`` when given.
    """
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 4.5))
    for delta, run in [*runs.items(), (FINEST_TRANSIENT, finest)]:
        static = static_top_tension(run.scene, run.line_out)
        share = 100 * (run.top_tension - static) / static
        style = "--" if run is finest else "-"
        label = f"Delta = {delta:g} m (new top {run.segments[-1].top_length[0]:.2g} m)"
        (line,) = ax.plot(run.time, share, style, lw=1, label=label)
        for segment in run.segments[1:]:
            ax.axvline(segment.time[0], color=line.get_color(), lw=0.3, alpha=0.4)
    ax.axhline(1.0, color="k", lw=0.8, ls=":", label="1 % of the static tension")
    ax.axhline(-1.0, color="k", lw=0.8, ls=":")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("top tension - static [% of static]")
    ax.set_title("pay-out 100 -> 200 m at 0.5 m/s under the tow: top tension at the splits")
    ax.legend(fontsize=8)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=CHART_DPI)
    return fig
