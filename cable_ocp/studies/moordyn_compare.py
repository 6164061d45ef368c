"""MoorDyn as a peer code and a speed baseline (optional: ``python -m pip install -e ".[bench]"``).

The same cable and tow motion as a cable_ocp scene is written as a MoorDyn v2 input file: one line
of ``N`` segments whose top end is a coupled point moved along the scene's vessel motion and whose
bottom end is a free point. Both codes start from their own hanging static equilibrium (MoorDyn's
IC solve at the initial top position, :func:`cable_ocp.simulation.statics.equilibrium`) and the
free-end trajectories are compared on a common time grid.

A step counts as *stable* when its run stays finite and its end trajectory is within
:data:`STEP_TOLERANCE` of a run at a step :data:`REFINEMENT` times smaller: too large a step can
give a wrong answer without NaN (CONVENTIONS.md §9). The same rule picks MoorDyn's internal step and
cable_ocp's RK4 step, and the wall time per simulated second of the two is set side by side.

MoorDyn's drag (``Cd`` on the frontal area ``d l``, ``CdAx`` on the surface ``pi d l``) and added
mass (``Ca``, ``CaAx`` on the displaced volume) have the meaning of CONVENTIONS.md §4, so the
scene's coefficients are passed unchanged. The models differ otherwise: MoorDyn's line is extensible
(lumped masses joined by axial springs ``EA``), ours has rigid bonds, and its end is the tip
``A_0`` of a half-length element; the end difference measures all of that, nothing is tuned.
"""

from __future__ import annotations

import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import Scene, load_scene
from cable_ocp.simulation.integrate import stage_inputs, step_function
from cable_ocp.simulation.statics import equilibrium

INSTALL_HINT = 'python -m pip install -e ".[bench]"'
MOORDYN_STEPS = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4)  # s, internal steps tried, large first
CABLE_OCP_STEPS = (0.4, 0.2, 0.1, 0.05, 0.04, 0.02, 0.01, 0.005)  # s, RK4 steps, large first
# MoorDyn's default RK2 amplifies the undamped axial modes of this stiff line (its stability
# region leaves out the imaginary axis): over 30 s of the tow at N = 100 no step down to 1e-4 s came
# within STEP_TOLERANCE of a 4x smaller one, while RK4 (our scheme too) passes at 1e-3 s.
MOORDYN_SCHEME = "RK4"
REFINEMENT = 4  # a step is checked against a run at step / REFINEMENT
# 1 cm: a tenth of the paper's optimised clearance error (Omega_A = 0.076 m), so a step that passes
# changes no conclusion about the winch.
STEP_TOLERANCE = 0.01  # m
COUPLING_STEP = 0.05  # s, interval at which MoorDyn is given the top position and velocity
SAMPLE_STEP = 0.4  # s, grid on which both end trajectories are recorded and compared
# MoorDyn counts a segment that reaches z = 0 as partly out of the water, while the scene's cable is
# fully submerged; its frame is therefore shifted down by this much below the highest top position.
SURFACE_CLEARANCE = 1.0  # m


@dataclass(frozen=True)
class EndRun:
    """Free-end trajectory of one run, with the wall time of its time loop.

    Attributes
    ----------
    time : array (k,), s
        Sample times, ``0, SAMPLE_STEP, ..``.
    end : array (k, 3), m
        End position in the scene's frame; NaN from where a run failed.
    wall_time : float, s
        Of the time loop only (no set-up, no initial-condition solve).
    step : float, s
        Internal (MoorDyn) or RK4 (cable_ocp) step.
    """

    time: np.ndarray
    end: np.ndarray
    wall_time: float
    step: float

    @property
    def finite(self) -> bool:
        """Whether the whole trajectory is finite."""
        return bool(np.all(np.isfinite(self.end)))

    @property
    def ms_per_simulated_second(self) -> float:
        """Wall time per simulated second, ms/s."""
        return 1e3 * self.wall_time / float(self.time[-1])


