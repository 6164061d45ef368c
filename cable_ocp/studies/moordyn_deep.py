"""MoorDyn's reference for deep lowering: a payload on an elastic line under a heaving vessel.

Issue 44, acceptance 1. A vertical line hangs a payload from the winch, which is locked and heaves
with the vessel in a JONSWAP sea (the project's own generator, :mod:`cable_ocp.drive.sea_state`,
through :meth:`DeepCase.scene` and :class:`~cable_ocp.drive.drive.Drive`). Line and payload form a
spring-mass system whose first axial period is (the Rayleigh estimate of the issue)

    T0 = 2 pi sqrt((M + A33 + m L / 3) / (EA / L)),

M the payload's mass, A33 = C_a rho_w V its added mass, m the line's mass per metre in air.

MoorDyn runs the same line (the input file of :mod:`cable_ocp.studies.moordyn_compare` with the
payload on the free point and the axial damping set) from its own static equilibrium;
statistics are taken after :data:`SETTLE`, once the start's transient (the sea-state heave starts
at rest but not with zero velocity) has died out.

Axial damping: MoorDyn's ``BA`` multiplies the strain rate (a Kelvin-Voigt line, tension
``EA e + BA de/dt``). That damping is proportional to the stiffness, so each axial mode of
angular frequency ``w`` has the ratio ``BA w / (2 EA)`` (on the uniform-strain mode: a spring
``EA / L`` beside a dashpot ``BA / L``). A ratio ``zeta`` of the first mode is therefore

    BA = 2 zeta EA / w0 = zeta EA T0 / pi   (N s),

with T0 the Rayleigh period above (the exact first mode, :func:`axial_period_exact`, is up to
1.5 % slower in these cases, so its ratio is that much below ``zeta``). Higher modes get
``zeta w / w0``: overdamped, which also sets MoorDyn's stable step (:func:`internal_step`).
"""

from __future__ import annotations

import math
import tempfile
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

from cable_ocp.drive.drive import Drive
from cable_ocp.drive.vessel import TopMotionFunction, smoothstep, smoothstep_curvature
from cable_ocp.model.cable import spec_from_scene
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import Scene, load_scene
from cable_ocp.studies import moordyn_compare as mc

DAMPING_RATIO = 0.02  # of the first axial mode (issue 44)
SEA_STATE = {"significant_height": 2.0, "peak_period": 9.0, "seed": 27}  # deploy's sea, m, s
# s, discarded: the start's transient decays as e^-(zeta w0 t), to 2 % by then at T0 = 6.3 s
# with BA alone (the drag, 0.8 % more damping in the free decays, takes it further).
SETTLE = 200.0
RECORD = 600.0  # s, over which the statistics are taken
COUPLING_STEP = mc.COUPLING_STEP  # s, MoorDyn is given the top position and velocity this often
# RK4 is stable to |h lambda| of about 2.8 on the real and imaginary axes; half of it is kept.
STABLE_STEP_FRACTION = 0.5
# MoorDyn's static solve until the nodes' accelerations are below 1e-6 m/s^2 (its default 1e-3
# left the payload 1 cm, 0.15 %, short of the stretch), for up to 300 s of pseudo-time.
STATIC_SOLVE = ["1e-6 threshIC", "300 TmaxIC"]
DECAY_LIFT = 0.2  # m, the free decay's top lift: small for a linear response, far from slack
DECAY_PERIODS = 12  # periods of free decay recorded; the first is left out (higher modes)


