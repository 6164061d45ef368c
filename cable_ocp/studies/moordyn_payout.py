"""MoorDyn against the line on the drum: the same rope paid out by the same drum (issue 26).

MoorDyn keeps its ``N`` segments and rescales them to ``L(t) / N`` as the line's unstretched
length changes (``SetLineUnstretchedLength`` and its rate ``SetLineUnstretchedLengthVel``, set at
every coupling step); cable_ocp splits elements off at the drum
(:mod:`cable_ocp.model.line_models`). Same rope, same tow, same pay-out, both from their own
hanging equilibrium; the free ends are compared on whole seconds. The input file and the
console handling are those of :mod:`cable_ocp.studies.moordyn_compare` (its differences hold
here too: MoorDyn's line is extensible, lumped masses at nodes, its end a node where ours is the
tip of a half element).
"""

from __future__ import annotations

import ctypes
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import Scene, load_scene
from cable_ocp.simulation.line_run import pay_out_drive
from cable_ocp.simulation.run import simulate
from cable_ocp.studies import moordyn_compare as mc
from cable_ocp.studies.payout_validation import RAMP, output_every, ramped_pay_out, step_for

INTERNAL_STEP = (
    2e-4  # s, MoorDyn's dtM at N = 100 (within 1 cm of 1e-4 s on the tow, moordyn_compare)
)
COUPLING_STEP = 1e-3  # s: the unstretched length moves by speed * this per call (1 mm at 1 m/s)


@dataclass(frozen=True)
class PayOutComparison:
    """The two codes' ends over one pay-out.

    Attributes
    ----------
    time : array (k,), s
        The whole seconds of the run, where both ends are compared.
    moordyn, cable_ocp : array (k, 3), m
        The free end of each.
    paid_out : float, m
        Line paid out over the run.
    difference : float, m
        Largest end distance over the run.
    moordyn_wall, cable_ocp_wall : float, s
        Wall time of each run (cable_ocp: ``simulate`` with its statics; MoorDyn: its loop).
    elements : (int, int)
        cable_ocp's ``n`` at the start and at the end.
    """

    time: np.ndarray
    moordyn: np.ndarray
    cable_ocp: np.ndarray
    paid_out: float
    difference: float
    moordyn_wall: float
    cable_ocp_wall: float
    elements: tuple[int, int]

    @property
    def share(self) -> float:
        """:attr:`difference` over the line paid out."""
        return self.difference / self.paid_out


def pay_out_scene(start: float, pay_out: float, elements: int, speed: float) -> Scene:
    """``paper_flat``'s rope and tow, ``start`` m out, ``pay_out`` m paid out at ``speed`` m/s.

    ``winch.line.element_length`` makes ``elements`` elements of the final line, MoorDyn's ``N``.
    """
    duration = pay_out / speed + RAMP / 2
    length = (start + pay_out) / elements
    return load_scene(
        scene_path("paper_flat"),
        {
            "cable.length": start,
            "top.tow.sway_period": duration,
            "numerics.duration": duration,
            "numerics.step": step_for(length),
            "numerics.output_every": output_every(length, None, speed),
            "winch.line": {"pay_out_max": pay_out + 1.0, "element_length": length},
        },
    )


def run_moordyn(scene: Scene, angle, elements: int, times: np.ndarray) -> tuple[np.ndarray, float]:
    """MoorDyn's free end (len(times), 3), m, and its loop's wall time (s), paying out by ``angle``.

    The unstretched length and its rate are set at the middle of every coupling step.
    """
    import moordyn

    mc.check_supported(scene)
    drive = Drive.from_scene(scene)
    drum = pay_out_drive(scene, angle)
    shift = mc.frame_shift(scene, float(times[-1]))
    longest = scene.cable.length + scene.winch.line.pay_out_max
    text = mc.moordyn_input(scene, elements, INTERNAL_STEP, shift, longest=longest)
    per_sample = round((times[1] - times[0]) / COUPLING_STEP)
    coupling = np.arange((times.size - 1) * per_sample) * COUPLING_STEP
    position, velocity, _ = drive.top(coupling)
    position[2] -= shift
    winch = drum.inputs(coupling + COUPLING_STEP / 2)
    length = scene.cable.length + winch[INPUTS.top_length]
    rate = winch[INPUTS.top_length_rate]
    end = np.full((times.size, 3), np.nan)
    with tempfile.TemporaryDirectory() as folder, mc._silenced_console():
        path = Path(folder) / "cable.txt"
        path.write_text(text)
        system = moordyn.Create(str(path))
        try:
            moordyn.Init(system, position[:, 0].tolist(), velocity[:, 0].tolist())
            line, point = moordyn.GetLine(system, 1), moordyn.GetPoint(system, 1)
            end[0] = moordyn.GetPointPos(point)
            started = time.perf_counter()
            set_length = _keeping_none(moordyn.SetLineUnstretchedLength, line, length[0])
            set_rate = _keeping_none(moordyn.SetLineUnstretchedLengthVel, line, rate[0])
            for k, t in enumerate(coupling):
                set_length(line, float(length[k]))
                set_rate(line, float(rate[k]))
                moordyn.Step(
                    system, position[:, k].tolist(), velocity[:, k].tolist(), t, COUPLING_STEP
                )
                if (k + 1) % per_sample == 0:
                    end[(k + 1) // per_sample] = moordyn.GetPointPos(point)
            wall = time.perf_counter() - started
        finally:
            moordyn.Close(system)
    end[:, 2] += shift
    return end, wall


def _keeping_none(setter, line, value: float):
    """``setter`` made safe from a reference it steals from ``None``.

    The moordyn binding's ``SetLineUnstretchedLength`` and ``SetLineUnstretchedLengthVel``
    return ``None`` without a new reference (moordyn 2.x: ``None``'s count fell by 100 in 100
    calls), so that a long run frees ``None`` and the interpreter aborts ("deallocating None").
    One trial call measures what a call steals, and each call gives that back.
    """
    before = sys.getrefcount(None)
    setter(line, float(value))
    stolen = before - sys.getrefcount(None)
    for _ in range(stolen):
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(None))

    def call(*args):
        setter(*args)
        for _ in range(stolen):
            ctypes.pythonapi.Py_IncRef(ctypes.py_object(None))

    return call


def compare(start: float = 100.0, pay_out: float = 200.0, elements: int = 100,
            speed: float = 1.0) -> PayOutComparison:  # fmt: skip
    """The pay-out of :func:`pay_out_scene` in both codes, ends on whole seconds."""
    scene = pay_out_scene(start, pay_out, elements, speed)
    angle = ramped_pay_out(speed, RAMP, scene.winch.drum_radius)
    started = time.perf_counter()
    ours = simulate(scene, winch=angle, compiled=True)
    ours_wall = time.perf_counter() - started
    whole = np.isclose(ours.time, np.round(ours.time), rtol=0.0, atol=1e-9)
    times, ours_end = ours.time[whole], ours.end[whole]
    theirs, theirs_wall = run_moordyn(scene, angle, elements, times)
    difference = float(np.linalg.norm(theirs - ours_end, axis=1).max())
    counts = (int(ours.element_count[0]), int(ours.element_count[-1]))
    return PayOutComparison(
        times, theirs, ours_end, pay_out, difference, theirs_wall, ours_wall, counts
    )