@dataclass(frozen=True)
class ComparisonRow:
    """One row of the MoorDyn comparison.

    Attributes
    ----------
    elements : int
        ``N``: MoorDyn segments and cable_ocp's ``n``.
    moordyn_step : float, s
        MoorDyn's largest stable internal step (NaN if none of :data:`MOORDYN_STEPS` is).
    moordyn_ms : float, ms/s
        MoorDyn's wall time per simulated second at that step.
    cable_ocp_step : float, s
        cable_ocp's largest stable RK4 step (compiled).
    cable_ocp_ms : float, ms/s
        cable_ocp's wall time per simulated second at that step.
    ratio : float
        ``moordyn_ms / cable_ocp_ms``: how many times faster cable_ocp is.
    end_difference : float, m
        Largest distance between the two codes' free ends over the run.
    duration : float, s
        Simulated time.
    """

    elements: int
    moordyn_step: float
    moordyn_ms: float
    cable_ocp_step: float
    cable_ocp_ms: float
    ratio: float
    end_difference: float
    duration: float


def check_supported(scene: Scene) -> None:
    """Raise ValueError if the scene uses what the MoorDyn input cannot reproduce here.

    Supported: a submerged cable of circular section in still water, without torsion or bending
    damping (a MoorDyn line has neither), with no end force or payload.
    """
    cable, end = scene.cable, scene.end
    problems = []
    if not math.isclose(cable.cross_section_area, math.pi * cable.diameter**2 / 4):
        problems.append("cable.area must be pi d^2/4 (MoorDyn derives the area from d)")
    if scene.model.torsion or cable.bending_damping:
        problems.append("model.torsion must be false and cable.bending_damping 0")
    if not scene.environment.submerged:
        problems.append("environment.submerged must be true")
    if any(scene.environment.current) or scene.environment.current_profile:
        problems.append("environment.current must be zero (and no environment.current_profile)")
    if any(end.force) or any(end.force_amplitude) or end.payload is not None:
        problems.append("no end force or payload ([end] section)")
    if problems:
        raise ValueError(f"scene {scene.name!r} cannot be run in MoorDyn: " + "; ".join(problems))


def frame_shift(scene: Scene, duration: float) -> float:
    """Depth by which MoorDyn's frame is shifted down, m (top stays SURFACE_CLEARANCE under)."""
    top = Drive.from_scene(scene).top(np.arange(0.0, duration + COUPLING_STEP, COUPLING_STEP))[0]
    return max(0.0, float(top[2].max())) + SURFACE_CLEARANCE


