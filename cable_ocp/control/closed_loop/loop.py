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
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from cable_ocp.control.closed_loop.command import WinchCommand
from cable_ocp.control.closed_loop.controller import WIDENED, RecedingHorizon
from cable_ocp.control.closed_loop.estimator import Estimator
from cable_ocp.control.closed_loop.plant import Measurement, Plant
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.interrupts import interrupt_here
from cable_ocp.control.ocp import compile_ahead, make_control, resolved
from cable_ocp.control.optimization import optimize, refuse_line_scene
from cable_ocp.control.solvers import ocp_settings
from cable_ocp.control.verification import lowest_clearance
from cable_ocp.drive.bounds import angle_bounds
from cable_ocp.drive.drive import Drive
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress
from cable_ocp.simulation.seabed import (
    OffGridError,
    check_start,
    clearance_error,
    clearance_reference,
    rms_objective,
)


@dataclass(frozen=True)
class LoopParts:
    """The parts of a scene's closed loop, each stepped once a sample (module docstring).

    Attributes
    ----------
    settings : MpcSettings
        Resolved for the scene (nothing left unset).
    derived : str
        How the settings left unset were derived.
    estimator : Estimator
    controller : RecedingHorizon
    command : WinchCommand
    plant : Plant
    """

    settings: MpcSettings
    derived: str
    estimator: Estimator
    controller: RecedingHorizon
    command: WinchCommand
    plant: Plant

    def start(self) -> Measurement:
        """Start the plant at its equilibrium under the command; what it measured there.

        Raises :class:`~cable_ocp.simulation.seabed.OffGridError` when the end starts off the
        bathymetry grid or under the seabed; sets the estimator's clearance reference.
        """
        measured = self.plant.start(self.command.angle)
        seabed = self.plant.scene.seabed
        check_start(seabed, self.plant.state[:3])
        self.estimator.reference = clearance_reference(seabed, self.plant.state)
        return measured


def loop_parts(scene, settings: MpcSettings) -> LoopParts:
    """Build the closed loop's parts for a scene (the controller's libraries compiled).

    A loop of one's own steps them as :func:`mpc` does::

        measured = parts.start()
        for k in range(samples):
            now = k * parts.settings.sample
            winch = parts.command.winch(now)  # the plan's angle and rate now
            estimate = parts.estimator.make_step(measured, *winch)
            solve = parts.controller.make_step(now, estimate, *winch)
            angle = parts.command.make_step(now, solve, estimate)
            measured = parts.plant.make_step(angle, now + parts.settings.sample)

    Raises ValueError for a setting that does not fit the scene, before any heavy work.
    """
    refuse_line_scene(scene, "mpc")
    settings, derived = settings.resolved(scene)
    compile_ahead(scene, settings.elements, settings.solver == "gauss-newton")
    controller = RecedingHorizon(scene, settings)
    plant = Plant(scene, angle_bounds(scene), settings.limiter_band)
    radius = scene.winch.drum_radius
    position, velocity, _ = plant.top(np.zeros(1))
    estimator = Estimator(settings, plant.model, controller.model, radius, position[2, 0])
    first = estimator.forecast(0.0, position[:, 0], velocity[:, 0])
    command = WinchCommand(settings, controller.control, plant.top, radius, first)
    return LoopParts(settings, derived, estimator, controller, command, plant)


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
    started = time.perf_counter()
    parts = loop_parts(scene, settings or MpcSettings(**fields))
    settings, plant, estimator = parts.settings, parts.plant, parts.estimator
    controller, command = parts.controller, parts.command
    duration, h = scene.numerics.duration, plant.step
    samples = round(duration / settings.sample)
    build_time = time.perf_counter() - started

    loop_started = time.perf_counter()
    measured = parts.start()
    runs, planned, solves, failures = [measured], [np.zeros(1)], [], []
    plant_failure = None
    progress = Progress("mpc", duration, quiet)
    for k in range(samples):
        now = k * settings.sample
        winch = command.winch(now)
        estimate = estimator.make_step(measured, *winch)
        solve = controller.make_step(now, estimate, *winch)
        solves.append(solve)
        if not solve.success:
            failures.append(f"t = {now:g} s: {solve.status}")
        angle = command.make_step(now, solve, estimate)
        try:
            measured = plant.make_step(angle, (k + 1) * settings.sample)
        except SimulationError as error:
            where = ", ".join(f"{value:.6g}" for value in plant.state[:3])
            verb = "stopped" if isinstance(error, OffGridError) else "failed"
            plant_failure = (
                f"the plant {verb} between t = {now:g} and {now + settings.sample:g} s (the end "
                f"at (x, y, z) = ({where}) m at t = {now:g} s): {error}"
            )
            break
        runs.append(measured)
        planned.append(command.plan(measured.time)[0])
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
        angle_range=plant.angle_range,
        real_time_factor=duration / wall_time,
        worst_solve_time=float(np.max(solve_times)),
        wall_time=wall_time,
        build_time=build_time,
        settings={
            **settings.record(),
            "derived": parts.derived,
            "plant_elements": scene.model.elements,
            "plant_step": h,
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
            settings, _ = resolved(calm, ocp_settings())
            result = optimize(calm, model=settings.model, grid=settings.grid, quiet=True)
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
