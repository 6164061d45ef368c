"""The plant: the scene's own model, driven by the true top motion and the winch angle applied.

The winch angle applied is the controller's plan (the commanded angle, for the top motion it
forecast) plus, with heave feedback, the pay-out ``(z_A - z_forecast) / r_D`` of the measured top
height's departure from the forecast (the compensation of eq. 38 on the measured motion, at the
plant's rate, as an active heave-compensated winch does). The applied angle is held inside the
winch's angle range (with the top-element length range) by a soft limiter (:meth:`Plant.apply`),
and the drum follows it within the winch's rate and acceleration limits (:mod:`.drum`): where the
command asks for more, the drum saturates and lags, and the plant reports when.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from cable_ocp.control.closed_loop.drum import GRID_PER_STAGE, ON_COMMAND, Drum, Lag
from cable_ocp.control.closed_loop.projection import (
    chain_state,
    onto_bonds,
    plant_joints,
    strain_of,
)
from cable_ocp.control.interrupts import keeping_interrupts
from cable_ocp.drive.drive import Drive, end_force, stage_times
from cable_ocp.drive.vessel import top_motion
from cable_ocp.drive.winch import with_left
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.integrate import SimulationError, bond_residuals, health, step_states
from cable_ocp.simulation.run import run_trajectory
from cable_ocp.simulation.seabed import check_on_grid
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.simulation.trajectory import Trajectory

# Substeps per plant step tried in turn when a sample's run is in doubt (see Plant.advance). The
# third (h / 16) carries a heave feedback that meets the winch's bound at 5.6 rad/s in Hs 3.8 m
# (bonds 1.8e-4 m open at h / 4; robustness seed 1, case 9, 31 s further before it failed). The
# fourth (h / 64) carries a drum saturated at its rate and acceleration limits: across the kink
# RK4 converges at first order only (deploy's hold in Hs 2.4 m, Tp 7.2 s: bonds open 1.64e-3,
# 4.09e-4 and 1.02e-4 m at h, h / 4 and h / 16 against the 1e-4 m tolerance; five of six such
# seas failed at h / 16 and all five run to the end at h / 64).
SUBSTEPS = (1, 4, 16, 64)
# A sample starts from a state moved back onto its bonds (Plant.onto_bonds) when its bond
# residual, with the drift its bond-velocity residual makes over the sample, is above this
# fraction of numerics.constraint_tolerance. Baumgarte's weak default gains (1/s) let the drift
# of a heaving plant creep up over tens of samples until a sample starts beyond the tolerance,
# where no substep can help (robustness seed 0, cases 8, 10 and 37: 1.69e-4 m at the start
# against 1.6e-4 m); and a sample can end with its bonds closed but opening at 2.1e-3 m/s
# (seed 0, case 12: the next sample failed at h and h / 16 alike). Below the fraction the state
# is left as it is, so a run that never gets there is unchanged.
PROJECT_ABOVE = 0.5
AngleFunction = Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]


class LastCall:
    """A function of a time array (s) that keeps its last answer.

    A sample asks for the top's motion at the same times twice (for the heave feedback's
    command, then for the model's inputs); in a sea state each costs a sum over its wave
    components (a tenth of a thin rope's loop).
    """

    def __init__(self, function: Callable):
        self.function = function
        self._key: tuple | None = None
        self._value = None

    def __call__(self, t):
        """``function(t)``, computed again only when ``t`` differs from the last call's."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        key = (t.shape, t.tobytes())
        if key != self._key:
            self._key, self._value = key, self.function(t)
        return self._value


@dataclass(frozen=True)
class Applied:
    """Winch angle applied over some times, with its rates and where the limiter acted.

    Attributes
    ----------
    angle, rate, acceleration : arrays (k,), rad, rad/s, rad/s^2
    limited : array of bool (k,)
        The soft limiter changed the commanded angle.
    saturated : array of bool (k,)
        The drum was held at its rate or acceleration limit (at a plant step: in the step that
        ends there); all False where it never was.
    lag : Lag
        The drum's lag behind the command after the last time (:mod:`.drum`).
    """

    angle: np.ndarray
    rate: np.ndarray
    acceleration: np.ndarray
    limited: np.ndarray
    saturated: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    lag: Lag = ON_COMMAND

    def tail(self, count: int) -> Applied:
        """The last ``count`` times."""
        saturated = self.saturated[-count:] if self.saturated.size else self.saturated
        return replace(self, angle=self.angle[-count:], rate=self.rate[-count:],
                       acceleration=self.acceleration[-count:], limited=self.limited[-count:],
                       saturated=saturated)  # fmt: skip


@dataclass(frozen=True)
class Measurement:
    """What the plant reports of one sample (or of its start).

    Attributes
    ----------
    now : float, s
        The time the sample ends at (the plant's clock), where the last state holds.
    time : array (k,), s
        The plant's steps in the sample after its start (``now`` alone at the start).
    states : array (k, state_size)
    inputs : array (k, 15)
        The model's inputs there: the true top motion, the line out, the end force.
    applied : Applied
        The winch angle applied there.
    step : float, s
        The plant's RK4 step.
    """

    now: float
    time: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    applied: Applied
    step: float


class Plant:
    """The scene's model integrated by RK4 at the scene's step, compiled to C.

    Parameters
    ----------
    scene : Scene
    angle_range : (float, float), rad
        The range the applied angle is held in.
    band : float, rad
        Width of the soft limiter at each end of the range (``MpcSettings.limiter_band``).
    """

    def __init__(self, scene, angle_range: tuple[float, float], band: float):
        self.scene = scene
        self.model = CableModel.from_scene(scene)
        self.step = scene.numerics.step
        self.top = LastCall(top_motion(scene.top))
        self.radius = scene.winch.drum_radius
        self.top_length = scene.top_element_length
        self.angle_range = angle_range
        self.band = band
        self.projections = 0  # samples started from a state moved onto its bonds
        self.drum, self.lag = Drum.of(scene.winch), ON_COMMAND  # the drum's lag at the plant's time
        # The bond check's Function is built here, with the rest of the loop's set-up (0.4 s at
        # n = 29), not in the first sample.
        self.model.parametric.bonds  # noqa: B018 - a cached property, built once
        self.state, self.now = np.zeros(0), 0.0  # set by start()
        self.started = False

    def start(self, command: AngleFunction) -> Measurement:
        """Put the plant at its start (:meth:`initial_state`) under ``command``; report it.

        The drum starts at the command's angle, its rate and acceleration within the winch's
        limits (:meth:`.drum.Drum.start`).
        """
        _check_command(command)
        zero = np.zeros(1)
        applied, self.lag = self.drum.start(self.apply(command, zero))
        self.state, self.now = self.initial_state(applied), 0.0
        self.started = True
        inputs = self.inputs(applied, zero).T
        return Measurement(0.0, zero, self.state[None, :], inputs, applied, self.step)

    def make_step(self, command: AngleFunction, until: float) -> Measurement:
        """Run from the plant's time to ``until`` (s, whole steps) under ``command``.

        Returns the sample's steps after its start. Raises as :meth:`advance` does, the plant
        left at the sample's start; and, before any work, RuntimeError before :meth:`start`,
        ValueError for an ``until`` that is not whole steps ahead of the plant's time, or is
        past the scene's ``numerics.duration``.
        """
        count = self.steps_to(until)
        _check_command(command)
        start = self.now
        states, inputs, applied = self.advance(self.state, start, count, command, self.lag)
        self.state, self.now, self.lag = states[-1], until, applied.lag
        times = start + np.arange(1, count + 1) * self.step
        return Measurement(until, times, states[1:], inputs[1:], applied.tail(count), self.step)

    def take_lag(self) -> Lag:
        """The drum's angle lag behind the command, handed to a new plan.

        The new plan starts at the drum's angle (:meth:`.command.WinchCommand.make_step`); the
        drum keeps the lag of its rate.
        """
        lag, self.lag = Lag(self.lag.angle, 0.0), Lag(0.0, self.lag.rate)
        return lag

    def steps_to(self, until) -> int:
        """The plant's steps from its time to ``until`` (s); the error naming what is wrong."""
        if not self.started:
            raise RuntimeError("Plant.make_step before Plant.start: start the plant (its "
                               "equilibrium under the command) first")  # fmt: skip
        if isinstance(until, bool) or not isinstance(until, int | float | np.number):
            raise ValueError(f"until = {until!r}: expected a time in s")
        until, h, end = float(until), self.step, self.scene.numerics.duration
        count = round((until - self.now) / h) if np.isfinite(until) else 0
        tolerance = 1e-9 * max(1.0, abs(until))
        if count < 1 or abs(until - self.now - count * h) > tolerance:
            raise ValueError(
                f"until = {until!r} s: must be a whole number (>= 1) of plant steps "
                f"(numerics.step = {h:g} s) after the plant's time {self.now:g} s"
            )
        if until > end + tolerance:
            raise ValueError(
                f"until = {until!r} s: past the scene's end (numerics.duration = {end:g} s); "
                f"the plant runs in [{self.now:g}, {end:g}] s"
            )
        return count

    def apply(self, angle: AngleFunction, t: np.ndarray, left=None) -> Applied:
        """Limit a commanded angle history to the winch range at the times ``t``.

        Within ``band`` of a bound the angle bends smoothly towards it (``b tanh(x /
        b)`` beyond the band's start ``x = 0``), so the applied angle never leaves the range and
        its rate and acceleration stay continuous: a hard clip would jump the pay-out speed, and
        a bend that is only C1 (the earlier ``b (1 - exp(-x / b))``) jumps the acceleration by
        ``rate^2 / b`` at the band's start, inside an RK4 step; at 1.3 rad/s that opened the
        bonds by 1e-3 m (a heaving paper_hill variant), and a quarter of the step only by 10x
        less.
        """
        phi, rate, acceleration = (np.array(v, dtype=float) for v in with_left(angle)(t, left))
        limited = np.zeros(phi.shape, dtype=bool)
        band = self.band
        low, high = self.angle_range
        for sign, edge in ((1.0, high - band), (-1.0, low + band)):
            over = sign * (phi - edge)
            active = over > 0
            if not active.any():
                continue
            limited |= active
            bend = np.tanh(over[active] / band)
            slope = 1 - bend**2
            curvature = -2 * bend * slope / band
            phi[active] = edge + sign * band * bend
            acceleration[active] = (
                curvature * sign * rate[active] ** 2 + slope * acceleration[active]
            )
            rate[active] = slope * rate[active]
        return Applied(phi, rate, acceleration, limited)

    def inputs(self, applied: Applied, t: np.ndarray) -> np.ndarray:
        """Model inputs (15, len(t)) under the true top motion and the applied angle."""
        position, velocity, acceleration = self.top(t)
        inputs = np.empty((INPUTS.end_force.stop, position.shape[1]))  # rows as INPUTS lays out
        inputs[INPUTS.top], inputs[INPUTS.top_velocity] = position, velocity
        inputs[INPUTS.top_acceleration] = acceleration
        inputs[INPUTS.top_length] = self.top_length + self.radius * applied.angle
        inputs[INPUTS.top_length_rate] = self.radius * applied.rate
        inputs[INPUTS.top_length_acceleration] = self.radius * applied.acceleration
        inputs[INPUTS.end_force] = end_force(self.scene.end, t)
        return inputs

    def initial_state(self, applied: Applied) -> np.ndarray:
        """Static equilibrium at t = 0, set moving with the top and the winch (bonds held).

        The joints below the top are at rest; the top element turns with the top's velocity
        across it, so that the initial velocities satisfy the bonds even when the top (heave) or
        the winch is moving at t = 0.
        """
        model = self.model
        x = equilibrium(model, Drive.from_scene(self.scene), compiled=True).state
        u = self.inputs(applied, np.zeros(1))[:, 0]
        joints, _ = plant_joints(model, x)
        top, velocity = u[INPUTS.top], u[INPUTS.top_velocity]
        upper = np.vstack([joints[1:], top])
        directions = upper - joints
        rates = np.zeros_like(directions)
        rates[-1] = velocity / np.linalg.norm(directions[-1])
        length, length_rate = u[INPUTS.top_length], u[INPUTS.top_length_rate]
        strain = strain_of(model, x)  # an elastic rope starts at its static stretch
        return chain_state(model, top, velocity, length, length_rate, directions, rates, strain)

    def advance(
        self, x: np.ndarray, start: float, count: int, angle: AngleFunction, lag: Lag = ON_COMMAND
    ):
        """Integrate ``count`` steps from ``x`` at ``start`` (s) under a commanded angle.

        The drum starts ``lag`` behind the command (:mod:`.drum`; on it by default).

        Returns
        -------
        states : array (count + 1, state_size)
            At ``start + k h``, ``k = 0..count``.
        inputs : array (count + 1, 15)
        applied : Applied
            At the same times, with the drum's lag at the end.

        Raises
        ------
        SimulationError
            If the state becomes non-finite or leaves its bonds (numerics.constraint_tolerance)
            at the scene's step and at each of :data:`SUBSTEPS`.
        OffGridError
            If the end leaves the bathymetry grid (a SimulationError naming the time and point).

        A sample in doubt at the scene's step is integrated again from the same state with
        substeps: the soft limiter bends the angle on a time scale of ``band / rate``
        (0.15 s when the heave feedback drives the winch into a bound at 1.3 rad/s, measured
        on a paper_hill variant), which RK4 at h = 0.05 s resolves badly enough to open the
        bonds by 1e-3 m; at h / 4 it stays at the health of the other samples.
        """
        x = self.onto_bonds(x, start, angle, count * self.step, lag)
        failures = []
        for substeps in SUBSTEPS:
            states, inputs, applied = self._integrate(x, start, count, angle, substeps, lag)
            failure = self._health(states[-1], inputs[-1], start + count * self.step, substeps)
            if failure is None:
                times = start + np.arange(count + 1) * self.step
                check_on_grid(self.scene.seabed, states[:, 0:3], times)
                return states, inputs, applied
            failures.append(failure)
        raise SimulationError(
            "the plant failed at its step and with substeps: " + "; ".join(failures) + ". "
            "Remedy: a smaller numerics.step, or a larger mpc heave_margin (the heave feedback "
            "then keeps clear of the winch's bounds)"
        )

    def onto_bonds(
        self, x: np.ndarray, start: float, angle: AngleFunction, span: float, lag: Lag = ON_COMMAND
    ) -> np.ndarray:
        """``x`` at ``start`` (s), moved onto its bonds if they have opened or are opening.

        The bonds are those of the drum ``lag`` behind the commanded ``angle`` (:mod:`.drum`).

        When the bond residual plus its rate times ``span`` (s, the sample ahead) is above
        :data:`PROJECT_ABOVE` of the tolerance, the joints are chained down again from
        the top with each element's direction and turning rate kept
        (:func:`.projection.onto_bonds`): a coordinate projection, which moves the end by at
        most the residual. Counted in :attr:`projections`. A model with torsion is left as it
        is (the chain is 5-DOF).
        """
        if self.model.spec.element.torsion:
            return x
        at = np.array([float(start)])
        applied = self.apply(angle, at)
        drum = replace(applied, angle=applied.angle + lag.angle, rate=applied.rate + lag.rate)
        u = self.inputs(drum, at)[:, 0]
        residual, rate = self.model.bond_values(x, u)
        residual = float(np.max(np.abs(residual))) + span * float(np.max(np.abs(rate)))
        if residual <= PROJECT_ABOVE * self.scene.numerics.constraint_tolerance:
            return x
        self.projections += 1
        return onto_bonds(
            self.model, x, u[INPUTS.top], u[INPUTS.top_velocity],
            float(u[INPUTS.top_length]), float(u[INPUTS.top_length_rate]),
        )  # fmt: skip

    def _integrate(self, x: np.ndarray, start: float, count: int, angle, substeps: int, lag: Lag):
        """``count`` plant steps of ``substeps`` RK4 steps each: states, inputs, applied."""
        h = self.step / substeps
        steps = count * substeps
        fine = start + np.arange(steps + 1) * h
        # The end stage of a step takes the input's left limit (drive.stage_times): the plan's
        # acceleration jumps at its nodes, which fall on step ends.
        times, left = stage_times(fine[:-1], h)
        # The stage times and the output times in one evaluation of the command.
        outputs = start + np.arange(count + 1) * self.step
        every = np.concatenate([times, outputs])
        applied = self.apply(angle, every, np.concatenate([left, np.zeros(count + 1, bool)]))
        applied = self.drum_under(applied, angle, start, h, steps, substeps, lag)
        inputs = self.inputs(applied, every)
        stages = inputs[:, : times.size]
        run_states = np.empty((count, x.size))
        # A Ctrl-C inside the CasADi call can leave Python's error set under a result that
        # numpy then rejects (SystemError): it is the user's interrupt. The states are written
        # into numpy directly: through CasADi's DM they cost 5.2 ms against 3.8 ms a sample at
        # n = 20 (50 steps).
        with keeping_interrupts():
            step_states(self.model, x, stages.T, h, substeps, True, run_states)
        states = np.vstack([x, run_states])
        return states, inputs[:, times.size :].T, applied.tail(count + 1)

    def drum_under(
        self, applied: Applied, angle, start: float, h: float, steps: int, substeps: int, lag: Lag
    ) -> Applied:
        """The drum under a sample's command ``applied`` at its stage and output times.

        The command as it is where the drum is on it and the command keeps within the limits
        at these times (a run that never saturates is unchanged); otherwise the drum of
        :meth:`.drum.Drum.follow` on the grid of the stages, from ``lag``. The stage times are
        ``steps`` RK4 steps of ``h`` (s) from ``start``, then the plant's steps (``substeps``
        RK4 steps each).
        """
        within = self.drum.within(applied.rate, applied.acceleration)
        if not self.drum.limited or (lag.on_track and within):
            never = np.zeros(applied.angle.size, dtype=bool)
            return replace(applied, saturated=never, lag=ON_COMMAND)
        per_step = 2 * GRID_PER_STAGE
        spacing = h / per_step
        grid = start + np.arange(steps * per_step + 1) * spacing
        command = self.apply(angle, grid)
        drum_angle, rate, acceleration, left_limit, saturated, end = self.drum.follow(
            ON_COMMAND if lag.on_track else lag, spacing, command.angle, command.rate,
            command.acceleration,
        )  # fmt: skip
        # Stage k of step i sits at grid index i * per_step + (0, per_step / 2, per_step)[k].
        index = (np.arange(steps)[:, None] * per_step
                 + np.array([0, per_step // 2, per_step])[None, :]).ravel()  # fmt: skip
        outputs = np.arange(0, grid.size, per_step * substeps)
        at = np.concatenate([index, outputs])
        # The end stages take the left limit, and so does the sample's end, whose interval
        # beyond is the next sample's (from its own command).
        is_end = np.concatenate([np.tile([False, False, True], steps),
                                 np.arange(outputs.size) == outputs.size - 1])  # fmt: skip
        # A plant step saturated if the drum was in any interval of it.
        in_step = np.concatenate([[False], saturated[:-1].reshape(-1, per_step * substeps).any(1)])
        return replace(
            applied,
            angle=drum_angle[at],
            rate=rate[at],
            acceleration=np.where(is_end, left_limit[at], acceleration[at]),
            saturated=np.concatenate([saturated[index], in_step]),
            lag=end,
        )

    def _health(self, x: np.ndarray, u: np.ndarray, t: float, substeps: int) -> str | None:
        """Why the plant's state at ``t`` cannot be trusted (None when it can).

        The health check of every run (:func:`~cable_ocp.simulation.integrate.health`) on the
        sample's last state.
        """
        x, u = x[None, :], u[None, :]
        norms = bond_residuals(self.model, x, u, compiled=True)
        tolerance = self.scene.numerics.constraint_tolerance
        fault = health(self.model, x, norms, np.array([t]), self.step / substeps, tolerance)
        return None if fault is None else fault.what


def _check_command(command) -> None:
    """ValueError unless ``command`` is an angle function (:meth:`WinchCommand.make_step`'s)."""
    if not callable(command):
        raise ValueError(
            f"command = {command!r:.60}: expected the winch angle function t -> (angle, rate, "
            "acceleration) that WinchCommand.make_step returns"
        )


def plant_run(
    plant: Plant, time: np.ndarray, states: np.ndarray, inputs: np.ndarray, angle: np.ndarray
) -> Trajectory:
    """The plant's run as a :class:`~cable_ocp.simulation.trajectory.Trajectory`.

    Its states and inputs at ``time`` (s) under the applied ``angle`` (rad), its outputs
    compiled (:func:`~cable_ocp.simulation.run.run_trajectory`).
    """
    return run_trajectory(plant.scene, plant.model, time, states, inputs, angle, compiled=True)
