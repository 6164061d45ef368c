"""The closed loop: ``mpc(scene, horizon=..., sample=...)`` runs the plant under the controller.

Every ``sample`` seconds the controller measures the plant (its state and the top motion so far),
projects the state onto its reduced model (:mod:`.projection`), forecasts the top
(:mod:`.forecast`) and solves the receding-horizon OCP warm-started from its previous
plan moved on by one sample (:mod:`.controller`); the plant then runs one sample
under the new plan (:mod:`.plant`). A failed solve keeps the previous plan, and is
counted and reported. The controller never sees the heave except through these measurements.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from cable_ocp.control.closed_loop.controller import (
    ControllerSettings,
    RecedingHorizon,
    hermite_basis,
)
from cable_ocp.control.closed_loop.forecast import BlendedHeight, HeightFilter, forecast_top
from cable_ocp.control.closed_loop.plant import LIMITER_BAND, Plant
from cable_ocp.control.closed_loop.projection import project_state
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.ocp import make_control
from cable_ocp.control.optimization import METHODS, optimize
from cable_ocp.drive.bounds import angle_bounds, winch_limits
from cable_ocp.drive.drive import Drive, end_force
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress
from cable_ocp.simulation.seabed import clearance_error, clearance_reference, rms_objective

# Relative slack when checking that one time span is a whole multiple of another.
MULTIPLE_TOLERANCE = 1e-9


def _multiple(value: float, unit: float) -> bool:
    count = round(value / unit)
    return count >= 1 and abs(count * unit - value) <= MULTIPLE_TOLERANCE * max(value, 1.0)


def check_arguments(
    scene, horizon, sample, elements, step, heave_filter, heave_margin, rate_weight, max_iter
) -> None:
    """Raise a ValueError naming the argument and its allowed range, before any heavy work."""
    duration, plant_step = scene.numerics.duration, scene.numerics.step
    if not (sample > 0 and math.isfinite(sample)):
        raise ValueError(f"sample = {sample} s: must be > 0")
    if not (horizon > sample and math.isfinite(horizon)):
        raise ValueError(f"horizon = {horizon} s: must be > sample = {sample} s")
    if horizon > duration:
        raise ValueError(
            f"horizon = {horizon} s: must be <= numerics.duration = {duration} s of the scene"
        )
    if not _multiple(horizon, sample):
        raise ValueError(f"horizon = {horizon} s must be a whole multiple of sample = {sample} s")
    if not _multiple(duration, sample):
        raise ValueError(
            f"sample = {sample} s must divide numerics.duration = {duration} s into whole samples"
        )
    if not _multiple(sample, plant_step):
        raise ValueError(
            f"sample = {sample} s must be a whole multiple of the plant step numerics.step = "
            f"{plant_step} s"
        )
    if not (isinstance(elements, int) and 1 <= elements <= scene.model.elements):
        raise ValueError(
            f"elements = {elements}: the reduced model needs 1 .. model.elements = "
            f"{scene.model.elements} elements"
        )
    if not (step > 0 and _multiple(sample, step)):
        raise ValueError(f"step = {step} s: must be > 0 and divide sample = {sample} s")
    if not (heave_filter > 0 and math.isfinite(heave_filter)):
        raise ValueError(f"heave_filter = {heave_filter} s: must be > 0 (a time constant)")
    if not (isinstance(max_iter, int) and max_iter >= 1):
        raise ValueError(f"max_iter = {max_iter}: must be an integer >= 1")
    if not 0 <= heave_margin <= 1:
        raise ValueError(f"heave_margin = {heave_margin}: must be in [0, 1]")
    if not rate_weight >= 0:
        raise ValueError(f"rate_weight = {rate_weight} s^2: must be >= 0")
    if scene.model.torsion:
        raise ValueError("model.torsion = true: the MPC supports 5-DOF models only")
    if scene.top.heave_compensated:
        raise ValueError(
            "top.heave.compensation = true: the MPC compensates heave from measurements itself; "
            "set it to false"
        )


class _Plan:
    """The plan in force: Hermite parameters from the solve at ``start``."""

    def __init__(self, start: float, parameters: np.ndarray, sample: float, intervals: int):
        self.start, self.parameters = start, parameters
        self.sample, self.intervals = sample, intervals

    def __call__(self, t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        bases = hermite_basis(np.asarray(t) - self.start, self.sample, self.intervals, left)
        return tuple(b @ self.parameters for b in bases)


def _command(plan: _Plan, reference: BlendedHeight | None, top, radius: float):
    """The commanded angle: the plan, plus the heave feedback when ``reference`` is given."""

    def angle(t, left=None):
        phi, rate, acc = plan(t, left)
        if reference is None:
            return phi, rate, acc
        position, velocity, acceleration = top(t)
        height, speed, height_acc = reference(t)
        return (
            phi + (position[2] - height) / radius,
            rate + (velocity[2] - speed) / radius,
            acc + (acceleration[2] - height_acc) / radius,
        )

    return angle


def mpc(
    scene,
    horizon: float = 20.0,
    sample: float = 5.0,
    elements: int = 2,
    step: float = 1.0,
    heave_feedback: bool = True,
    heave_filter: float = 15.0,
    heave_margin: float = 1.0,
    rate_weight: float = 1e-4,
    max_iter: int = 100,
    references: tuple[str, ...] = ("locked",),
    quiet: bool = False,
) -> MpcResult:
    """Closed-loop winch control of a scene by a receding-horizon OCP.

    Parameters
    ----------
    scene : Scene
        The plant (its own model, step and top motion, heave included).
    horizon : float, s
        Prediction horizon; a multiple of ``sample``, at most the scene's duration.
    sample : float, s
        Time between solves; a multiple of the plant's step and of ``step``.
    elements : int
        Elements of the controller's reduced model.
    step : float, s
        RK4 step of the reduced model. Keep several steps per sample: at ``sample = 2 s`` with
        ``step = 1 s`` (two steps per control interval) IPOPT hit ``max_iter`` at most solves on
        paper_hill; four or more steps per sample solved every time.
    heave_feedback : bool
        Add the measured top height's departure from the forecast to the plan (eq. 38 on the
        measured motion, :mod:`.plant`).
    heave_filter : float, s
        Time constant of the low-pass of the measured top height that makes the vertical
        forecast (:class:`cable_ocp.control.closed_loop.forecast.HeightFilter`); waves pass it with
        the gain ``1 / (1 + (2 pi heave_filter / period)^2)``.
    heave_margin : float
        Fraction of the measured heave (its largest departure from the filtered height over the
        last ``2 heave_filter`` seconds, in rad of winch) by which the plan keeps clear of the
        angle bounds, so that the heave feedback has room (0: none, 1: all of it).
    rate_weight : float, s^2
        Weight of the pay-out speed in the objective (regularisation).
    max_iter : int
        IPOPT iterations per solve.
    references : tuple of str
        Reference runs on the same plant: ``"locked"`` (winch locked), ``"open-loop"`` (the
        open-loop optimum of ``cable_ocp.optimize`` on the scene without its heave, applied as it
        is and with the heave feedback).
    quiet : bool
        Print nothing (otherwise a progress bar on stderr).

    Returns
    -------
    MpcResult
        ``success`` is False if any solve failed (see ``failures``).
    """
    check_arguments(
        scene, horizon, sample, elements, step, heave_filter, heave_margin, rate_weight, max_iter
    )
    unknown = set(references) - {"locked", "open-loop"}
    if unknown:
        raise ValueError(f"references = {references}: each must be 'locked' or 'open-loop'")
    started = time.perf_counter()
    low, high = angle_bounds(scene)
    commanded_bounds = [limit[:3] for limit in winch_limits(scene)]
    settings = ControllerSettings(horizon, sample, elements, step, rate_weight, max_iter)
    controller = RecedingHorizon(scene, settings, commanded_bounds)
    plant = Plant(scene, (low, high))
    reduced: CableModel = controller.model
    radius = scene.winch.drum_radius
    duration, h = scene.numerics.duration, plant.step
    per_sample = round(sample / h)
    samples = round(duration / sample)
    intervals = controller.intervals
    build_time = time.perf_counter() - started

    loop_started = time.perf_counter()
    plan = _Plan(0.0, np.zeros(controller.size), sample, intervals)
    zero = np.zeros(1)
    position, velocity, _ = plant.top(zero)
    height_filter = HeightFilter(heave_filter, position[2, 0])
    filtered = [position[2].copy()]
    previous = forecast_top(0.0, position[:, 0], velocity[:, 0], height_filter)
    height = BlendedHeight(previous, previous, 0.0, sample) if heave_feedback else None
    applied = plant.apply(_command(plan, height, plant.top, radius), zero)
    x = plant.initial_state(applied)
    times = [zero]
    states = [x[None, :]]
    inputs = [plant.inputs(applied, zero).T]
    angles = [applied.angle]
    planned = [np.zeros(1)]
    limited = 0
    reference = clearance_reference(scene.seabed.hills, x)
    guess = np.zeros(controller.size)
    sample_times, solve_times, iterations, statuses, failures = [], [], [], [], []
    plant_failure = None
    progress = Progress("mpc", duration, quiet)
    for k in range(samples):
        now = k * sample
        u_now = inputs[-1][-1]
        forecast = forecast_top(now, u_now[INPUTS.top], u_now[INPUTS.top_velocity], height_filter)
        phi, rate, _ = plan(np.array([now]))
        projected = project_state(
            plant.model,
            x,
            u_now[INPUTS.top_length],
            reduced,
            forecast.position,
            forecast.velocity,
            reduced.spec.top_length + radius * phi[0],
            radius * rate[0],
        )
        force = end_force(scene.end, now + controller.force_times)
        parameters = controller.parameters(
            projected.state, forecast, projected.end_offset, reference, force
        )
        margin = LIMITER_BAND
        if heave_feedback:
            # Room for the heave feedback: the largest departure from the filtered height over
            # the last two filter time constants.
            history = np.concatenate(times)
            recent = history >= now - 2 * heave_filter
            heights = np.concatenate(inputs)[recent, 2]
            departure = np.max(np.abs(heights - np.concatenate(filtered)[recent]))
            margin += heave_margin * departure / radius
        solve = controller.solve(parameters, guess, phi[0], rate[0], margin)
        sample_times.append(now)
        solve_times.append(solve.solve_time)
        iterations.append(solve.iterations)
        statuses.append(solve.status)
        if solve.success:
            plan = _Plan(now, solve.parameters, sample, intervals)
            guess = controller.shifted(solve.parameters)
        else:
            failures.append(f"t = {now:g} s: {solve.status}")
            guess = controller.shifted(guess)
        if heave_feedback:
            height = BlendedHeight(previous, forecast, now, sample)
        previous = forecast
        command = _command(plan, height, plant.top, radius)
        try:
            block, block_inputs, applied = plant.advance(x, now, per_sample, command)
        except SimulationError as error:
            plant_failure = f"the plant failed between t = {now:g} and {now + sample:g} s: {error}"
            break
        x = block[-1]
        step_times = now + np.arange(1, per_sample + 1) * h
        times.append(step_times)
        states.append(block[1:])
        inputs.append(block_inputs[1:])
        filtered.append(height_filter.update(h, block_inputs[1:, 2]))
        angles.append(applied.angle[1:])
        planned.append(plan(step_times)[0])
        limited += int(np.count_nonzero(applied.limited[1:]))
        progress.update(now + sample, f"solve {solve.solve_time:.2f} s {solve.status[:20]}")
    progress.close()
    wall_time = time.perf_counter() - loop_started

    time_grid = np.concatenate(times)
    end = np.concatenate(states)[:, 0:3]
    error = clearance_error(scene.seabed.hills, end)
    ref_errors, ref_failures = _references(scene, plant, references, time_grid)
    status = _status(samples, failures, plant_failure, ref_failures)
    return MpcResult(
        time=time_grid,
        winch_angle=np.concatenate(angles),
        planned_angle=np.concatenate(planned),
        end=end,
        top=np.concatenate(inputs)[:, 0:3],
        clearance_error=error,
        omega=rms_objective(time_grid, error),
        sample_times=np.array(sample_times),
        solve_times=np.array(solve_times),
        iterations=np.array(iterations),
        statuses=statuses,
        failures=failures,
        success=not failures and plant_failure is None,
        limited_steps=limited,
        angle_range=(low, high),
        real_time_factor=duration / wall_time,
        worst_solve_time=float(np.max(solve_times)),
        wall_time=wall_time,
        build_time=build_time,
        settings={
            "horizon_s": horizon,
            "sample_s": sample,
            "elements": elements,
            "step_s": step,
            "heave_feedback": heave_feedback,
            "heave_filter_s": heave_filter,
            "rate_weight_s2": rate_weight,
            "heave_margin": heave_margin,
            "max_iter": max_iter,
            "plant_elements": scene.model.elements,
            "plant_step_s": h,
        },
        references=ref_errors,
        reference_omegas={k: rms_objective(time_grid, v) for k, v in ref_errors.items()},
        status=status,
    )


def _status(samples: int, failures: list[str], plant_failure: str | None, references) -> str:
    """One line on how the loop went: every solve, the plant, the reference runs."""
    parts = [plant_failure] if plant_failure else []
    parts.append(
        f"{len(failures)} of {samples} solves failed (the plant kept the previous plan)"
        if failures
        else "every solve succeeded"
    )
    return "; ".join(parts + references)


def _run_open(plant: Plant, angle, time_grid: np.ndarray) -> np.ndarray:
    """Clearance error of the plant under a fixed angle history (no controller).

    Raises SimulationError when the plant fails under it.
    """
    x = plant.initial_state(plant.apply(angle, np.zeros(1)))
    states, _, _ = plant.advance(x, 0.0, time_grid.size - 1, angle)
    return clearance_error(plant.scene.seabed.hills, states[:, 0:3])


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
        calm = scene.updated({"top.heave.amplitude": 0.0})
        default = METHODS["ipopt"].default
        settings = replace(default, intervals=_intervals(scene, default.step))
        result = optimize(calm, "ipopt", settings, quiet=True)
        if not result.success:
            missing.append(f"reference 'open-loop' left out: {result.status}")
            return out, missing
        profile = make_control(calm, settings).angle_function(result.parameters)
        run("open-loop", profile)
        # The same profile with the heave paid out by eq. 38 (the drive's compensation).
        compensated = scene.updated({"top.heave.compensation": True})
        run("open-loop + heave feedback", Drive.from_scene(compensated, profile).winch_angle)
    return out, missing


def _intervals(scene, step: float) -> int:
    """Shooting intervals of about 5 s that divide the open-loop OCP's RK4 steps (42 at 210 s)."""
    steps = round(scene.numerics.duration / step)
    wanted = max(1, round(scene.numerics.duration / 5.0))
    return max(k for k in range(1, wanted + 1) if steps % k == 0)
