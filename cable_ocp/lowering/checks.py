"""The checks of a landing run, from the run's own samples and independent of any solver.

:func:`check_landing` takes a simulated run of a ``[lowering]`` scene (a :class:`Trajectory` or
a :class:`LineTrajectory`, typically the verified full-model run) and the winch profile that
drove it, and measures each of the lowering's constraints on it (CONVENTIONS.md §5, lowering):
the landing error and vertical speed at ``lowering.land_time``, the band of the hold after it,
the least and the peak top tension, DNV-RP-H103's slack criterion (the top tension above 10 % of
its static value, :mod:`cable_ocp.simulation.slack`), the least signed bond tension anywhere (a
pushing bond is a slack rope), the drum's peak rate and acceleration between the samples, the
minimum clearance, and the seabed over the load's footprint (:func:`footprint_checks`). The
report also gives the dynamic amplification factor (the peak top tension over its static value).
Nothing here comes from a solver's own bookkeeping: positions, velocities and bond forces are
recomputed from the saved states and inputs by the model's outputs.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.verification import CLEARANCE_TOLERANCE
from cable_ocp.drive.bounds import BOUND_TOLERANCE
from cable_ocp.lowering.files import Flat
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel, spec_from_scene
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.line_models import line_models
from cable_ocp.scene.schema import Scene
from cable_ocp.simulation.line_run import pay_out_drive
from cable_ocp.simulation.line_trajectory import LineTrajectory
from cable_ocp.simulation.seabed import (
    OffGridError,
    clearance,
    clearance_reference,
    seabed_elevation,
)
from cable_ocp.simulation.slack import SLACK_FRACTION, run_static, signed_tensions, top_values
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.simulation.winch_input import winch_function

# Drum samples per output interval for the winch's rate and acceleration between the outputs.
DRUM_SAMPLES = 16
# The steepest seabed a load may be set down on, rad. A stated choice, not a standard's figure:
# subsea foundations (mudmats) are commonly designed for a few degrees of slope and levelled
# beyond; 10 degrees is twice that, and a load set down on more slides or tips.
SLOPE_LIMIT = np.radians(10.0)
# Added to the load's half-diagonal for the footprint's radius, m: a load lowered on a wire is
# set down within about a metre of its target (the vessel's station keeping, the load's swing).
FOOTPRINT_MARGIN = 1.0
# The footprint is sampled on rings at these fractions of its radius, at FOOTPRINT_ANGLES each.
FOOTPRINT_RINGS = (0.25, 0.5, 0.75, 1.0)
FOOTPRINT_ANGLES = 24


@dataclass(frozen=True)
class Check:
    """One constraint measured on a run.

    Attributes
    ----------
    name : str
        What is checked (``landing height``, ``top tension max``, ...).
    value : float
        The run's figure, in ``unit``.
    limit : float
        The bound it is held to, in ``unit``.
    unit : str
        The unit of ``value`` and ``limit`` (``m``, ``N``, ``rad/s``, ``of static``: each check
        has its own).
    passed : bool
        Whether ``value`` keeps within ``limit`` (the side the check names).
    where : str
        When (and where) the figure was reached.
    """

    name: str
    value: float
    limit: float
    unit: str
    passed: bool
    where: str

    def __str__(self) -> str:
        verdict = "ok" if self.passed else "FAILED"
        return (
            f"{self.name}: {self.value:.6g} {self.unit} against {self.limit:.6g} {self.unit} "
            f"{self.where}: {verdict}"
        )


@dataclass(frozen=True)
class LandingReport(Flat):
    """The checks of one landing run (:func:`check_landing`).

    Attributes
    ----------
    checks : tuple of Check
        Every constraint measured, in the order checked (kept in a file as a JSON table).
    landing_error : float, m
        ``z_E - z_sb - lowering.height`` at the landing time.
    landing_speed : float, m/s
        The end's vertical speed there (negative: going down).
    least_tension : float, N
        The least top tension over the run.
    peak_tension : float, N
        The largest top tension over the run.
    least_bond_tension : float, N
        The least signed tension of any bond at any sample (negative: a bond pushes).
    hold_deviation : float, m
        The largest ``|z_E - z_sb - lowering.height|`` from the landing time to the run's end.
    dynamic_amplification : float
        DNV-RP-H103's dynamic amplification factor: the largest top tension over its static
        value (the submerged weight hanging from the top then, :mod:`~cable_ocp.simulation.slack`).
    least_static_share : float
        The least top tension over its static value (DNV's slack criterion: above 0.1).
    """

    # CF units of the fields kept as variables (result_files.units).
    UNITS = MappingProxyType({
        "landing_error": "m", "landing_speed": "m s-1", "least_tension": "N", "peak_tension": "N",
        "least_bond_tension": "N", "hold_deviation": "m", "dynamic_amplification": "1",
        "least_static_share": "1",
    })  # fmt: skip

    checks: tuple[Check, ...]
    landing_error: float
    landing_speed: float
    least_tension: float
    peak_tension: float
    least_bond_tension: float
    hold_deviation: float
    dynamic_amplification: float = float("nan")
    least_static_share: float = float("nan")

    @property
    def passed(self) -> bool:
        """Whether every check passed."""
        return all(check.passed for check in self.checks)

    @property
    def failures(self) -> tuple[Check, ...]:
        """The checks that failed, in the order checked."""
        return tuple(check for check in self.checks if not check.passed)

    @property
    def reason(self) -> str:
        """One line per failed check; empty when every check passed."""
        return "; ".join(str(check) for check in self.failures)

    def __str__(self) -> str:
        amplification = f"dynamic amplification factor: {self.dynamic_amplification:.4g}"
        return "\n".join([*(str(check) for check in self.checks), amplification])


def check_landing(run: Trajectory | LineTrajectory, winch=None, scene=None) -> LandingReport:
    """Measure a ``[lowering]`` scene's constraints on a run of it.

    Parameters
    ----------
    run : Trajectory or LineTrajectory
        A run that reaches ``lowering.land_time``.
    winch : None, array, callable, OcpResult or MpcResult
        The winch profile that drove it, as :func:`cable_ocp.simulate` takes it: the drum's rate
        and acceleration are checked on it between the run's samples. A closed loop's
        (:class:`MpcResult`) is known only at its samples: the run's own line rate and
        acceleration are checked there.
    scene : Scene, optional
        Whose ``[lowering]``, ``[winch]`` limits and minimum clearance the run is held to
        (default: the run's own scene). The model is always the run's own.

    Returns
    -------
    LandingReport

    Raises
    ------
    TypeError
        ``run`` is not a run, ``winch`` is text, or ``scene`` is not a Scene (before any work).
    ValueError
        The scene has no ``[lowering]``, or the run ends before the landing time.
    """
    if not isinstance(run, Trajectory | LineTrajectory):
        raise TypeError(
            "check_landing: run must be a Trajectory or a LineTrajectory (co.simulate's, or a "
            f"result's .trajectory); got {type(run).__name__}"
        )
    if isinstance(winch, str):
        raise TypeError(
            f"check_landing: winch = {winch!r:.40}: must be the profile that drove the run "
            "(None, knot angles, a callable, or the OcpResult or MpcResult it came from)"
        )
    if scene is not None and not isinstance(scene, Scene):
        raise TypeError(f"check_landing: scene must be a Scene; got {type(scene).__name__}")
    scene = run.scene if scene is None else scene
    lowering = scene.lowering
    if lowering is None:
        raise ValueError(f"scene {scene.name!r} has no [lowering] table: nothing to check")
    time = run.time
    if time[-1] < lowering.land_time - 1e-9 * max(1.0, lowering.land_time):
        raise ValueError(
            f"the run ends at {time[-1]:g} s, before lowering.land_time = {lowering.land_time!r} s"
        )
    end = run.end
    height = clearance(scene.seabed, end, clearance_reference(scene.seabed, end[0]))
    deviation = height - lowering.height
    land = int(np.argmin(np.abs(time - lowering.land_time)))
    speed = float(_end_velocity(run)[land, 2])
    tensions, top = _bond_tensions(run)
    static = run_static(run, spec_from_scene(run.scene))
    static_top = top_values(static)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(static_top > 0, top / static_top, np.nan)
    after = slice(land, None)
    worst_hold = land + int(np.argmax(np.abs(deviation[after])))
    checks = [
        _bounded("landing height error", abs(deviation[land]), lowering.height_tolerance, "m",
                 f"at t = {time[land]:g} s"),
        _bounded("landing speed", abs(speed), lowering.landing_speed, "m/s",
                 f"at t = {time[land]:g} s"),
        _bounded("hold band", abs(deviation[worst_hold]), lowering.hold_band, "m",
                 f"at t = {time[worst_hold]:g} s"),
        _least("top tension min", top, lowering.tension_min, "N", time),
    ]  # fmt: skip
    if lowering.tension_max is not None:
        worst = int(np.argmax(top))
        checks.append(
            _bounded("top tension max", top[worst], lowering.tension_max, "N",
                     f"at t = {time[worst]:g} s")
        )  # fmt: skip
    if np.isfinite(share).any():
        worst = int(np.nanargmin(share))
        checks.append(
            Check("slack criterion (DNV-RP-H103)", float(share[worst]), SLACK_FRACTION,
                  "of static", bool(share[worst] > SLACK_FRACTION),
                  f"at t = {time[worst]:g} s (top tension {top[worst]:.4g} N, static "
                  f"{static_top[worst]:.4g} N)")
        )  # fmt: skip
    sample, bond = np.unravel_index(int(np.argmin(tensions)), tensions.shape)
    checks.append(
        Check("no slack bond", float(tensions[sample, bond]), 0.0, "N",
              bool(tensions[sample, bond] > 0.0), f"at t = {time[sample]:g} s, bond {bond + 1}")
    )  # fmt: skip
    if isinstance(winch, MpcResult):
        checks += drum_checks(scene.winch, time, *sampled_line(run))
    else:
        checks += _drum_checks(scene, winch, time)
    if scene.seabed.minimum_clearance is not None:
        k = int(np.argmin(height))
        least = scene.seabed.minimum_clearance
        where = f"at t = {time[k]:g} s, (x, y) = ({end[k, 0]:.1f}, {end[k, 1]:.1f}) m"
        checks.append(
            Check("minimum clearance", float(height[k]), least, "m",
                  bool(height[k] >= least - CLEARANCE_TOLERANCE), where)
        )  # fmt: skip
    checks += footprint_checks(scene, end[land], end[0], f"at t = {time[land]:g} s")
    return LandingReport(
        checks=tuple(checks),
        landing_error=float(deviation[land]),
        landing_speed=speed,
        least_tension=float(top.min()),
        peak_tension=float(top.max()),
        least_bond_tension=float(tensions.min()),
        hold_deviation=float(abs(deviation[worst_hold])),
        dynamic_amplification=float(np.nanmax(share)) if np.isfinite(share).any() else np.nan,
        least_static_share=float(np.nanmin(share)) if np.isfinite(share).any() else np.nan,
    )


def footprint_radius(scene) -> float:
    """The radius of the seabed a landed load covers, m.

    The half-diagonal of a square of the payload's plan area (its drag area, the area it shows
    to vertical flow; none without a payload), plus :data:`FOOTPRINT_MARGIN` for where it is
    set down.
    """
    payload = scene.end.payload
    area = 0.0 if payload is None else payload.drag_area
    return float(np.sqrt(area / 2)) + FOOTPRINT_MARGIN


def footprint_checks(scene, landing: np.ndarray, start: np.ndarray, where: str) -> list[Check]:
    """The seabed over the load's footprint at the landing: its slope and its highest point.

    Rule: on rings of the footprint's radius (:func:`footprint_radius`; fractions
    :data:`FOOTPRINT_RINGS` of it, :data:`FOOTPRINT_ANGLES` points each) around the end's
    landing position,

    - **seabed slope**: the steepest rise or fall from the seabed under the end to a point of
      the footprint, ``atan(|z_sb(p) - z_sb(E)| / |p - E|)``, must stay within
      :data:`SLOPE_LIMIT` (a load set down on more slides or tips);
    - **footprint clearance**: the end must be above the highest seabed point of its footprint
      (``z_E - max z_sb >= 0``): a cliff or a boulder beside the target is under the load.

    Parameters
    ----------
    scene : Scene
    landing : array (3,), m
        The end at the landing.
    start : array (3,), m
        The end at the run's start (a relative seabed's reference).
    where : str
        When, for the checks' text.
    """
    radius = footprint_radius(scene)
    angles = np.linspace(0.0, 2 * np.pi, FOOTPRINT_ANGLES, endpoint=False)
    distance = (radius * np.asarray(FOOTPRINT_RINGS))[:, None] * np.ones_like(angles)
    x = landing[0] + distance * np.cos(angles)
    y = landing[1] + distance * np.sin(angles)
    reference = clearance_reference(scene.seabed, start)
    try:
        ground = seabed_elevation(scene.seabed, x, y, reference)
    except OffGridError as error:
        return [Check("seabed footprint", radius, radius, "m", False, f"{where}: {error}")]
    centre = float(seabed_elevation(scene.seabed, landing[0], landing[1], reference))
    slopes = np.arctan(np.abs(ground - centre) / distance)
    k = np.unravel_index(int(np.argmax(slopes)), slopes.shape)
    highest = np.unravel_index(int(np.argmax(ground)), ground.shape)
    above = float(landing[2] - ground[highest])
    footprint = f"within {radius:.3g} m of the end"
    return [
        Check("seabed slope", float(np.degrees(slopes[k])), float(np.degrees(SLOPE_LIMIT)),
              "deg", bool(slopes[k] <= SLOPE_LIMIT),
              f"{where}, {footprint}, towards ({x[k]:.1f}, {y[k]:.1f}) m"),
        Check("footprint clearance", above, 0.0, "m", bool(above >= 0.0),
              f"{where}, over the highest seabed {footprint}, at ({x[highest]:.1f}, "
              f"{y[highest]:.1f}) m"),
    ]  # fmt: skip


def _bounded(name: str, value: float, limit: float, unit: str, where: str) -> Check:
    return Check(name, float(value), float(limit), unit, bool(value <= limit), where)


def _least(name: str, values: np.ndarray, limit: float, unit: str, time: np.ndarray) -> Check:
    k = int(np.argmin(values))
    return Check(name, float(values[k]), float(limit), unit, bool(values[k] >= limit),
                 f"at t = {time[k]:g} s")  # fmt: skip


def _over_run(run: Trajectory | LineTrajectory, values) -> np.ndarray:
    """``values(segment)`` over the whole run, joined as :meth:`LineTrajectory.joined` joins."""
    return run.joined(values) if isinstance(run, LineTrajectory) else values(run)


def _end_velocity(run: Trajectory | LineTrajectory) -> np.ndarray:
    """The end's velocity (k, 3), m/s: the rates of element 0's x, y, z in the states."""
    return _over_run(run, lambda s: s.states[:, s.states.shape[1] // 2 :][:, :3])


def _bond_tensions(run: Trajectory | LineTrajectory) -> tuple[np.ndarray, np.ndarray]:
    """Signed bond tensions (k, largest n + 1; padded with +inf) and the top's (k,), N.

    From the model's bond forces along the element axes at every saved state and input
    (positive pulls, negative pushes: ``model.outputs`` and the run keep only the norms).
    """
    scene = run.scene
    if isinstance(run, LineTrajectory):
        model_of = line_models(spec_from_scene(scene), run.element_length, compiled=True).model
        counts = run.element_count
    else:
        model_of = {run.tensions.shape[1] - 1: CableModel.from_scene(scene)}.__getitem__
        counts = np.full(run.time.size, run.tensions.shape[1] - 1)
    width = int(counts.max()) + 1

    def signed(segment: Trajectory) -> np.ndarray:
        n, count = segment.tensions.shape[1] - 1, segment.time.size
        joints, forces = _joints_and_forces(model_of(n), segment.states.T, segment.inputs.T)
        joints = np.array(joints).reshape(3, n + 2, count, order="F")
        forces = np.array(forces).reshape(3, n + 1, count, order="F")
        padded = np.full((count, width), np.inf)
        padded[:, : n + 1] = signed_tensions(joints.transpose(2, 0, 1), forces.transpose(2, 0, 1))
        return padded

    tensions = _over_run(run, signed)
    return tensions, tensions[np.arange(counts.size), counts]


def _joints_and_forces(model: CableModel, states: np.ndarray, inputs: np.ndarray):
    """Joints (3, (n + 2) k) and bond forces (3, (n + 1) k) of k states and inputs (columns).

    By the structure's compiled loops where it has them (a line's models: no graph is built),
    else by the model's own outputs.
    """
    if structured.supports(model):
        return structured.compiled_structured(model, "joints_and_forces")(states, inputs)
    outputs = model.parametric.output_values(states, inputs, model.parameters)
    return outputs["joints"], outputs["bond_forces"]


def _drum_checks(scene, winch, time: np.ndarray) -> list[Check]:
    """The drum's peak rate and acceleration (heave compensation included) against its limits."""
    if scene.winch.rate_max is None and scene.winch.acceleration_max is None:
        return []
    dense = np.linspace(time[0], time[-1], (time.size - 1) * DRUM_SAMPLES + 1)
    u = pay_out_drive(scene, winch_function(scene, winch)).inputs(dense)
    return drum_checks(scene.winch, dense, u[INPUTS.top_length_rate],
                       u[INPUTS.top_length_acceleration])  # fmt: skip


