"""The open-loop landing, corrected on the full model until its verified run lands.

:func:`plan_landing` starts from :func:`~.descent.reference_descent` (the static landing line) and
simulates it on the scene's own model, the line paid out by elements: the run that the checks
(:func:`~.checks.check_landing`) judge. Where the vessel heaves and the scene does not compensate
it, the heave is paid out by eq. 38 on the approach, faded in over the descent's last ramp
(``w = S((t - T + t_r) / t_r)``, S the quintic smoothstep: the descent's own rate falls as
``v (1 - w)``, so the drum's rate stays about the larger of the cruise and the heave's), and held
from the landing on: the open loop knows the vessel's whole motion, as the clearance OCP's
feedforward does. The dynamic run lands off the static line by what the rope's drag and the
heave's offset leave, so the landing line is moved by the run's landing error and run again, up to
:data:`CORRECTIONS` times, until the error is within :data:`CORRECTION_SHARE` of
``lowering.height_tolerance``. After the landing the rope still settles (a light load on a long
line bowed by the current rises or sinks by decimetres over a minute), so each run's settling is
paid out in the next (:class:`HoldCorrection`, an iterative learning of the hold on the full
model) until the hold stays within :data:`HOLD_SHARE` of ``lowering.hold_band``
(CONVENTIONS.md §5, lowering).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from types import MappingProxyType

import numpy as np

from cable_ocp.drive.vessel import smoothstep, smoothstep_curvature, top_motion
from cable_ocp.lowering.checks import LandingReport, check_landing
from cable_ocp.lowering.descent import ReferenceDescent, reference_descent
from cable_ocp.lowering.files import Flat, WithParts, check_landing_scene, check_recomputed
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.schema import Scene
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.progress import stage
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import clearance, clearance_reference

CORRECTIONS = 4  # runs of the full model after the first
CORRECTION_SHARE = 0.1  # of lowering.height_tolerance: a landing error this small stops them
HOLD_SHARE = 0.5  # of lowering.hold_band: a hold this close (and a landing as above) stops them
HOLD_FADE = 10.0  # s after the landing over which the hold's correction fades in (C2)


@dataclass(frozen=True)
class LandingPlan(WithParts):
    """An open-loop landing and its verified run.

    Attributes
    ----------
    scene : Scene
        The ``[lowering]`` scene landed (kept in a file as its ``scene_record``).
    descent : ReferenceDescent
        The descent flown, its landing line corrected.
    heave_feedforward : bool
        Whether the heave was paid out on the approach.
    run : LineTrajectory or None
        The verified run of the last descent (None if the full model failed).
    report : LandingReport or None
        Its checks.
    landing_errors : tuple of float, m
        The landing error of each run, first to last.
    wall_time : float, s
        Wall-clock time of the plan, every run included.
    failure : str
        Why the full model failed ('' when it ran).
    hold : HoldCorrection or None
        The line paid out after the landing, learnt from the runs before the last.
    """

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "heave_feedforward": "1", "landing_errors": "m", "wall_time": "s",
    })  # fmt: skip

    PARTS = ("descent", "run", "report", "hold")
    DIMS = {"landing_errors": ("run_index",)}
    WHAT = "landing plan"

    scene: Scene
    descent: ReferenceDescent
    heave_feedforward: bool
    run: LineTrajectory | None
    report: LandingReport | None
    landing_errors: tuple[float, ...]
    wall_time: float
    failure: str = ""
    hold: HoldCorrection | None = None

    def check_file(self) -> None:
        """Check a plan read from a file against its verified run.

        Its scene has ``[lowering]`` and is the scene its run ran on; its report is what that
        run gives under the angle flown (:func:`~.checks.check_landing`, as :func:`plan_landing`
        made it), and the last of ``landing_errors`` is its landing error.

        Raises
        ------
        ValueError
            Naming the field (a forged file).
        """
        check_landing_scene(self.scene, self.run.scene_record if self.run else {}, "run")
        if (self.run is None) != (self.report is None):
            raise ValueError("report: kept without its run, or a run kept without its report")
        if self.run is None:
            return
        check_recomputed("report", self.report, check_landing(self.run, self.angle))
        errors = self.landing_errors
        check_recomputed("landing_errors[-1]", errors[-1] if errors else None,
                         self.report.landing_error)  # fmt: skip

    @property
    def success(self) -> bool:
        """Whether the verified run passed every check."""
        return self.report is not None and self.report.passed

    @property
    def status(self) -> str:
        """What happened, in one line."""
        if self.report is None:
            return f"the full model failed: {self.failure}"
        runs = len(self.landing_errors)
        found = f"landing error {self.report.landing_error:+.3g} m after {runs} run(s)"
        if self.report.passed:
            return f"every check passed ({found})"
        return f"{found}; failed: {self.report.reason}"

    def angle(self, t, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The winch angle flown (rad, rad/s, rad/s^2), the approach's heave included."""
        return _landing_angle(self.scene, self.descent, self.heave_feedforward, self.hold)(t)

    def winch_profile(self, scene=None):
        """The winch angle flown, to replay the plan: ``simulate(plan.scene, winch=plan)``.

        :meth:`angle`, in the plan's own time on any ``scene``: held after the landing, its
        heave feedforward that of the plan's scene's sea.
        """
        return self.angle


