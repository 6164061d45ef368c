"""The optimised and the closed-loop landing from a hover: the lowering objective of a WinchProblem.

A descent stops a little above its target (the hover, as installations do before the set-down:
the line settles, the position is confirmed), then the load is landed. :func:`landing_scene`
makes that last part a scene of fixed ``n``: the line whose hanging end is ``hover`` above the
target (trimmed on its statics), its own ``n`` of ``winch.line.element_length``, the drum free to
pay out the hover and :data:`~.hold.HOLD_RANGE` more, ``[lowering]`` kept with the land time of
the approach (:func:`approach_time`) and the hold after it. On such a scene the objective of the
one :class:`~cable_ocp.control.problem.WinchProblem` is the deviation from the landing reference
(:mod:`cable_ocp.simulation.landing_reference`: a smoothstep from the hover to the target height
at ``land_time``, held after), so every solver, the model correction and the verification on the
scene's own model are those of :func:`cable_ocp.optimize`, and the closed loop
(:func:`cable_ocp.mpc`, the measured heave fed back) is the same problem with its named
parameters set at every sample.

The top tension limits bound the reference's acceleration (:func:`tension_acceleration`: the line
and the load accelerated as one rigid body change the top tension by their mass times the
acceleration; a compensated heave moves the drum, not the load, so they are no limit on the
drum), the winch's rate and acceleration limits are the problem's linear bounds, the minimum
clearance its clearance rows. :func:`land` then measures every constraint on the
verified run by :func:`~.checks.check_landing`, code independent of the solver.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.keywords import refuse_unknown
from cable_ocp.control.optimization import OPTIMIZE_KEYWORDS, OcpResult, optimize
from cable_ocp.drive.drive import Drive
from cable_ocp.drive.vessel import top_motion
from cable_ocp.lowering.arguments import real_number
from cable_ocp.lowering.checks import LandingReport, check_landing
from cable_ocp.lowering.descent import landing_line
from cable_ocp.lowering.files import WithParts, check_landing_scene, check_recomputed
from cable_ocp.lowering.hold import (
    HOLD_RANGE,
    compensation_ratio,
    held_on_station,
    trimmed_line,
    vessel_heights,
)
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.schema import Scene, whole_steps
from cable_ocp.simulation.run import TOP_SHARE, check_rod, joints_and_tensions
from cable_ocp.simulation.statics import starting_state

HOVER = 10.0  # m above the target height where the descent stops before the landing
# Shares of the winch's line speed and acceleration, and multiple of lowering.landing_speed,
# that the landing reference's peak speed and acceleration may use (the rest is for the
# heave and the corrections).
SPEED_SHARE, ACCELERATION_SHARE, LANDING_SPEEDS = 0.5, 0.5, 10.0
SHORTEST_APPROACH = 10.0  # s
NO_ROOM = 0.1  # share of a winch limit used when the heave's peak leaves none
HEAVE_SAMPLE = 0.1  # s between the samples of the heave's peaks
APPROACH_ITERATIONS = 8  # of the approach and the heave's window (it stops growing in 2-3)
# Share of the room between the hover's top tension and each tension limit that the line's
# acceleration may use (the rest is for drag and the heave).
TENSION_SHARE = 0.5
# Peak speed and acceleration of the smoothstep S(t/T) over a drop H: 1.875 H/T, 5.7735 H/T^2.
PEAK_SPEED, PEAK_ACCELERATION = 1.875, 10 / math.sqrt(3)


def approach_time(scene, hover: float, hold: float) -> float:
    """The landing's duration from the hover (s, whole seconds): the reference's peaks in limits.

    The drum pays the heave out too, so the room is what the winch has beyond the heave's peaks
    over the landing and its ``hold`` (s) (:func:`heave_peaks`; the landing scene's sea is the
    scene's from t = 0, so the window grows with the approach until the approach stops
    growing). The smoothstep over ``hover`` (m) keeps its peak speed within
    :data:`SPEED_SHARE` of that room in line speed and within :data:`LANDING_SPEEDS` landing
    speeds, its peak acceleration within :data:`ACCELERATION_SHARE` of the room in line
    acceleration, and lasts at least :data:`SHORTEST_APPROACH`. A drum with no room beyond the
    heave is given :data:`NO_ROOM` of its limit (the landing's checks will say it is too slow).
    """
    approach = SHORTEST_APPROACH
    for _ in range(APPROACH_ITERATIONS):
        longer = _approach_within(scene, hover, *heave_peaks(scene, approach + hold))
        if longer <= approach:
            break
        approach = longer
    return approach


def _approach_within(scene, hover: float, heave_speed: float, heave_acceleration: float):
    """The approach (s) that keeps the reference's peaks within the room the heave leaves."""
    winch = scene.winch
    speed = LANDING_SPEEDS * scene.lowering.landing_speed
    if winch.rate_max is not None:
        line = winch.rate_max * winch.drum_radius
        speed = min(speed, SPEED_SHARE * max(line - heave_speed, NO_ROOM * line))
    needed = [SHORTEST_APPROACH, PEAK_SPEED * hover / speed]
    if winch.acceleration_max is not None:
        line = winch.acceleration_max * winch.drum_radius
        acceleration = ACCELERATION_SHARE * max(line - heave_acceleration, NO_ROOM * line)
        needed.append(math.sqrt(PEAK_ACCELERATION * hover / acceleration))
    return float(math.ceil(max(needed)))


def heave_peaks(scene, duration: float) -> tuple[float, float]:
    """The largest vertical speed (m/s) and acceleration (m/s^2) of the top over ``duration`` s.

    Sampled every :data:`HEAVE_SAMPLE` s from the scene's own top motion (its sea state, seed
    included); zero for a top that does not heave.
    """
    times = np.arange(0.0, duration + HEAVE_SAMPLE, HEAVE_SAMPLE)
    _, velocity, acceleration = top_motion(scene.top)(times)
    return float(np.abs(velocity[2]).max()), float(np.abs(acceleration[2]).max())


def tension_acceleration(scene: Scene, hover: float = 0.0) -> tuple[float, float]:
    """The line acceleration (m/s^2) the tension limits allow, and the hover's top tension (N).

    At the hover the top tension is ``T_0`` (the model's, at its equilibrium); once the ``hover``
    (m) is paid out it is about ``T_0 + w hover``, ``w`` the rope's submerged weight per metre.
    Paying out with acceleration ``a`` lowers it, hauling in raises it, by about ``m a``: ``m``
    the line's mass, the payload's and its added mass. Returned: :data:`TENSION_SHARE` of the
    smaller room, ``min(T_0 - tension_min, tension_max - T_0 - w hover) / m`` (0 when there is
    none), and ``T_0``.
    """
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    x0 = starting_state(model, drive, compiled=True)
    _, tensions = joints_and_tensions(model, x0[None, :], drive.inputs(np.zeros(1)).T, True)
    top = float(tensions[0, -1])
    element = model.spec.element  # the rope's mass and submerged weight per metre
    lowering = scene.lowering
    room = top - lowering.tension_min
    if lowering.tension_max is not None:
        weight = max(element.submerged_weight_per_length, 0.0)
        room = min(room, lowering.tension_max - top - weight * hover)
    mass = element.mass_per_length * scene.cable.length
    payload = scene.end.payload
    if payload is not None:
        mass += payload.inertia_in(scene.environment)
    return TENSION_SHARE * max(room, 0.0) / mass, top


def landing_scene(scene, hover: float = HOVER) -> Scene:
    """The fixed-``n`` landing of a ``[lowering]`` scene's load from a hover (module docstring).

    Parameters
    ----------
    scene : Scene, str or path-like
        With ``[lowering]`` and ``[winch.line]``, its vessel holding station (a path or a
        bundled name is loaded, :func:`~cable_ocp.scene.given.scene_given`).
    hover : float, m
        How far above the target height the descent stopped.

    Returns
    -------
    Scene
        ``[lowering]`` with the approach's ``land_time`` (:func:`approach_time`, lengthened
        where the reference's peak acceleration would be more than the tension limits allow,
        :func:`tension_acceleration`), and the hold of the scene after it
        (``numerics.duration - lowering.land_time``).

    Raises
    ------
    TypeError
        A hover that is not a number (before any work).
    ValueError
        A scene without ``[lowering]`` or ``[winch.line]``, a moving vessel, a hover that is not
        positive or that would make the top element a rigid rod of the line (naming ``hover``
        and its largest value here, :func:`_check_hover_rod`), or no hold.
    """
    checked_hover(hover)
    scene = scene_given(scene, "landing_scene")
    hold = held_on_station(scene, "a landing")
    lowering, step = scene.lowering, scene.numerics.step
    landing = landing_line(scene)
    line = landing - hover
    _check_hover_rod(hover, _landing_top(scene, line), line)
    approach = _on_steps(approach_time(scene, hover, hold), step)
    table = {**scene.to_dict()["lowering"], "land_time": approach}
    landed = trimmed_line(
        scene, lowering.height + hover, line, approach + hold, hover + HOLD_RANGE, table
    )
    _check_hover_rod(hover, landed.top_element_length, landed.cable.length)
    # The tension limits bound the load's acceleration, not the drum's: a compensated heave
    # moves the drum and leaves the load (and the tension) still. So they lengthen the approach.
    allowed, _ = tension_acceleration(landed, hover)
    if allowed > 0:
        needed = _on_steps(math.ceil(math.sqrt(PEAK_ACCELERATION * hover / allowed)), step)
        if needed > approach:
            landed = landed.updated(
                {"lowering.land_time": float(needed), "numerics.duration": needed + hold}
            )
    return landed


def checked_hover(hover) -> float:
    """``hover`` (m) as a float, or an error naming it: a finite number > 0.

    Raises
    ------
    TypeError
        Not a real number (a string, a bool, None).
    ValueError
        Not finite and positive.
    """
    hover = real_number("hover", hover, "m")
    if not hover > 0:
        raise ValueError(f"hover = {hover!r} m is out of range: must be > 0")
    return hover


def _landing_top(scene: Scene, line: float) -> float:
    """The landing scene's top element (m) on ``line`` (m) of the scene's line, as built.

    :func:`~.hold.trimmed_line` gives it the line's own ``n``, the drum's haul-in of
    :data:`~.hold.HOLD_RANGE` and the line's shortest top element
    (:meth:`~cable_ocp.scene.schema.Scene.mesh`: ``max(L / 2n, l_min + haul-in)``).
    """
    mesh = scene.winch.line.mesh
    return max(line / (2 * mesh.starting_elements(line)), mesh.top_length_min + HOLD_RANGE)


def _check_hover_rod(hover: float, top: float, line: float) -> None:
    """Refuse a hover whose pay-out would make the landing scene's top element a rigid rod.

    The landing pays the hover (and :data:`~.hold.HOLD_RANGE` more) out through its graded top
    element of ``top`` (m) at the hover, on ``line`` (m) of line there; the simulation's rule
    (:func:`~cable_ocp.simulation.run.check_rod`) refuses a top element of more than
    :data:`~cable_ocp.simulation.run.TOP_SHARE` of the line, and is asked here, blaming
    ``hover``. The excess falls one for one with the hover (the line out at the end,
    ``line + hover + HOLD_RANGE``, does not depend on it), so the largest hover is the hover
    less the excess: one figure, the same before and after the line is trimmed.
    """
    paid = hover + HOLD_RANGE
    try:
        check_rod(np.array([top + paid]), np.array([line + paid]), np.zeros(1))
    except ValueError:
        largest = hover - (top + paid - TOP_SHARE * (line + paid))
    else:
        return
    if largest <= 0:
        raise ValueError(
            f"hover = {hover!r} m is out of range: no hover fits here, the landing scene's top "
            f"element alone ({top:.4g} m: winch.line.top_length_min and the hold's "
            f"{HOLD_RANGE:g} m of haul-in) and the hold's pay-out leave more than "
            f"{TOP_SHARE:.0%} of the {line + paid:.4g} m of line out in it (a rigid rod, not a "
            "rope): land on a longer line, or shorten winch.line.top_length_min or "
            "winch.line.element_length"
        )
    raise ValueError(
        f"hover = {hover!r} m is out of range: must be > 0 and <= about {largest:.4g} m here: "
        f"the landing pays it out through its top element ({top:.4g} m at the hover), which "
        f"may hold at most {TOP_SHARE:.0%} of the {line + paid:.4g} m of line out then (more is "
        "a rigid rod, not a rope)"
    )


def _on_steps(duration: float, step: float) -> float:
    """``duration`` (s) rounded up to a whole number of RK4 steps of ``step`` (s).

    The landing scene's land time and duration must be whole steps (the scene refuses others);
    an approach of whole seconds is already, wherever the step divides a second.
    """
    if whole_steps(duration, step) is not None:
        return duration
    return math.ceil(duration / step) * step


@dataclass(frozen=True)
class LandingResult(WithParts):
    """A landing from the hover, optimised (open loop) or closed-loop, and its checks.

    Attributes
    ----------
    scene : Scene
        The landing scene (:func:`landing_scene`).
    closed_loop : bool
        Whether the closed loop landed it (:func:`cable_ocp.mpc`), else the optimum.
    result : OcpResult or MpcResult
        What :func:`cable_ocp.optimize` or :func:`cable_ocp.mpc` returned.
    report : LandingReport or None
        Every constraint measured on the verified run (the open loop's on the scene's own model,
        the closed loop's plant run); None when there is no run.
    compensation_ratio : float, %
        Over the hold (from ``land_time`` on): ``100 (1 - std z_E / std z_top)``; NaN in a calm.
    wall_time : float, s
        Wall-clock time of the landing, the landing scene's making included.
    """

    PARTS = ("result", "report")
    WHAT = "landing from the hover"
    # CF units of the fields kept as variables (a percentage is no SI symbol of a docstring).
    UNITS = MappingProxyType(
        {"closed_loop": "1", "compensation_ratio": "percent", "wall_time": "s"}
    )

    scene: Scene
    closed_loop: bool
    result: OcpResult | MpcResult
    report: LandingReport | None
    compensation_ratio: float
    wall_time: float

    def winch_profile(self, scene=None, retime: str | None = None):
        """The landing's winch angle, to replay it: ``simulate(landing.scene, winch=landing)``.

        That of its optimum or closed loop (``OcpResult.winch_profile``,
        ``MpcResult.winch_profile``), on ``scene`` (default: the landing scene).
        """
        return self.result.winch_profile(scene if scene is not None else self.scene, retime)

    def check_file(self) -> None:
        """Check a landing read from a file against the run its result holds.

        Its scene has ``[lowering]`` and is the scene its result ran on; its report and
        compensation ratio are what that run gives (:func:`_measured`, as :func:`land` made them).

        Raises
        ------
        ValueError
            Naming the field (a forged file).
        """
        check_landing_scene(self.scene, self.result.scene_record, "result")
        report, ratio = _measured(self.scene, self.result)
        check_recomputed("report", self.report, report)
        check_recomputed("compensation_ratio", self.compensation_ratio, ratio)

    @property
    def success(self) -> bool:
        """Whether the solver or the loop succeeded and every check passed on its run."""
        return bool(self.result.success) and self.report is not None and self.report.passed

    @property
    def status(self) -> str:
        """What happened, in one line."""
        what = "closed loop" if self.closed_loop else f"{self.result.solver} optimum"
        if not self.result.success:
            return f"the {what} failed: {self.result.status}"
        if self.report is None:
            return f"the {what} has no run to check"
        report = self.report
        found = (
            f"landing error {report.landing_error:+.3g} m at {report.landing_speed:+.3g} m/s, "
            f"hold {report.hold_deviation:.3g} m, top tension {report.least_tension / 1e3:.4g}-"
            f"{report.peak_tension / 1e3:.4g} kN"
        )
        if not math.isnan(self.compensation_ratio):
            found += f", compensation {self.compensation_ratio:.1f} %"
        if report.passed:
            return f"the {what} landed, every check passed ({found})"
        return f"the {what}: {found}; failed: {report.reason}"


# land's own keywords, and the keywords of :func:`cable_ocp.optimize` that ``optimize_options``
# may hold (``solver`` is land's own; ``scene`` and ``quiet`` are land's to give).
LAND_KEYWORDS = ("scene", "closed_loop", "hover", "quiet", "solver", "optimize_options",
                 "mpc_settings")  # fmt: skip
OPTIMIZE_OPTIONS = tuple(k for k in OPTIMIZE_KEYWORDS if k not in ("scene", "quiet", "solver"))


def land(
    scene, closed_loop: bool = False, hover: float = HOVER, quiet: bool = True, *,
    solver: str | None = None, optimize_options: Mapping[str, object] | None = None,
    mpc_settings: MpcSettings | None = None, **unknown,
) -> LandingResult:  # fmt: skip
    """Land a ``[lowering]`` scene's load from a hover, by optimisation or by the closed loop.

    Parameters
    ----------
    scene : Scene, str or path-like
        With ``[lowering]`` and ``[winch.line]`` (see :func:`landing_scene`), or a landing scene
        already (a fixed-``n`` scene with ``[lowering]``); a path or a bundled name is loaded.
    closed_loop : bool
        :func:`cable_ocp.mpc` (the measured heave fed back) instead of :func:`cable_ocp.optimize`.
    hover : float, m
        Where the descent stopped, above the target height.
    quiet : bool
        No progress.
    solver : str, optional
        The open loop's solver, as :func:`cable_ocp.optimize` takes it (default: its default).
    optimize_options : mapping, optional
        More keywords of :func:`cable_ocp.optimize` for the open loop (``settings``, ``model``,
        ``grid``, ``transcription``, ``refinements``, ``verbose``).
    mpc_settings : MpcSettings, optional
        The closed loop's settings (default: :class:`MpcSettings`'s defaults).
    **unknown
        Refused (TypeError naming the allowed keywords).

    Returns
    -------
    LandingResult
        Never raises for a landing that fails on a valid scene: ``success`` and ``status`` say
        why (the solver's or the loop's status, or the failed checks).

    Raises
    ------
    TypeError
        An unknown keyword, or an argument of the wrong type, before any work.
    ValueError
        Settings of the other loop (``mpc_settings`` for the open loop, ``solver`` or
        ``optimize_options`` for the closed one), or a scene or hover out of range, before any
        heavy work.
    """
    started = time.perf_counter()
    options = _land_arguments(closed_loop, solver, optimize_options, mpc_settings, unknown)
    checked_hover(hover)
    scene = scene_given(scene, "land")
    landing = scene if scene.winch.line is None else landing_scene(scene, hover)
    if landing.lowering is None:
        raise ValueError(f"scene {landing.name!r} has no [lowering] table: nothing to land")
    if closed_loop:
        result = mpc(landing, settings=mpc_settings, quiet=quiet)
    else:
        result = optimize(landing, quiet=quiet, **options)
    report, ratio = _measured(landing, result)
    return LandingResult(
        scene=landing,
        closed_loop=closed_loop,
        result=result,
        report=report,
        compensation_ratio=ratio,
        wall_time=time.perf_counter() - started,
    )


def _measured(landing: Scene, result: OcpResult | MpcResult) -> tuple[LandingReport | None, float]:
    """The checks of a landing's run and its compensation ratio (%; NaN without a report).

    None and NaN when the run is missing or ends before ``lowering.land_time``.
    """
    run = result.trajectory
    if run is None or run.time[-1] < landing.lowering.land_time:
        return None, float("nan")
    after = run.time >= landing.lowering.land_time
    ratio = compensation_ratio(vessel_heights(run)[after], run.end[after, 2])[0]
    return check_landing(run, result), ratio


def _land_arguments(closed_loop, solver, optimize_options, mpc_settings, unknown) -> dict:
    """:func:`land`'s arguments checked before any work; returns ``optimize``'s keywords."""
    refuse_unknown("land", unknown, LAND_KEYWORDS)
    if not isinstance(closed_loop, bool):
        raise TypeError(f"land: closed_loop = {closed_loop!r:.40} must be True or False")
    if mpc_settings is not None and not isinstance(mpc_settings, MpcSettings):
        raise TypeError(
            f"land: mpc_settings must be an MpcSettings (co.MpcSettings(...)); got "
            f"{type(mpc_settings).__name__}"
        )
    if optimize_options is not None and not isinstance(optimize_options, Mapping):
        raise TypeError(
            "land: optimize_options must be a mapping of optimize's keywords "
            f"({', '.join(OPTIMIZE_OPTIONS)}); got {type(optimize_options).__name__}"
        )
    options = dict(optimize_options or {})
    refuse_unknown("land(optimize_options=...)", {k: v for k, v in options.items()
                   if k not in OPTIMIZE_OPTIONS}, OPTIMIZE_OPTIONS)  # fmt: skip
    if closed_loop and (solver is not None or options):
        raise ValueError(
            "land(closed_loop=True): solver and optimize_options are the open loop's; the "
            "closed loop takes mpc_settings (co.MpcSettings(solver=...))"
        )
    if not closed_loop and mpc_settings is not None:
        raise ValueError(
            "land(closed_loop=False): mpc_settings is the closed loop's; the open loop takes "
            "solver and optimize_options"
        )
    return options if solver is None else {**options, "solver": solver}