def moordyn_input(
    scene: Scene,
    elements: int,
    internal_step: float,
    shift: float,
    time_scheme: str = MOORDYN_SCHEME,
    longest: float | None = None,
) -> str:
    """Text of a MoorDyn v2 input file for the scene's cable hanging from its initial top point.

    Parameters
    ----------
    scene : Scene
        The cable, environment, top point and seabed.
    elements : int
        Number of segments ``N``.
    internal_step : float, s
        MoorDyn's internal step ``dtM``.
    shift : float, m
        The frame is moved down by this depth (see :func:`frame_shift`).
    time_scheme : str
        MoorDyn's ``tScheme`` (MoorDyn's own default is RK2).
    longest : float, m, optional
        The longest the line becomes (a pay-out); the cable's length by default. The seabed is
        laid twice that below the frame's top.
    """
    cable, water, hydro = scene.cable, scene.environment, scene.hydrodynamics
    x, y, z = (float(c) for c in np.asarray(scene.top.start, dtype=float) - [0.0, 0.0, shift])
    drag_normal = hydro.drag_normal if hydro.drag else 0.0
    drag_axial = hydro.drag_axial if hydro.drag else 0.0
    added_normal = hydro.added_mass_normal if hydro.added_mass else 0.0
    added_axial = hydro.added_mass_axial if hydro.added_mass else 0.0
    bending = cable.bending_stiffness if scene.model.bending else 0.0
    axial = cable.youngs_modulus * cable.cross_section_area
    longest = cable.length if longest is None else longest
    depth = shift + 2 * longest  # the seabed stays a line's length below the lowest end
    return "\n".join(
        [
            "--------------------- MoorDyn Input File ------------------------------------",
            f"cable_ocp scene {scene.name}: N = {elements}, frame shifted down by {shift:g} m",
            "---------------------- LINE TYPES -------------------------------------------",
            "TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx",
            "(name) (m) (kg/m) (N) (N-s/-) (N-m^2) (-) (-) (-) (-)",
            f"cable {cable.diameter!r} {cable.mass_per_length!r} {axial!r} 0.0 {bending!r} "
            f"{drag_normal!r} {added_normal!r} {drag_axial!r} {added_axial!r}",
            "---------------------- POINTS -----------------------------------------------",
            "ID Attachment X Y Z Mass Volume CdA Ca",
            "(#) (word/ID) (m) (m) (m) (kg) (m^3) (m^2) (-)",
            f"1 Free {x!r} {y!r} {z - cable.length!r} 0 0 0 0",
            f"2 Coupled {x!r} {y!r} {z!r} 0 0 0 0",
            "---------------------- LINES ------------------------------------------------",
            "ID LineType AttachA AttachB UnstrLen NumSegs LineOutputs",
            "(#) (name) (ID) (ID) (m) (-) (-)",
            f"1 cable 1 2 {cable.length!r} {elements} -",
            "---------------------- OPTIONS ----------------------------------------------",
            "0 writeLog",
            "1 disableOutput",
            "1 disableOutTime",
            f"{internal_step!r} dtM",
            f"{time_scheme} tScheme",
            f"{water.gravity!r} g",
            f"{water.water_density!r} rho",
            f"{depth!r} WtrDpth",
            "------------------------- need this line ------------------------------------",
            "",
        ]
    )


@contextmanager
def _silenced_console() -> Iterator[None]:
    """Send what is written to file descriptors 1 and 2 to /dev/null.

    MoorDyn prints its set-up there, and a NaN report when a step is unstable; the caller sees
    the failure as NaN in the trajectory instead.
    """
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            os.dup2(null.fileno(), 2)
            yield
    finally:
        for descriptor, copy in zip((1, 2), saved, strict=True):
            os.dup2(copy, descriptor)
            os.close(copy)


def _sample_times(duration: float) -> np.ndarray:
    count = round(duration / SAMPLE_STEP)
    if count < 1 or abs(count * SAMPLE_STEP - duration) > 1e-9 * duration:
        raise ValueError(f"duration {duration} s must be a multiple of {SAMPLE_STEP} s")
    return np.arange(count + 1) * SAMPLE_STEP