@dataclass(frozen=True)
class DeepCase:
    """A payload hanging on a vertical line from a heaving vessel, the winch locked.

    Attributes
    ----------
    name : str
        Key of the case in :data:`CASES`, as tables and tests name it.
    length : float, m
        Unstretched line length L.
    diameter : float, m
        Of the line, d.
    density : float, kg/m^3
        Of the line; its mass per metre is ``density pi d^2 / 4``.
    axial_stiffness : float, N
        ``EA``.
    payload_mass : float, kg
        Of the payload in air.
    payload_volume : float, m^3
        Displaced by the payload (its buoyancy).
    payload_drag_area : float, m^2
        The payload's area across the flow.
    payload_drag : float
        Drag coefficient on ``payload_drag_area``.
    segments : int
        MoorDyn's ``N``: doubling it changes the heave figures by less than 1 % (:func:`case_row`).
    """

    name: str
    length: float
    diameter: float
    density: float
    axial_stiffness: float
    payload_mass: float
    payload_volume: float
    payload_drag_area: float
    payload_drag: float
    segments: int

    def scene(self, heave: bool = True, elements: int = 10) -> Scene:
        """The case as a project scene: ``hanging`` with this line, payload and sea.

        Drive the project's model with it (``co.simulate(case.scene())``) to get the same vessel
        motion; ``Drive.from_scene(case.scene()).top(t)`` is that motion. The line is water at
        1025 kg/m^3 with C_dn 1.0, C_dt 0.1, C_an 1.0, C_at 0 (the scene defaults).

        Parameters
        ----------
        heave : bool
            The vessel heaves in :data:`SEA_STATE` (else the top is fixed).
        elements : int
            The project model's ``n``.
        """
        area = math.pi * self.diameter**2 / 4
        overrides = {
            "name": self.name,
            "cable.length": self.length,
            "cable.diameter": self.diameter,
            "cable.density": self.density,
            "cable.youngs_modulus": self.axial_stiffness / area,
            "end.payload": {
                "mass": self.payload_mass,
                "volume": self.payload_volume,
                "drag_area": self.payload_drag_area,
                "drag": self.payload_drag,
                "added_mass": 1.0,
            },
            "model.elements": elements,
            "winch.top_length_max": self.length,  # hanging's 30 m is for its 300 m line
            "numerics.duration": SETTLE + RECORD,
        }
        if heave:
            overrides["top.heave"] = {"sea_state": dict(SEA_STATE)}
        return load_scene(scene_path("hanging"), overrides)


CASES = (
    DeepCase("steel_500m_5t", 500.0, 0.04, 7850.0, 1e11 * math.pi * 0.04**2 / 4,
             5000.0, 0.64, 6.25, 1.2, 20),
    DeepCase("steel_1000m_5t", 1000.0, 0.04, 7850.0, 1e11 * math.pi * 0.04**2 / 4,
             5000.0, 0.64, 6.25, 1.2, 20),
    DeepCase("steel_2000m_40t", 2000.0, 0.04, 7850.0, 1e11 * math.pi * 0.04**2 / 4,
             40000.0, 5.0, 25.0, 1.2, 20),
    DeepCase("hmpe_3000m_70t", 3000.0, 0.08, 975.0, 2.5e8,
             70000.0, 9.0, 36.0, 1.2, 20),
)  # fmt: skip
"""The deep cases (T0 1.1 to 6.3 s): deploy's 5 t frame on 40 mm steel wire (E = 1e11 Pa) at
500 m and 1000 m, a 40 t structure on it at 2000 m, 70 t on an 80 mm HMPE-like rope at 3000 m."""


def axial_period(scene: Scene) -> float:
    """First axial period ``T0 = 2 pi sqrt((M + A33 + m L / 3) / (EA / L))`` of a scene, s.

    ``EA = E A`` (``cable.youngs_modulus`` times the section), ``A33 = C_a rho_w V``.
    """
    spec, length = spec_from_scene(scene), scene.cable.length
    mass = spec.payload_inertia + spec.element.mass_per_length * length / 3
    return 2 * math.pi * math.sqrt(mass * length / _axial_stiffness(scene))


def axial_period_exact(scene: Scene) -> float:
    """First axial period of the uniform line with the payload at its end (a continuum), s.

    The first root ``x`` of ``x tan x = m L / (M + A33)`` gives ``T = 2 pi L / (x c)``, ``c``
    the axial wave speed ``sqrt(EA / m)``; :func:`axial_period` is its Rayleigh estimate.
    """
    spec = spec_from_scene(scene)
    length, mass = scene.cable.length, spec.element.mass_per_length
    ratio = mass * length / spec.payload_inertia
    root = brentq(lambda x: x * math.tan(x) - ratio, 0.0, math.pi / 2 - 1e-12)
    return 2 * math.pi * length / (root * math.sqrt(_axial_stiffness(scene) / mass))


