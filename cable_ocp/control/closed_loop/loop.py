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

import numpy as np

from cable_ocp.control.closed_loop.command import WinchCommand
from cable_ocp.control.closed_loop.controller import WIDENED, RecedingHorizon
from cable_ocp.control.closed_loop.drum import ON_COMMAND, saturation_note
from cable_ocp.control.closed_loop.estimator import Estimator
from cable_ocp.control.closed_loop.plant import Measurement, Plant, plant_run
from cable_ocp.control.closed_loop.result import MpcResult, SolveLog
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.keywords import refuse_unknown
from cable_ocp.control.optimization import refuse_line_scene
from cable_ocp.control.shooting import compile_ahead
from cable_ocp.control.solvers import SOLVERS
from cable_ocp.control.verification import lowest_clearance
from cable_ocp.drive.bounds import angle_bounds
from cable_ocp.scene.given import scene_given
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.progress import Progress
from cable_ocp.simulation.seabed import (
    OffGridError,
    check_start,
    clearance_error,
    clearance_reference,
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
        Turns the plant's measurements into the controller's view (reduced state, forecast,
        heave room).
    controller : RecedingHorizon
        Solves the receding-horizon problem at each sample.
    command : WinchCommand
        Holds the plan in force and the heave feedback; says where the drum is.
    plant : Plant
        The scene's own model, run one sample at a time under the command.
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
        self.estimator.start_error = float(clearance_error(seabed, self.plant.state[None, :3])[0])
        return measured


def loop_parts(scene, settings: MpcSettings) -> LoopParts:
    """Build the closed loop's parts for a scene (the controller's libraries compiled).

    A loop of one's own steps them as :func:`mpc` does::

        measured = parts.start()
        for k in range(samples):
            now = k * parts.settings.sample
            winch = parts.command.winch(now, parts.plant.lag)  # where the drum is now
            estimate = parts.estimator.make_step(measured, *winch)
            solve = parts.controller.make_step(now, estimate, *winch)
            lag = parts.plant.take_lag() if solve.success else ON_COMMAND
            angle = parts.command.make_step(now, solve, estimate, lag)
            measured = parts.plant.make_step(angle, now + parts.settings.sample)

    Raises TypeError when ``settings`` is not an :class:`MpcSettings`, ValueError for a setting
    that does not fit the scene, before any heavy work.
    """
    if not isinstance(settings, MpcSettings):
        raise TypeError(
            f"mpc: settings must be an MpcSettings (co.MpcSettings(...)) or None; got "
            f"{type(settings).__name__}"
        )
    refuse_line_scene(scene, "mpc")
    settings, derived = settings.resolved(scene)
    compile_ahead(scene, settings.elements, SOLVERS[settings.solver].needs_compiled)
    controller = RecedingHorizon(scene, settings)
    plant = Plant(scene, angle_bounds(scene), settings.limiter_band)
    radius = scene.winch.drum_radius
    position, velocity, _ = plant.top(np.zeros(1))
    estimator = Estimator(settings, plant.model, controller.model, radius, position[2, 0])
    first = estimator.forecast(0.0, position[:, 0], velocity[:, 0])
    command = WinchCommand(settings, controller.control, plant.top, radius, first)
    return LoopParts(settings, derived, estimator, controller, command, plant)


def mpc(
    scene, settings: MpcSettings | None = None, quiet: bool = False, policy=None, **fields
) -> MpcResult:
    """Closed-loop winch control of a scene by a receding-horizon OCP.

    Parameters
    ----------
    scene : Scene, str or path-like
        The plant (its own model, step and top motion, heave included); a scene file's path or a
        bundled scene's name is loaded.
    settings : MpcSettings, optional
        How the controller is built and run (defaults: a 20 s horizon re-solved every 1 s by one
        Gauss-Newton step on a 2-element model; the sample, horizon, plan intervals and the
        controller's step left unset are derived from the scene, :meth:`MpcSettings.resolved`,
        and the result's ``settings["derived"]`` says how).
    quiet : bool
        Print nothing (otherwise a progress bar on stderr).
    policy : optional
        A learned policy that acts instead of the controller where it is trusted
        (:class:`cable_ocp.policy.Policy`): ``policy.controller(parts)`` makes, from the loop's
        :class:`LoopParts`, the object whose ``make_step(now, measured, estimate, angle, rate)``
        returns the sample's :class:`~.controller.Solve` (the policy's action, or the
        controller's solve where its safety net hands the sample over). The result's
        ``solves.by_policy`` says which acted, ``handed_share`` how often the MPC did, and
        ``settings["policy"]`` names the policy.
    **fields
        Fields of :class:`MpcSettings` to set instead of passing ``settings`` (``horizon=10.0``);
        another keyword is refused (TypeError naming the allowed ones).

    Returns
    -------
    MpcResult
        ``success`` is False if any solve failed (see ``failures``), the plant failed or its end
        left the bathymetry grid (the loop then stops there, with the arrays up to that time),
        the end came under ``seabed.minimum_clearance``, or the plant's run fails its physics
        check (a rope that pushes, an end under an absolute seabed:
        :mod:`cable_ocp.simulation.slack`); ``status`` says which, when and where. The runs
        it is judged against (the winch locked, the open-loop optimum) are left to
        :func:`~.references.reference_runs`.

    Raises
    ------
    TypeError
        ``settings`` is not an :class:`MpcSettings` (e.g. an optimiser's settings), before any
        heavy work.
    ValueError
        A setting out of its range, or one that does not fit the scene, before any heavy work.
    OffGridError
        The end starts off the bathymetry grid or under the seabed (before the loop), as for
        ``simulate``.
    """
    own = MpcSettings.__dataclass_fields__
    unknown = {name: value for name, value in fields.items() if name not in own}
    refuse_unknown("mpc", unknown, ("scene", "settings", "quiet", "policy", *own))
    if policy is not None and not callable(getattr(policy, "controller", None)):
        raise TypeError(
            f"mpc: policy must be a learned policy (co.load_policy(...)) or None; got "
            f"{type(policy).__name__}"
        )
    if settings is not None and fields:
        raise ValueError(f"mpc: pass settings or its fields ({', '.join(fields)}), not both")
    started = time.perf_counter()
    scene = scene_given(scene, "mpc")
    parts = loop_parts(scene, MpcSettings(**fields) if settings is None else settings)
    settings, plant, estimator = parts.settings, parts.plant, parts.estimator
    command = parts.command
    duration, h = scene.numerics.duration, plant.step
    samples = round(duration / settings.sample)
    step = _controller_step(parts) if policy is None else policy.controller(parts).make_step
    build_time = time.perf_counter() - started

    loop_started = time.perf_counter()
    measured = parts.start()
    runs, planned, solves, failures = [measured], [np.zeros(1)], [], []
    plant_failure = None
    progress = Progress("mpc", duration, quiet)
    for k in range(samples):
        now = k * settings.sample
        winch = command.winch(now, plant.lag)
        estimate = estimator.make_step(measured, *winch)
        solve = step(now, measured, estimate, *winch)
        solves.append(solve)
        if not solve.success:
            failures.append(f"t = {now:g} s: {solve.status}")
        lag = plant.take_lag() if solve.success else ON_COMMAND
        angle = command.make_step(now, solve, estimate, lag)
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
    trajectory = plant_run(
        plant,
        time_grid,
        np.concatenate([run.states for run in runs]),
        np.concatenate([run.inputs for run in runs]),
        np.concatenate([run.applied.angle for run in runs]),
    )
    _, _, too_low = lowest_clearance(scene.seabed, trajectory)
    # The end under the minimum clearance; the plant's rope pushing, or its end under an
    # absolute seabed (simulation.slack).
    broken = "; ".join(filter(None, [too_low, *trajectory.physics.failures])) or None
    solve_log = SolveLog(
        sample_time=settings.sample * np.arange(len(solves)),
        solve_time=np.array([solve.solve_time for solve in solves]),
        iterations=np.array([solve.iterations for solve in solves]),
        status=[solve.status for solve in solves],
        by_policy=np.array([solve.by_policy for solve in solves], dtype=bool),
    )
    widened = sum(WIDENED in text for text in solve_log.status)
    notes = [f"{widened} solves {WIDENED}"] if widened else []
    saturated = np.concatenate([np.zeros(1, bool)] + [run.applied.saturated for run in runs[1:]])
    saturation = saturation_note(time_grid, saturated, h)
    notes += [saturation] if saturation else []
    if policy is not None:
        acted = int(np.count_nonzero(solve_log.by_policy))
        notes.append(
            f"the policy acted at {acted} of {len(solves)} samples, the MPC at "
            f"{len(solves) - acted} (its safety net)"
        )
    return MpcResult(
        trajectory=trajectory,
        planned_angle=np.concatenate(planned),
        solves=solve_log,
        failures=failures,
        success=not failures and plant_failure is None and broken is None,
        status=_status(samples, failures, plant_failure, broken, notes),
        iterations=int(np.sum(solve_log.iterations)),
        solve_time=float(np.sum(solve_log.solve_time)),
        worst_solve_time=float(np.max(solve_log.solve_time)),
        limited_steps=sum(int(np.count_nonzero(run.applied.limited)) for run in runs[1:]),
        projected_samples=plant.projections,
        saturated_steps=int(np.count_nonzero(saturated)),
        saturation=saturation,
        angle_range=plant.angle_range,
        real_time_factor=float(trajectory.time[-1]) / wall_time,  # the time simulated
        wall_time=wall_time,
        build_time=build_time,
        settings={
            **settings.record(),
            "derived": parts.derived,
            "plant_elements": scene.model.elements,
            "plant_step": h,
            **({"policy": policy.name} if policy is not None else {}),
        },
    )


def _controller_step(parts: LoopParts):
    """The controller's solve as a loop's step ``(now, measured, estimate, angle, rate)``."""

    def step(now, measured, estimate, angle, rate):
        return parts.controller.make_step(now, estimate, angle, rate)

    return step


SHOWN_FAILURES = 3  # failed solves named in the status (all of them are in MpcResult.failures)


def _status(
    samples: int,
    failures: list[str],
    plant_failure: str | None,
    broken: str | None,
    notes: list[str],
) -> str:
    """One line on how the loop went: plant, minimum clearance and physics, solves, ``notes``.

    The notes: solves on the winch's own range, the drum's saturation.
    """
    parts = [reason for reason in (plant_failure, broken) if reason]
    parts.append(
        f"{len(failures)} of {samples} solves failed (the plant kept the previous plan): "
        + "; ".join(failures[:SHOWN_FAILURES])
        + ("; ..." if len(failures) > SHOWN_FAILURES else "")
        if failures
        else "every solve succeeded"
    )
    return "; ".join(parts + notes)