def _moordyn_loop(moordyn, system, drive: Drive, times: np.ndarray, shift: float) -> np.ndarray:
    """Step MoorDyn through ``times``; free-end positions (len(times), 3), NaN after a failure."""
    per_sample = round(SAMPLE_STEP / COUPLING_STEP)
    coupling = np.arange((times.size - 1) * per_sample) * COUPLING_STEP
    position, velocity, _ = drive.top(coupling)
    position[2] -= shift
    end_point = moordyn.GetPoint(system, 1)
    end = np.full((times.size, 3), np.nan)
    end[0] = moordyn.GetPointPos(end_point)
    for k, t in enumerate(coupling):
        try:
            moordyn.Step(system, position[:, k].tolist(), velocity[:, k].tolist(), t, COUPLING_STEP)
        except RuntimeError:  # MoorDyn found NaN node positions
            break
        if (k + 1) % per_sample == 0:
            end[(k + 1) // per_sample] = moordyn.GetPointPos(end_point)
    end[:, 2] += shift
    return end


def run_moordyn(
    scene: Scene,
    elements: int,
    internal_step: float,
    duration: float | None = None,
    time_scheme: str = MOORDYN_SCHEME,
) -> EndRun:
    """Run the scene's tow in MoorDyn (winch locked) from MoorDyn's own static equilibrium.

    Parameters
    ----------
    scene : Scene
        The cable, its tow and the sea; its step is not used.
    elements : int
        Number of segments ``N``.
    internal_step : float, s
        MoorDyn's internal step ``dtM``; it must divide :data:`COUPLING_STEP`.
    duration : float, s, optional
        Simulated time, a multiple of :data:`SAMPLE_STEP`; the scene's by default.
    time_scheme : str
        MoorDyn's ``tScheme``.

    Returns
    -------
    EndRun
        The end in the scene's frame; NaN from where MoorDyn failed (its step is unstable).
    """
    import moordyn

    check_supported(scene)
    duration = scene.numerics.duration if duration is None else duration
    times = _sample_times(duration)
    drive = Drive.from_scene(scene)
    shift = frame_shift(scene, duration)
    text = moordyn_input(scene, elements, internal_step, shift, time_scheme)
    position, velocity, _ = drive.top(np.zeros(1))
    top, top_velocity = (position[:, 0] - [0.0, 0.0, shift]).tolist(), velocity[:, 0].tolist()
    wall_time = math.inf
    with tempfile.TemporaryDirectory() as folder, _silenced_console():
        path = Path(folder) / "cable.txt"
        path.write_text(text)
        system = moordyn.Create(str(path))
        try:
            moordyn.Init(system, top, top_velocity)
            started = time.perf_counter()
            end = _moordyn_loop(moordyn, system, drive, times, shift)
            wall_time = time.perf_counter() - started
        except RuntimeError:  # the initial-condition solve failed at this step
            end = np.full((times.size, 3), np.nan)
        finally:
            moordyn.Close(system)
    return EndRun(times, end, wall_time, internal_step)


def run_cable_ocp(
    model: CableModel, drive: Drive, x0: np.ndarray, step: float, duration: float
) -> EndRun:
    """Integrate the model by compiled RK4 and record the end ``A_0`` on the sample grid.

    Parameters
    ----------
    model : CableModel
        The project's model of the scene (n = the segments' number).
    drive : Drive
        The scene's top motion, winch (locked) and end force over time.
    x0 : array (state_size,)
        Initial state (the static equilibrium).
    step : float, s
        RK4 step; it must divide :data:`SAMPLE_STEP`.
    duration : float, s
        A multiple of :data:`SAMPLE_STEP`.

    Returns
    -------
    EndRun
    """
    times = _sample_times(duration)
    per_sample = round(SAMPLE_STEP / step)
    run = step_function(model, step, compiled=True).fold(per_sample).mapaccum(times.size - 1)
    inputs = stage_inputs(drive, np.arange((times.size - 1) * per_sample) * step, step)
    started = time.perf_counter()
    states = np.array(run(x0, inputs))
    wall_time = time.perf_counter() - started
    end = np.vstack([x0[:3], states[:3].T])  # A_0 = (x_0, y_0, z_0)
    return EndRun(times, end, wall_time, step)


def end_difference(a: EndRun, b: EndRun) -> float:
    """Largest distance between the ends of two runs on their common sample times, m."""
    if a.time.size != b.time.size:
        raise ValueError("the runs have different sample grids")
    return float(np.max(np.linalg.norm(a.end - b.end, axis=1)))


def largest_stable_step(
    run: Callable[[float], EndRun], steps: Sequence[float], tolerance: float = STEP_TOLERANCE
) -> EndRun | None:
    """Run at the largest of ``steps`` that is stable, or None.

    Parameters
    ----------
    run : callable
        ``step -> EndRun``.
    steps : sequence of float, s
        Tried from the first (largest) on.
    tolerance : float, m
        Largest end difference allowed against a run at ``step / REFINEMENT``.

    Returns
    -------
    EndRun or None
        The run at the stable step (finite, and within ``tolerance`` of the finer run).
    """
    runs: dict[float, EndRun] = {}

    def cached(step: float) -> EndRun:
        if step not in runs:
            runs[step] = run(step)
        return runs[step]

    for step in steps:
        coarse = cached(step)
        if not coarse.finite:
            continue
        fine = cached(step / REFINEMENT)
        if fine.finite and end_difference(coarse, fine) <= tolerance:
            return coarse
    return None


def _faster(first: EndRun, second: EndRun) -> EndRun:
    """The run with the smaller wall time (both runs are the same computation)."""
    return first if first.wall_time <= second.wall_time else second


def compare(scene: Scene, elements: int, duration: float | None = None) -> ComparisonRow:
    """Both codes at their largest stable steps on the scene's tow; timings best of 3.

    The timing runs of the two codes alternate, so that a busy moment of a shared machine does
    not fall on one code only.

    Parameters
    ----------
    scene : Scene
        The tow compared, its winch locked.
    elements : int
        ``N`` for both codes.
    duration : float, s, optional
        The scene's by default.

    Returns
    -------
    ComparisonRow
        NaN in MoorDyn's columns if none of :data:`MOORDYN_STEPS` is stable.
    """
    duration = scene.numerics.duration if duration is None else duration
    model = CableModel.from_scene(scene, elements=elements)
    drive = Drive.from_scene(scene, elements=elements)
    x0 = equilibrium(model, drive).state

    def ours_at(step: float) -> EndRun:
        return run_cable_ocp(model, drive, x0, step, duration)

    def theirs_at(step: float) -> EndRun:
        return run_moordyn(scene, elements, step, duration)

    ours = largest_stable_step(ours_at, CABLE_OCP_STEPS)
    if ours is None:
        raise RuntimeError(f"no stable cable_ocp step among {CABLE_OCP_STEPS} s at n = {elements}")
    theirs = largest_stable_step(theirs_at, MOORDYN_STEPS)
    for _ in range(2):
        ours = _faster(ours, ours_at(ours.step))
        if theirs is not None:
            theirs = _faster(theirs, theirs_at(theirs.step))
    ms = ours.ms_per_simulated_second
    if theirs is None:
        moordyn_step = moordyn_ms = difference = float("nan")
    else:
        moordyn_step, moordyn_ms = theirs.step, theirs.ms_per_simulated_second
        difference = end_difference(theirs, ours)
    return ComparisonRow(
        elements, moordyn_step, moordyn_ms, ours.step, ms, moordyn_ms / ms, difference, duration
    )


def moordyn_available() -> bool:
    """Whether the optional ``moordyn`` package can be imported."""
    try:
        import moordyn  # noqa: F401
    except ImportError:
        return False
    return True


def moordyn_report(models_dir: Path, quick: bool = False) -> list[ComparisonRow]:
    """Print MoorDyn against cable_ocp on ``paper_flat`` (locked winch) and return the rows.

    Parameters
    ----------
    models_dir : Path
        Folder with ``paper_flat.toml``.
    quick : bool
        Simulate 30 s instead of the scene's 210 s.

    Returns
    -------
    list of ComparisonRow
        One per ``N`` in (15, 100); empty (after one line saying how to install it) when
        ``moordyn`` is not installed.
    """
    if not moordyn_available():
        print(f"MoorDyn comparison skipped: moordyn is not installed ({INSTALL_HINT})")
        return []
    scene = load_scene(Path(models_dir) / "paper_flat.toml")
    duration = 30.0 if quick else scene.numerics.duration
    rows = [compare(scene, n, duration) for n in (15, 100)]
    print(
        f"MoorDyn (lumped mass, {MOORDYN_SCHEME}) vs cable_ocp (rfe, compiled RK4): {scene.name}, "
        f"tow with the winch locked, {duration:g} s; each at its largest step within "
        f"{STEP_TOLERANCE:g} m of a run at a {REFINEMENT}x smaller step; wall time best of 3, "
        "time loop only"
    )
    print(f"{'N':>5}{'MoorDyn dt [s]':>16}{'MoorDyn ms/sim s':>18}{'cable_ocp h [s]':>17}"
          f"{'cable_ocp ms/sim s':>20}{'ratio':>8}{'end diff. [m]':>15}")  # fmt: skip
    for r in rows:
        print(
            f"{r.elements:>5}{r.moordyn_step:>16.3g}{r.moordyn_ms:>18.2f}{r.cable_ocp_step:>17.3g}"
            f"{r.cable_ocp_ms:>20.3f}{r.ratio:>7.1f}x{r.end_difference:>15.3f}"
        )
    return rows