def static_top_tension(scene: Scene) -> float:
    """Top tension of the line hanging at rest, ``W_p + w' L`` (submerged weights), N."""
    payload_weight, line_weight = _submerged_weights(scene)
    return payload_weight + line_weight * scene.cable.length


def static_stretch(scene: Scene) -> float:
    """Stretch of the vertical line hanging at rest, ``(W_p L + w' L^2 / 2) / EA``, m."""
    payload_weight, line_weight = _submerged_weights(scene)
    length = scene.cable.length
    return (payload_weight * length + line_weight * length**2 / 2) / _axial_stiffness(scene)


def axial_damping(scene: Scene, ratio: float = DAMPING_RATIO) -> float:
    """MoorDyn's ``BA`` for a damping ratio of the first axial mode, ``ratio EA T0 / pi``, N s."""
    if not 0.0 <= ratio < 1.0:
        raise ValueError(f"ratio = {ratio!r} is out of range: must be in [0, 1)")
    return ratio * _axial_stiffness(scene) * axial_period(scene) / math.pi


def _axial_stiffness(scene: Scene) -> float:
    """``EA`` as MoorDyn's input file has it (:func:`moordyn_compare.moordyn_input`), N."""
    return scene.cable.youngs_modulus * scene.cable.cross_section_area


def _submerged_weights(scene: Scene) -> tuple[float, float]:
    """The payload's submerged weight (N) and the line's per metre (N/m)."""
    spec = spec_from_scene(scene)
    return spec.payload_weight, spec.element.submerged_weight_per_length


def internal_step(scene: Scene, segments: int, ratio: float = DAMPING_RATIO) -> float:
    """The largest of MoorDyn's tried steps inside RK4's stability limit on the axial modes, s.

    A chain of node masses ``m s`` (``s = L / N``) joined by springs ``EA / s`` and dashpots
    ``BA / s`` has its highest frequency ``2 sqrt(EA / (m s^2))`` and, overdamped, its fastest
    decay rate ``4 BA / (m s^2)``; the step keeps ``h |lambda|`` within
    :data:`STABLE_STEP_FRACTION` of RK4's limit (2.8) for the larger of the two.
    """
    mass = scene.cable.mass_per_length * (scene.cable.length / segments) ** 2
    fastest = max(2 * math.sqrt(_axial_stiffness(scene) / mass),
                  4 * axial_damping(scene, ratio) / mass)  # fmt: skip
    limit = STABLE_STEP_FRACTION * 2.8 / fastest
    steps = [h for h in mc.MOORDYN_STEPS if h <= limit]
    if not steps:
        raise ValueError(f"no MoorDyn step of {mc.MOORDYN_STEPS} s is below {limit:.3g} s")
    return steps[0]


def moordyn_input(scene: Scene, segments: int, step: float, shift: float, ratio: float) -> str:
    """MoorDyn input of the scene's line (:func:`moordyn_compare.moordyn_input`) with the payload.

    The free point gets the payload's mass, volume, ``C_d A`` and ``C_a`` (MoorDyn's point drag
    is ``1/2 rho_w C_dA |v| v``, its added mass ``C_a rho_w V``), the line type ``BA``
    (:func:`axial_damping`). The free point starts :func:`static_stretch` below the unstretched
    line's end: MoorDyn's static solve (:data:`STATIC_SOLVE`) then converges in every case, where
    from the unstretched line it diverged under the 70 t payload (stretch 0.05 m of 7.1 m).
    """
    rows = mc.moordyn_input(scene, segments, step, shift).splitlines()
    payload = spec_from_scene(scene).payload
    for k, row in enumerate(rows):
        columns = row.split()
        if row.startswith("cable "):  # TypeName Diam Mass/m EA BA/-zeta EI Cd Ca CdAx CaAx
            columns[4] = repr(axial_damping(scene, ratio))
        elif row.startswith("1 Free "):  # ID Attachment X Y Z Mass Volume CdA Ca
            drag = payload.drag_coefficient * payload.drag_area
            columns[4] = repr(float(columns[4]) - static_stretch(scene))
            columns[5:9] = [repr(v) for v in (payload.mass, payload.volume, drag,
                                              payload.added_mass_coefficient)]  # fmt: skip
        elif "need this line" in row:  # the end of the options
            rows[k:k] = STATIC_SOLVE
            break
        else:
            continue
        rows[k] = " ".join(columns)
    return "\n".join(rows)


