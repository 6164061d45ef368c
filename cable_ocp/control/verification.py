"""Verification of a winch profile on the scene's own model: does it do what it claims.

What a user asks of an optimised profile: on the scene's full model, within the winch's limits, in
a simulation that can be trusted, where does it keep the end? :func:`verify_profile` answers it:

1. the winch bounds, held between the samples (:func:`cable_ocp.drive.bounds.violation`);
2. a simulation of the scene's model under the profile. Its bond residual is the health check of
   that simulation, not a measure of the profile: it is reported, and a run that leaves the
   scene's ``numerics.constraint_tolerance`` at the scene's step is tried again at half and a
   quarter of the step (the same output times) before the profile is declared unverifiable;
3. how long the winch rode a bound: a bound-limited optimum is a success that says so. With a heave
   feedforward the profile rides the bound less the heave's reach (its largest pay-out), at the
   wave crests and between them alike;
4. the smallest clearance ``z_E - z_sb`` over the run's samples, always reported; a scene with a
   hard minimum ``seabed.minimum_clearance`` fails a profile that takes the end closer than it
   (by more than :data:`CLEARANCE_TOLERANCE`), naming where and by how much. An end that leaves
   the bathymetry grid fails the profile at once (a smaller step would not bring it back).

Model correction learns from full-model runs that need not be at the scene's step: they run at
:func:`correction_step` (a multiple of it, well inside the RK4 stability limit), and only the
profile reported is verified at the scene's step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive.bounds import angle_bounds, violation
from cable_ocp.drive.drive import Drive
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError, step_count
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import OffGridError, clearance, clearance_reference
from cable_ocp.simulation.stability import linearised_step
from cable_ocp.simulation.statics import starting_state
from cable_ocp.simulation.trajectory import Trajectory

# Halvings of the scene's step tried when a run at it leaves its bonds or blows up.
STEP_HALVINGS = 2
# The winch counts as riding a bound while its angle's Bernstein coefficients are within this of
# it (rad, 0.5 mm of line on a 0.5 m drum).
BOUND_RIDE = 1e-3
# Model-correction runs of the full model take at most this multiple of the scene's step, and
# stay within this share of its linearised RK4 limit (:func:`correction_step`). The stability
# study's runs at 0.53 and 0.68 of the limit (n = 15 at h = 0.2 s, n = 100 at 0.025 s) kept the
# end within 2e-6 m and 1e-7 m of runs at a quarter of their step (notebooks/studies/bench.md).
CORRECTION_COARSENING = 4
CORRECTION_STABILITY_SHARE = 0.7
# What a profile under which the rope pushes can change: the optimisers bound the drum, not the
# rope's tension. Whole-space robustness seed 0 case 3 (a 34 mm rope, Hs 2 m): its optimum pushed
# from t = 1.6 s, the locked winch's run did not, and with winch.rate_max and acceleration_max
# halved the optimum verified (2026-12-06).
PUSHING_REMEDY = (
    " (the optimiser bounds the drum's angle, rate and acceleration, not the rope's tension: where "
    "the drum paid out faster than the rope could follow, lower winch.rate_max or "
    "winch.acceleration_max)"
)
# How far (m) the end may come under seabed.minimum_clearance before the profile fails: the
# verified run is the full model, the constraint was imposed on the optimiser's (often reduced) one.
CLEARANCE_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Verification:
    """The verdict on a winch profile.

    Attributes
    ----------
    trajectory : Trajectory or None
        The scene's model under the profile; None when the profile failed.
    reason : str or None
        Why it failed (a bound broken, or no trustworthy simulation); None when it passed.
    step : float, s
        RK4 step of the run that passed (the scene's, or a halving of it).
    bond_residual : float, m
        Largest bond residual of that run (NaN without one).
    bound_time : float, s
        Time the winch angle spent within :data:`BOUND_RIDE` of a bound.
    note : str
        How the run was obtained, when not at the scene's step (else empty).
    minimum_clearance : float, m
        Smallest clearance ``z_E - z_sb`` (= delta + e(t)) over the run's samples (NaN without a
        run); also reported when it broke ``seabed.minimum_clearance``.
    minimum_clearance_time : float, s
        When it was reached (NaN without a run).
    run : Trajectory or None
        The full model's run whenever there was a trustworthy one, also when it broke
        ``seabed.minimum_clearance`` (model correction learns from it).
    """

    trajectory: Trajectory | None
    reason: str | None
    step: float
    bond_residual: float = float("nan")
    bound_time: float = 0.0
    note: str = ""
    minimum_clearance: float = float("nan")
    minimum_clearance_time: float = float("nan")
    run: Trajectory | None = None


def correction_step(scene, compiled: bool = False, breakpoints=None) -> float:
    """RK4 step (s) of the full-model runs that model correction learns its bias from.

    The bias ``e_full - e_reduced`` is a correction to the optimisation model, so its runs need
    not be at the scene's step: the scene's step times the largest power of 2 up to
    :data:`CORRECTION_COARSENING` that divides the run into whole steps and stays within
    :data:`CORRECTION_STABILITY_SHARE` of the RK4 limit of the full model linearised at its start
    (:func:`cable_ocp.simulation.stability.linearised_step`). On paper_hill (n = 15) that is
    0.2 s against the scene's 0.05 s: a quarter of the cost, and e(t) within 7e-6 m of the
    scene's step. The profile that is reported is always verified at the scene's step.
    ``breakpoints`` (s), where given, are times (the control's nodes) that must stay on step
    ends of the coarser run as they are on the scene's.
    """
    numerics = scene.numerics
    count = step_count(numerics.duration, numerics.step)
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    start = starting_state(model, drive, compiled=compiled)
    rhs = None
    if compiled and structured.supports(model):
        rhs = structured.compiled_structured(model, "rhs")
    try:
        limit = linearised_step(model, start, drive.inputs(np.zeros(1))[:, 0], rhs=rhs)
    except (ValueError, RuntimeError):  # no eigenvalues to go by (numpy's LinAlgError included)
        return numerics.step
    factor = 1
    while (
        2 * factor <= CORRECTION_COARSENING
        and count % (2 * factor) == 0
        and _on_steps(breakpoints, 2 * factor * numerics.step)
        and 2 * factor * numerics.step <= CORRECTION_STABILITY_SHARE * limit
    ):
        factor *= 2
    return factor * numerics.step


def fitted_step(step: float, scene_step: float, breakpoints) -> float:
    """A correction step (s) halved until ``breakpoints`` (s) fall on its step ends.

    For a control whose nodes are not the ones :func:`correction_step` was fitted to (an
    adaptive grid's nodes kept); never below ``scene_step`` (s), on whose step ends they are.
    """
    while step > scene_step and not _on_steps(breakpoints, step):
        step /= 2
    return max(step, scene_step)


def _on_steps(times, step: float) -> bool:
    """Whether every time of ``times`` (s; None: none) is a whole multiple of ``step``."""
    if times is None:
        return True
    counts = np.asarray(times) / step
    return bool(np.all(np.abs(counts - np.round(counts)) <= 1e-9 * np.maximum(counts, 1.0)))


def verify_profile(
    scene,
    control,
    parameters: np.ndarray,
    quiet: bool = True,
    compiled: bool = False,
    step: float | None = None,
) -> Verification:
    """Check the bounds of a profile and simulate the scene's own model under it.

    Parameters
    ----------
    scene : Scene
        Heave compensation (a feedforward of the optimisation) is the scene's.
    control : KnotSpline or HermiteIntervals
    parameters : array
        The profile's parameters (rad, rad/s).
    quiet : bool
        No progress bar.
    compiled : bool
        Simulate the compiled model.
    step : float, optional, s
        Run at this multiple of the scene's step first (a model-correction run,
        :func:`correction_step`), falling back to the scene's step (and its halvings) if that
        run fails; the scene's step by default.

    Returns
    -------
    Verification
        Never raises for a failed check: the reason says what failed and where.
    """
    numerics = scene.numerics
    reason = violation(scene, control, parameters)
    if reason is not None:
        return Verification(None, reason, numerics.step)
    angle = control.angle_function(parameters)
    trials = [
        (numerics.step / 2**halving, numerics.output_every * 2**halving)
        for halving in range(STEP_HALVINGS + 1)
    ]
    if step is not None and step > numerics.step:
        factor = round(step / numerics.step)
        every = numerics.output_every
        trials.insert(0, (step, every // factor if every % factor == 0 else 1))
    drifted = []
    for trial_step, every in trials:
        trial = scene
        if trial_step != numerics.step:
            trial = scene.updated({"numerics.step": trial_step, "numerics.output_every": every})
        try:
            trajectory = simulate(trial, winch=angle, quiet=quiet, compiled=compiled)
        except OffGridError as error:
            return Verification(None, str(error), trial.numerics.step)
        except SimulationError as error:
            drifted.append(f"at h = {trial.numerics.step:g} s: {error}")
            continue
        except Exception as error:  # noqa: BLE001 - any other failure of the check fails it
            reason = f"the full-model simulation raised {type(error).__name__}: {error}"
            return Verification(None, reason, trial.numerics.step)
        note = ""
        if drifted:
            first = trials[0][0]
            what = "the model-correction run" if first > numerics.step else "the verification run"
            note = (
                f"{what} at h = {first:g} s failed ({drifted[0]}); it was run at "
                f"h = {trial.numerics.step:g} s"
            )
        lowest, when, broken = lowest_clearance(scene.seabed, trajectory)
        if broken is None and trajectory.physics.failures:  # a rope that pushes, an end underground
            broken = f"the verified run is not physical: {trajectory.physics.status}"
            if trajectory.physics.slack.reason:
                broken += PUSHING_REMEDY
        return Verification(
            None if broken else trajectory,
            broken,
            trial.numerics.step,
            trajectory.bond_residual,
            bound_time(scene, control, parameters, trajectory),
            note,
            lowest,
            when,
            trajectory,
        )
    reason = (
        f"no trustworthy simulation of the full model (the scene's own, n = "
        f"{scene.model.elements}) at the scene's step or {STEP_HALVINGS} halvings of it: "
        f"{'; '.join(drifted)}"
    )
    return Verification(None, reason, numerics.step / 2**STEP_HALVINGS)


def bound_time(scene, control, parameters: np.ndarray, trajectory: Trajectory) -> float:
    """Time (s) that the winch rode a bound of its angle within :data:`BOUND_RIDE`.

    The profile's own angle is compared with the bounds narrowed by the heave's reach (the
    largest pay-out of a heave feedforward; none without one), so that a profile pressed on its
    bound counts between the wave crests too.
    """
    low, high = angle_bounds(scene)
    profile = control.angle_function(parameters)(trajectory.time)[0]
    reach = float(np.max(np.abs(trajectory.winch_angle - profile)))
    riding = (profile <= low + reach + BOUND_RIDE) | (profile >= high - reach - BOUND_RIDE)
    both = riding[:-1] & riding[1:]
    return float(np.sum(np.diff(trajectory.time)[both]))


def lowest_clearance(seabed, trajectory: Trajectory) -> tuple[float, float, str | None]:
    """The smallest clearance ``z_E - z_sb`` over a run's samples, and whether it broke c_min.

    Parameters
    ----------
    seabed : Seabed
        The scene's ``[seabed]`` section.
    trajectory : Trajectory

    Returns
    -------
    clearance : float, m
        The smallest ``delta + e(t)``.
    time : float, s
        When.
    reason : str or None
        Where and by how much the end broke ``seabed.minimum_clearance`` (beyond
        :data:`CLEARANCE_TOLERANCE`); None when it held or the scene sets none.
    """
    end = trajectory.end
    heights = clearance(seabed, end, clearance_reference(seabed, end[0]))
    k = int(np.argmin(heights))
    lowest, when = float(heights[k]), float(trajectory.time[k])
    minimum = seabed.minimum_clearance
    if minimum is None or lowest >= minimum - CLEARANCE_TOLERANCE:
        return lowest, when, None
    below = heights < minimum - CLEARANCE_TOLERANCE
    span = trajectory.time[below]
    where = (
        f"comes within {lowest:.3g} m of the seabed"
        if lowest >= 0
        else f"goes {-lowest:.3g} m into the seabed"
    )
    reason = (
        f"the end {where} at t = {when:g} s, (x, y) = "
        f"({end[k, 0]:.1f}, {end[k, 1]:.1f}) m: {minimum - lowest:.3g} m under "
        f"seabed.minimum_clearance = {minimum:g} m (under it for {span.size} samples in "
        f"t = {span[0]:g}..{span[-1]:g} s)"
    )
    return lowest, when, reason