def sampled_line(run: Trajectory) -> tuple[np.ndarray, np.ndarray]:
    """The line's pay-out rate (m/s) and acceleration (m/s^2) at a run's samples, from its inputs.

    Heave compensation included: what the drum did, where no profile between the samples is
    known (a closed loop's plant run).
    """
    inputs = run.inputs
    return inputs[:, INPUTS.top_length_rate], inputs[:, INPUTS.top_length_acceleration]


def drum_checks(winch, time: np.ndarray, line_rate: np.ndarray, line_acceleration: np.ndarray):
    """The drum's peak rate and acceleration against the winch's limits, those it has.

    Parameters
    ----------
    winch : Winch
        The scene's ``[winch]`` (its radius and its limits, rad/s and rad/s^2).
    time : array (k,), s
    line_rate, line_acceleration : arrays (k,), m/s, m/s^2
        The top element's (the line's pay-out), heave compensation included.

    Returns
    -------
    list of Check
        ``drum rate`` and ``drum acceleration``, each where the winch sets its limit.
    """
    checks = []
    for name, line, limit, unit in (
        ("drum rate", line_rate, winch.rate_max, "rad/s"),
        ("drum acceleration", line_acceleration, winch.acceleration_max, "rad/s^2"),
    ):
        if limit is None:
            continue
        values = np.abs(line) / winch.drum_radius
        k = int(np.argmax(values))
        checks.append(
            Check(name, float(values[k]), limit, unit,
                  bool(values[k] <= limit * (1 + BOUND_TOLERANCE)), f"at t = {time[k]:g} s")
        )  # fmt: skip
    return checks