@dataclass(frozen=True)
class DeepRun:
    """One MoorDyn run, sampled every :data:`COUPLING_STEP`.

    Attributes
    ----------
    time : array (k,), s
        The sample times, from 0.
    top : array (k,), m
        The top's height, scene frame.
    payload : array (k,), m
        The payload's height, scene frame.
    tension : array (k,), N
        Top tension: the magnitude of the line's force on the top point.
    stretch : float, m
        Static stretch of MoorDyn's initial equilibrium.
    segments : int
        MoorDyn's ``N``.
    internal_step : float, s
        MoorDyn's internal step ``dtM``.
    wall_time : float, s
        Of the time loop.
    """

    time: np.ndarray
    top: np.ndarray
    payload: np.ndarray
    tension: np.ndarray
    stretch: float
    segments: int
    internal_step: float
    wall_time: float

    @property
    def ms_per_simulated_second(self) -> float:
        """Wall time per simulated second, ms/s."""
        return 1e3 * self.wall_time / float(self.time[-1])


def run_moordyn(scene: Scene, top: TopMotionFunction, duration: float, segments: int,
                step: float | None = None, ratio: float = DAMPING_RATIO) -> DeepRun:  # fmt: skip
    """Run the scene's line in MoorDyn from its static equilibrium with the top moved by ``top``.

    Parameters
    ----------
    scene : Scene
        The line, its payload and the sea; the top's motion comes from ``top``.
    top : callable
        ``t -> (position, velocity, ...)``, arrays (3, len(t)) in m, m/s (a ``Drive``'s ``top``).
    duration : float, s
        Simulated time.
    segments : int
        MoorDyn's ``N``.
    step : float, s, optional
        MoorDyn's internal step; :func:`internal_step` by default.
    ratio : float
        Damping ratio of the first axial mode.
    """
    if segments < 1:
        raise ValueError(f"segments = {segments!r} is out of range: must be >= 1")
    if not duration >= COUPLING_STEP:
        raise ValueError(f"duration = {duration!r} s is out of range: must be >= {COUPLING_STEP} s")
    if step is not None and not 0.0 < step <= COUPLING_STEP:
        raise ValueError(f"step = {step!r} s is out of range: must be in (0, {COUPLING_STEP}] s")
    import moordyn

    step = internal_step(scene, segments, ratio) if step is None else step
    times = np.arange(round(duration / COUPLING_STEP) + 1) * COUPLING_STEP
    position, velocity = top(times)[:2]
    shift = max(0.0, float(position[2].max())) + mc.SURFACE_CLEARANCE
    position = position - np.array([[0.0], [0.0], [shift]])
    payload, tension = np.full(times.size, np.nan), np.full(times.size, np.nan)
    with tempfile.TemporaryDirectory() as folder, mc._silenced_console():
        path = Path(folder) / "deep.txt"
        path.write_text(moordyn_input(scene, segments, step, shift, ratio))
        system = moordyn.Create(str(path))
        try:
            # At rest: MoorDyn's initial-condition solve moves the top with a velocity given here.
            moordyn.Init(system, position[:, 0].tolist(), [0.0, 0.0, 0.0])
            point = moordyn.GetPoint(system, 1)
            payload[0] = moordyn.GetPointPos(point)[2]
            tension[0] = math.hypot(*moordyn.GetPointForce(moordyn.GetPoint(system, 2)))
            started = time.perf_counter()
            for k in range(times.size - 1):
                force = moordyn.Step(system, position[:, k].tolist(), velocity[:, k].tolist(),
                                     float(times[k]), COUPLING_STEP)  # fmt: skip
                payload[k + 1] = moordyn.GetPointPos(point)[2]
                tension[k + 1] = math.hypot(*force)
            wall_time = time.perf_counter() - started
        finally:
            moordyn.Close(system)
    stretch = float(position[2, 0] - payload[0]) - scene.cable.length
    return DeepRun(times, position[2] + shift, payload + shift, tension, stretch, segments, step,
                   wall_time)  # fmt: skip