def _faded(t: np.ndarray, start: float, length: float, value, rate, acceleration):
    """``w(t) f(t)`` with its rate and acceleration, ``f`` given with its own (m, m/s, m/s^2).

    ``w`` is the smoothstep over ``[start, start + length]`` (s): 0 before, 1 after, and its
    value, slope and curvature are 0 at ``start``, so the product is C2 wherever ``f`` is.
    """
    tau = (t - start) / length
    w, slope, _ = smoothstep(tau)
    dw, ddw = slope / length, smoothstep_curvature(tau) / length**2
    return w * value, dw * value + w * rate, ddw * value + 2 * dw * rate + w * acceleration


def approach_feedforward(scene, descent: ReferenceDescent):
    """The descent's winch angle with the heave paid out on its approach (eq. 38, faded in).

    ``phi = phi_descent + w(t) (z_A(t) - z_A(0)) / r_D`` with ``w`` the smoothstep over the
    descent's last ramp (0 before it, 1 from the landing on), and its rates by the product rule.
    """
    top = top_motion(scene.top)
    start = top(np.zeros(1))[0][2, 0]
    begins, ramp = descent.land_time - descent.ramp, descent.ramp

    def heave(t):
        position, velocity, acceleration = top(t)
        return _faded(t, begins, ramp, position[2] - start, velocity[2], acceleration[2])

    return _paying_out(descent.angle, heave, scene.winch.drum_radius)


