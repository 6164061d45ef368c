"""The closed loop: ``mpc(scene, settings)`` runs the plant under the controller, sample by sample.

As in do-mpc's loop, three parts each make a step every ``sample`` seconds: the estimator
(:mod:`.estimator`) turns the plant's measurements into the controller's view (the reduced state,
the top forecast, the room for the heave feedback), the controller (:mod:`.controller`) solves the
receding-horizon winch problem from its previous plan moved on by one sample, and the plant
(:mod:`.plant`) runs one sample under the new plan with the heave feedback. A failed solve keeps
the previous plan, and is counted and reported. The controller never sees the heave except
through these measurements. Each part's ``make_step`` is public: the loop below is those three
calls and the bookkeeping of what they return (a :class:`~.plant.Measurement` per sample, a
:class:`~.controller.Solve` per solve).
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from cable_ocp.control.closed_loop.controller import WIDENED, RecedingHorizon
from cable_ocp.control.closed_loop.estimator import Estimator
from cable_ocp.control.closed_loop.forecast import BlendedHeight
from cable_ocp.control.closed_loop.plant import Plant
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.interrupts import interrupt_here
from cable_ocp.control.ocp import compile_ahead, make_control, resolved
from cable_ocp.control.optimization import METHODS, optimize
from cable_ocp.control.verification import lowest_clearance
from cable_ocp.drive.bounds import angle_bounds
from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.drive.drive import Drive
from cable_ocp.drive.winch import heave_payout
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress
from cable_ocp.simulation.seabed import (
    OffGridError,
    check_start,
    clearance_error,
    clearance_reference,
    rms_objective,
)


class Plan:
    """The plan in force: the controller's parameters from the solve at ``start`` (s).

    A new plan starts at the winch's angle and rate (its first node is held there) but not at
    its acceleration: over its first ``blend`` seconds (one RK4 step of the controller's model)
    it takes over from the ``previous`` one by the quintic smoothstep, as the heave reference
    does (:class:`.forecast.BlendedHeight`), so that the top element's acceleration never jumps
    at a sample (with it, one of the 5 heaving robustness scenes whose plant's bonds opened ran
    through; a wider limiter band did the rest, ``MpcSettings.limiter_band``).
    """

    def __init__(
        self,
        start: float,
        parameters: np.ndarray,
        control: HermiteIntervals,
        previous: Plan | None = None,
        blend: float = 0.0,
    ):
        self.start, self.parameters, self.control = start, parameters, control
        self.previous, self.blend = previous, blend

    def __call__(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Angle, rate and acceleration (rad, rad/s, rad/s^2) at the times ``t``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        new = self.control.evaluate(self.parameters, t - self.start, left)
        if self.previous is None or self.blend <= 0:
            return tuple(new)
        old = self.previous(t, left)
        tau = np.clip((t - self.start) / self.blend, 0.0, 1.0)
        keep = 1 - tau**3 * (10 - 15 * tau + 6 * tau**2)
        keep_rate = -30 * tau**2 * (1 - tau) ** 2 / self.blend
        keep_acc = -(60 * tau - 180 * tau**2 + 120 * tau**3) / self.blend**2
        gap = [o - n for o, n in zip(old, new, strict=True)]
        return (
            new[0] + keep * gap[0],
            new[1] + keep * gap[1] + keep_rate * gap[0],
            new[2] + keep * gap[2] + 2 * keep_rate * gap[1] + keep_acc * gap[0],
        )

    def settled(self) -> Plan:
        """The same plan without its predecessor (once the blend is over)."""
        return Plan(self.start, self.parameters, self.control)


def _command(plan: Plan, reference: BlendedHeight | None, top, radius: float):
    """The commanded angle: the plan, plus the heave feedback when ``reference`` is given."""

    def angle(t, left=None):
        phi, rate, acc = plan(t, left)
        if reference is None:
            return phi, rate, acc
        position, velocity, acceleration = top(t)
        height, speed, height_acc = reference(t)
        payout = heave_payout(
            position[2] - height, velocity[2] - speed, acceleration[2] - height_acc, radius
        )
        return phi + payout[0], rate + payout[1], acc + payout[2]

    return angle


def mpc(scene, settings: MpcSettings | None = None, quiet: bool = False, **fields) -> MpcResult:
    """Closed-loop winch control of a scene by a receding-horizon OCP.

    Parameters
    ----------
    scene : Scene
        The plant (its own model, step and top motion, heave included).
    settings : MpcSettings, optional
        How the controller is built and run (defaults: a 20 s horizon re-solved every 1 s by one
        Gauss-Newton step on a 2-element model; the sample, horizon, plan intervals and the
        controller's step left unset are derived from the scene, :meth:`MpcSettings.resolved`,
        and the result's ``settings["derived"]`` says how).
    quiet : bool
        Print nothing (otherwise a progress bar on stderr).
    **fields
        Fields of :class:`MpcSettings` to set instead of passing ``settings`` (``horizon=10.0``).

    Returns
    -------
    MpcResult
        ``success`` is False if any solve failed (see ``failures``), the plant failed or its end
        left the bathymetry grid (the loop then stops there, with the arrays up to that time),
        or the end came under ``seabed.minimum_clearance``; ``status`` says which, when and
        where. A reference run that fails is left out, with the reason in ``status``.

    Raises
    ------
    ValueError
        A setting out of its range, or one that does not fit the scene, before any heavy work.
    OffGridError
        The end starts off the bathymetry grid or under the seabed (before the loop), as for
        ``simulate``.
    """
    if settings is not None and fields:
        raise ValueError(f"mpc: pass settings or its fields ({', '.join(fields)}), not both")
    settings = settings or MpcSettings(**fields)
    settings, derived = settings.resolved(scene)
    started = time.perf_counter()
    compile_ahead(scene, settings.elements, settings.solver == "gauss-newton")
    low, high = angle_bounds(scene)
    controller = RecedingHorizon(scene, settings)
    plant = Plant(scene, (low, high), settings.limiter_band)
    radius = scene.winch.drum_radius
    duration, h = scene.numerics.duration, plant.step
    samples = round(duration / settings.sample)
    build_time = time.perf_counter() - started

    loop_started = time.perf_counter()
    plan = Plan(0.0, np.zeros(controller.control.size), controller.control)
    zero = np.zeros(1)
    position, velocity, _ = plant.top(zero)
    estimator = Estimator(settings, plant.model, controller.model, radius, position[2, 0])
    previous = estimator.forecast(0.0, position[:, 0], velocity[:, 0])
    height = BlendedHeight(previous, previous, 0.0, settings.sample)
    if not settings.heave_feedback:
        height = None
    # With the heave feedback the winch already pays out the heave's speed at t = 0.
    measured = plant.start(_command(plan, height, plant.top, radius))
    check_start(scene.seabed, plant.state[:3])
    estimator.reference = clearance_reference(scene.seabed, plant.state)
    runs, planned, solves, failures = [measured], [np.zeros(1)], [], []
    plant_failure = None
    progress = Progress("mpc", duration, quiet)
    for k in range(samples):
        now = k * settings.sample
        phi, rate, _ = plan(np.array([now]))
        estimate = estimator.make_step(measured, phi[0], rate[0])
        solve = controller.make_step(now, estimate, phi[0], rate[0])
        solves.append(solve)
        if solve.success:
            plan = Plan(now, solve.parameters, controller.control, plan.settled(), settings.step)
        else:
            failures.append(f"t = {now:g} s: {solve.status}")
        if settings.heave_feedback:
            height = BlendedHeight(previous, estimate.forecast, now, settings.sample)
        previous = estimate.forecast
        try:
            measured = plant.make_step(
                _command(plan, height, plant.top, radius), (k + 1) * settings.sample
            )
        except SimulationError as error:
            where = ", ".join(f"{value:.6g}" for value in plant.state[:3])
            verb = "stopped" if isinstance(error, OffGridError) else "failed"
            plant_failure = (
                f"the plant {verb} between t = {now:g} and {now + settings.sample:g} s (the end "
                f"at (x, y, z) = ({where}) m at t = {now:g} s): {error}"
            )
            break
        runs.append(measured)
        planned.append(plan(measured.time)[0])
        progress.update(now + settings.sample, f"solve {solve.solve_time * 1e3:.0f} ms")
    progress.close()
    wall_time = time.perf_counter() - loop_started

    time_grid = np.concatenate([run.time for run in runs])
    end = np.concatenate([run.states for run in runs])[:, 0:3]
    error = clearance_error(scene.seabed, end)
    ref_errors, ref_failures = _references(scene, plant, settings.references, time_grid)
    # lowest_clearance reads a run's time and end, as a Trajectory has them.
    _, _, too_low = lowest_clearance(scene.seabed, SimpleNamespace(time=time_grid, end=end))
    statuses = [solve.status for solve in solves]
    solve_times = [solve.solve_time for solve in solves]
    widened = sum(WIDENED in text for text in statuses)
    if widened:
        ref_failures = [f"{widened} solves {WIDENED}", *ref_failures]
    status = _status(samples, failures, plant_failure, too_low, ref_failures)
    return MpcResult(
        time=time_grid,
        winch_angle=np.concatenate([run.applied.angle for run in runs]),
        planned_angle=np.concatenate(planned),
        end=end,
        top=np.concatenate([run.inputs for run in runs])[:, 0:3],
        clearance_error=error,
        # No Omega of a plant that failed in its first sample (one point, no span).
        omega=rms_objective(time_grid, error) if time_grid.size > 1 else float("nan"),
        sample_times=settings.sample * np.arange(len(solves)),
        solve_times=np.array(solve_times),
        iterations=np.array([solve.iterations for solve in solves]),
        statuses=statuses,
        failures=failures,
        success=not failures and plant_failure is None and too_low is None,
        limited_steps=sum(int(np.count_nonzero(run.applied.limited)) for run in runs[1:]),
        projected_samples=plant.projections,
        angle_range=(low, high),
        real_time_factor=duration / wall_time,
        worst_solve_time=float(np.max(solve_times)),
        wall_time=wall_time,
        build_time=build_time,
        settings={
            **settings.record(),
            "derived": derived,
            "plant_elements": scene.model.elements,
            "plant_step_s": h,
        },
        references=ref_errors,
        reference_omegas={k: rms_objective(time_grid, v) for k, v in ref_errors.items()},
        status=status,
        scene_record=scene.to_dict(),
    )


SHOWN_FAILURES = 3  # failed solves named in the status (all of them are in MpcResult.failures)


def _status(
    samples: int,
    failures: list[str],
    plant_failure: str | None,
    too_low: str | None,
    notes: list[str],
) -> str:
    """One line on how the loop went: plant, minimum clearance, solves, then ``notes``.

    The notes: solves on the winch's own range, reference runs left out.
    """
    parts = [reason for reason in (plant_failure, too_low) if reason]
    parts.append(
        f"{len(failures)} of {samples} solves failed (the plant kept the previous plan): "
        + "; ".join(failures[:SHOWN_FAILURES])
        + ("; ..." if len(failures) > SHOWN_FAILURES else "")
        if failures
        else "every solve succeeded"
    )
    return "; ".join(parts + notes)


def _run_open(plant: Plant, angle, time_grid: np.ndarray) -> np.ndarray:
    """Clearance error of the plant under a fixed angle history (no controller).

    Raises SimulationError when the plant fails under it.
    """
    x = plant.initial_state(plant.apply(angle, np.zeros(1)))
    interrupt_here("reference run")
    states, _, _ = plant.advance(x, 0.0, time_grid.size - 1, angle)
    return clearance_error(plant.scene.seabed, states[:, 0:3])


def _references(scene, plant: Plant, names, time_grid) -> tuple[dict[str, np.ndarray], list]:
    """The reference runs asked for (see :func:`mpc`), and why any of them is missing."""
    out, missing = {}, []

    def run(name, angle):
        try:
            out[name] = _run_open(plant, angle, time_grid)
        except SimulationError as error:
            missing.append(f"reference {name!r} left out: its plant run failed ({error})")

    if time_grid[-1] < scene.numerics.duration:
        return out, ["no reference runs: the loop stopped early"]
    if "locked" in names:
        run("locked", lambda t: tuple(np.zeros((3, np.size(t)))))
    if "open-loop" in names:
        # The open loop knows no heave at all: neither the sine nor the sea state.
        calm = scene.updated({"top.heave": None})
        try:
            # The settings optimize() derives, fixed here: the profile's control needs them.
            settings, _ = resolved(calm, METHODS["ipopt"].default)
            result = optimize(calm, settings=settings, quiet=True)
        except (ValueError, RuntimeError) as error:  # the derivation's locked run, say
            missing.append(f"reference 'open-loop' left out: {error}")
            return out, missing
        if not result.success:
            missing.append(f"reference 'open-loop' left out: {result.status}")
            return out, missing
        profile = make_control(calm, settings).angle_function(result.parameters)
        run("open-loop", profile)
        if scene.top.has_heave:
            # The same profile with the heave paid out by eq. 38 (the drive's compensation).
            compensated = scene.updated({"top.heave.compensation": True})
            run("open-loop + heave feedback", Drive.from_scene(compensated, profile).winch_angle)
    return out, missing