@dataclass(frozen=True)
class HeaveFigures:
    """Statistics of a heave run after :data:`SETTLE`.

    Attributes
    ----------
    vessel_heave_std, payload_heave_std : float, m
        Standard deviations of the top's and of the payload's heights.
    tension_min, tension_max : float, N
        Least and largest top tension.
    """

    vessel_heave_std: float
    payload_heave_std: float
    tension_min: float
    tension_max: float

    @property
    def tension_range(self) -> float:
        """``tension_max - tension_min``, N."""
        return self.tension_max - self.tension_min


def heave_run(scene: Scene, segments: int, step: float | None = None) -> DeepRun:
    """MoorDyn under the scene's heaving top (its ``Drive``) for ``SETTLE + RECORD`` seconds.

    ``scene``: :meth:`DeepCase.scene`; ``segments``: MoorDyn's ``N`` (``DeepCase.segments``).
    """
    top = Drive.from_scene(scene).top
    return run_moordyn(scene, top, SETTLE + RECORD, segments, step)


def heave_figures(time: np.ndarray, top: np.ndarray, payload: np.ndarray,
                  tension: np.ndarray) -> HeaveFigures:  # fmt: skip
    """The statistics of a heave run over ``t >= SETTLE``.

    Parameters
    ----------
    time : array (k,), s
        The sample times.
    top, payload : array (k,), m
        Heights of the top and of the payload.
    tension : array (k,), N
        Top tension.

    The arrays of a :class:`DeepRun`, or of any run of the same scene (the project's model).
    """
    kept = np.asarray(time) >= SETTLE
    tension = np.asarray(tension)[kept]
    return HeaveFigures(float(np.std(np.asarray(top)[kept])),
                        float(np.std(np.asarray(payload)[kept])),
                        float(tension.min()), float(tension.max()))  # fmt: skip


def decay_top(scene: Scene) -> TopMotionFunction:
    """The free decay's top: lifted by :data:`DECAY_LIFT` over ``T0 / 2``, then held.

    The lift is a quintic smoothstep, which puts most of its work into the first axial mode.

    Returns
    -------
    callable
        ``t -> (position, velocity, acceleration)``, arrays (3, len(t)) in m, m/s, m/s^2 (a
        ``Drive``'s ``top``), from ``scene.top.start``.
    """
    ramp = axial_period(scene) / 2
    start = np.asarray(scene.top.start, dtype=float).reshape(3, 1)
    up = np.array([[0.0], [0.0], [DECAY_LIFT]])

    def motion(t):
        tau = np.atleast_1d(np.asarray(t, dtype=float)) / ramp
        value, slope, _ = smoothstep(tau)
        return start + up * value, up * slope / ramp, up * smoothstep_curvature(tau) / ramp**2

    return motion


def decay_run(scene: Scene, segments: int, step: float | None = None) -> DeepRun:
    """MoorDyn's free decay from rest under :func:`decay_top`, for :data:`DECAY_PERIODS` T0.

    ``scene``: ``DeepCase.scene(heave=False)``; ``segments``: MoorDyn's ``N``.
    """
    period = axial_period(scene)
    return run_moordyn(scene, decay_top(scene), (DECAY_PERIODS + 0.5) * period, segments, step)