@dataclass(frozen=True)
class HoldCorrection(Flat):
    """Line paid out on top of the descent after the landing (m), learnt from full-model runs.

    ``c(t) = w(t) g(t)``: ``g`` the runs' settling after the landing (``e(t) - e(T)``, ``e``
    the end's height above the target; a C2 cubic spline through ``values`` at ``times``, held
    after the last), ``w`` the quintic smoothstep over :data:`HOLD_FADE` s from ``land_time``,
    whose value, slope and curvature vanish there, so that ``c`` is C2 and zero before the
    landing. :meth:`learnt` adds a run's settling to ``g``: the next run pays it out, as the end
    falls by what is paid out.

    Attributes
    ----------
    land_time : float, s
        Where the correction starts to fade in (``lowering.land_time``).
    times : array (k,), s
        The settling's knots, from ``land_time`` on.
    values : array (k,), m
        The line paid out at each knot (``g``).
    """

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "land_time": "s", "times": "s", "values": "m",
    })  # fmt: skip

    DIMS = {"times": ("hold_knot",), "values": ("hold_knot",)}

    land_time: float
    times: np.ndarray
    values: np.ndarray

    @classmethod
    def none(cls, land_time: float) -> HoldCorrection:
        """No correction."""
        return cls(land_time, np.array([land_time, land_time + 1.0]), np.zeros(2))

    def _settling(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from scipy.interpolate import CubicSpline

        spline = CubicSpline(self.times, self.values, bc_type="natural")
        inside = (t <= self.times[-1]) * 1.0
        held = np.clip(t, self.times[0], self.times[-1])
        return spline(held), spline(held, 1) * inside, spline(held, 2) * inside

    def line(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The correction (m) with its rate (m/s) and acceleration (m/s^2) at ``t`` (s)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if not self.values.any():
            zeros = np.zeros(t.shape)
            return zeros, zeros.copy(), zeros.copy()
        return _faded(t, self.land_time, HOLD_FADE, *self._settling(t))

    def learnt(self, run, target: float, seabed_heights: np.ndarray) -> HoldCorrection:
        """The correction with the settling of ``run`` after the landing added.

        ``seabed_heights`` (k,) are the run's end heights above the seabed (m), ``target`` the
        lowering's height (m).
        """
        after = run.time >= self.land_time
        times = run.time[after]
        error = seabed_heights[after] - target
        settling = error - error[0]
        if self.values.any():
            settling = settling + self._settling(times)[0]
        return HoldCorrection(self.land_time, times, settling)


def _heaves(scene) -> bool:
    heave = scene.top.heave
    moving = heave is not None and (bool(heave.amplitude) or heave.sea_state is not None)
    return moving and not scene.top.heave_compensated


def _landing_angle(scene, descent: ReferenceDescent, feedforward: bool,
                   hold: HoldCorrection | None = None):  # fmt: skip
    angle = approach_feedforward(scene, descent) if feedforward else descent.angle
    if hold is None or not hold.values.any():
        return angle
    return _paying_out(angle, hold.line, scene.winch.drum_radius)


def _paying_out(angle, line, radius: float):
    """The winch angle ``angle`` with the drum paying ``line(t)`` more out (m, m/s, m/s^2)."""

    def paid(t, left=None):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return tuple(a + m / radius for a, m in zip(angle(t), line(t), strict=True))

    return paid


def plan_landing(scene, quiet: bool = True) -> LandingPlan:
    """Land a ``[lowering]`` scene's load in open loop, verified on the scene's own model.

    Parameters
    ----------
    scene : Scene, str or path-like
        With ``[lowering]`` and ``[winch.line]`` (a path or a bundled name is loaded).
    quiet : bool
        No progress bars.

    Returns
    -------
    LandingPlan
        Never raises for a landing that fails on a valid scene: ``success`` and ``status`` say
        why (a failed check, or the full model's failure).

    Raises
    ------
    TypeError
        A scene that is none (:func:`~cable_ocp.scene.given.scene_given`).
    ValueError
        A scene without ``[lowering]`` or ``[winch.line]``, before any work.
    DescentError
        Before any simulation: no descent within the winch's limits reaches the landing.
    """
    started = time.perf_counter()
    scene = scene_given(scene, "plan_landing")
    if scene.lowering is None or scene.winch.line is None:
        raise ValueError(
            f"scene {scene.name!r}: plan_landing needs a scene with [lowering] and [winch.line] "
            "(see models/deploy.toml)"
        )
    lowering = scene.lowering
    descent = reference_descent(scene)
    feedforward = _heaves(scene)
    hold = HoldCorrection.none(lowering.land_time)
    errors: list[float] = []
    run = report = None
    for attempt in range(1, CORRECTIONS + 2):
        angle = _landing_angle(scene, descent, feedforward, hold)
        label = f"landing run {attempt} of {scene.name}"  # one bar for its segments
        try:
            with stage(label, scene.numerics.duration, quiet=quiet):
                run = simulate(scene, winch=angle, quiet=quiet)
        except SimulationError as error:
            return LandingPlan(scene, descent, feedforward, None, None, tuple(errors),
                               time.perf_counter() - started, str(error), hold)  # fmt: skip
        report = check_landing(run, angle)
        errors.append(report.landing_error)
        landed = abs(report.landing_error) <= CORRECTION_SHARE * lowering.height_tolerance
        held = landed and report.hold_deviation <= HOLD_SHARE * lowering.hold_band
        if held or attempt > CORRECTIONS:  # the plan keeps the descent its run flew
            break
        # Too high by the error: pay out as much more (the end falls by what is paid out).
        descent = replace(descent, landing_line=descent.landing_line + report.landing_error)
        hold = hold.learnt(run, lowering.height, _heights(run, scene))
    return LandingPlan(scene, descent, feedforward, run, report, tuple(errors),
                       time.perf_counter() - started, hold=hold)  # fmt: skip


def _heights(run, scene) -> np.ndarray:
    """The end's height above the seabed over a run (k,), m."""
    end = run.end
    return clearance(scene.seabed, end, clearance_reference(scene.seabed, end[0]))