def _rest_offset_and_crossings(time: np.ndarray, top: np.ndarray, payload: np.ndarray):
    """The payload above its rest height (m); indices and times (s) of its upward crossings.

    Crossings once the top is held, linearly interpolated, the first one left out (higher
    modes). The rest height is the initial one plus :data:`DECAY_LIFT` (the static line moved up
    rigidly).
    """
    time, top, payload = (np.asarray(v, dtype=float) for v in (time, top, payload))
    offset = payload - (payload[0] + DECAY_LIFT)
    held = top >= top[-1] - 1e-12
    up = np.flatnonzero(held[:-1] & (offset[:-1] < 0.0) & (offset[1:] >= 0.0))
    if up.size < 4:
        raise ValueError(f"the free decay crossed its rest height {up.size} times (< 4)")
    step = time[up + 1] - time[up]
    crossings = time[up] - offset[up] * step / (offset[up + 1] - offset[up])
    return offset, up[1:], crossings[1:]


def decay_period(time: np.ndarray, top: np.ndarray, payload: np.ndarray) -> float:
    """The mean period between upward crossings of the payload's rest height in a free decay, s.

    Parameters
    ----------
    time : array (k,), s
        The sample times of a free decay.
    top, payload : array (k,), m
        Heights of the top (:func:`decay_top`) and of the payload, from rest.
    """
    _, _, crossings = _rest_offset_and_crossings(time, top, payload)
    return float((crossings[-1] - crossings[0]) / (crossings.size - 1))


def decay_damping_ratio(time: np.ndarray, top: np.ndarray, payload: np.ndarray) -> float:
    """The damping ratio of a free decay from its peaks: ``ln(a_0 / a_k) / (2 pi k)``.

    ``a_j`` the highest payload offset in each cycle between upward crossings; the arrays as in
    :func:`decay_period`. It includes the payload's and the line's drag besides ``BA``.
    """
    offset, up, _ = _rest_offset_and_crossings(time, top, payload)
    peaks = [offset[i:j].max() for i, j in zip(up[:-1], up[1:], strict=True)]
    return float(np.log(peaks[0] / peaks[-1]) / (2 * np.pi * (len(peaks) - 1)))


@dataclass(frozen=True)
class CaseRow:
    """One row of the deep-lowering table.

    Attributes
    ----------
    case : DeepCase
        The case the row measures.
    period_analytic, period_exact, period_moordyn : float, s
        ``T0`` of :func:`axial_period`, of :func:`axial_period_exact` and of MoorDyn's free
        decay.
    damping_moordyn : float
        The free decay's damping ratio (:func:`decay_damping_ratio`, drag included).
    static_tension : float, N
        Top tension of the line hanging at rest, ``W_p + w' L`` (:func:`static_top_tension`).
    stretch_analytic, stretch_moordyn : float, m
        Static stretch of the line: ``(W_p L + w' L^2 / 2) / EA`` (:func:`static_stretch`), and
        that of MoorDyn's initial equilibrium.
    heave : HeaveFigures
        MoorDyn's heave run at ``segments`` and its own step.
    heave_refined, heave_half_step : HeaveFigures
        At twice the segments (and their own step), and at half the step: the convergence.
    ms_per_simulated_second : float, ms/s
        MoorDyn's heave run.
    internal_step : float, s
        MoorDyn's step ``dtM`` of the heave run.
    """

    case: DeepCase
    period_analytic: float
    period_exact: float
    period_moordyn: float
    damping_moordyn: float
    static_tension: float
    stretch_analytic: float
    stretch_moordyn: float
    heave: HeaveFigures
    heave_refined: HeaveFigures
    heave_half_step: HeaveFigures
    ms_per_simulated_second: float
    internal_step: float

    @property
    def segments_change(self) -> float:
        """Largest relative change of the heave figures when the segments double."""
        return _largest_change(self.heave, self.heave_refined)

    @property
    def step_change(self) -> float:
        """Largest relative change of the heave figures when the internal step halves."""
        return _largest_change(self.heave, self.heave_half_step)


def _largest_change(a: HeaveFigures, b: HeaveFigures) -> float:
    """Largest relative change from ``a`` to ``b`` of the payload's heave std and the tensions."""
    pairs = [(a.payload_heave_std, b.payload_heave_std), (a.tension_min, b.tension_min),
             (a.tension_max, b.tension_max), (a.tension_range, b.tension_range)]  # fmt: skip
    return max(abs(y - x) / abs(x) for x, y in pairs)


def case_row(case: DeepCase) -> CaseRow:
    """Every figure of one case: analytic, free decay, heave at ``N``, ``2 N`` and half the step."""
    scene = case.scene()
    run = heave_run(scene, case.segments)
    refined = heave_run(scene, 2 * case.segments)
    half_step = heave_run(scene, case.segments, run.internal_step / 2)
    heave, heave_refined, heave_half_step = (heave_figures(r.time, r.top, r.payload, r.tension)
                                             for r in (run, refined, half_step))  # fmt: skip
    decay = decay_run(case.scene(heave=False), case.segments)
    free = (decay.time, decay.top, decay.payload)
    return CaseRow(case, axial_period(scene), axial_period_exact(scene), decay_period(*free),
                   decay_damping_ratio(*free), static_top_tension(scene), static_stretch(scene),
                   run.stretch, heave, heave_refined, heave_half_step,
                   run.ms_per_simulated_second, run.internal_step)  # fmt: skip


def print_table(rows: Iterable[CaseRow]) -> None:
    """Print the deep-lowering table (kN for tensions), each row as it comes."""
    print(f"MoorDyn deep lowering: winch locked, JONSWAP Hs {SEA_STATE['significant_height']} m, "
          f"Tp {SEA_STATE['peak_period']} s, seed {SEA_STATE['seed']}; statistics over "
          f"{SETTLE:g}..{SETTLE + RECORD:g} s; axial damping {DAMPING_RATIO:.0%} of the first "
          "mode")  # fmt: skip
    print("T0 [s]: Rayleigh (an.), continuum (exact), MoorDyn free decay (MD, err against an.) "
          "and its damping ratio (drag included); T_st, Tmin, Tmax, range: top tension [kN]; "
          "str: static stretch [m]; vessel, payload: heave std [m]; 2N, h/2 chg: largest change "
          "of the heave figures at twice the segments, half the step; ms/s: MoorDyn's wall time "
          "per simulated second")  # fmt: skip
    print(f"{'case':<17}{'N':>4}{'dtM [s]':>9}{'T0 an.':>8}{'exact':>8}{'T0 MD':>8}{'err':>7}"
          f"{'zeta':>7}{'T_st':>8}{'str an.':>9}{'str MD':>8}{'vessel':>8}{'payload':>8}{'Tmin':>8}"
          f"{'Tmax':>8}{'range':>8}{'2N chg':>8}{'h/2 chg':>8}{'ms/s':>8}")  # fmt: skip
    for r in rows:
        h = r.heave
        error = r.period_moordyn / r.period_analytic - 1
        print(f"{r.case.name:<17}{r.case.segments:>4}{r.internal_step:>9.0e}"
              f"{r.period_analytic:>8.3f}{r.period_exact:>8.3f}{r.period_moordyn:>8.3f}"
              f"{error:>7.1%}{r.damping_moordyn:>7.1%}"
              f"{r.static_tension / 1e3:>8.1f}{r.stretch_analytic:>9.3f}{r.stretch_moordyn:>8.3f}"
              f"{h.vessel_heave_std:>8.3f}{h.payload_heave_std:>8.3f}{h.tension_min / 1e3:>8.1f}"
              f"{h.tension_max / 1e3:>8.1f}{h.tension_range / 1e3:>8.1f}{r.segments_change:>8.2%}"
              f"{r.step_change:>8.2%}"
              f"{r.ms_per_simulated_second:>8.1f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    print_table(case_row(case) for case in CASES)
