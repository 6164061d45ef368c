"""The receding-horizon OCP: multiple shooting on a reduced model, built once, solved every sample.

Over a horizon of ``M`` shooting intervals (each one sample long, ``K`` RK4 steps of the reduced
model) the winch angle is a C1 piecewise cubic (Hermite) with the angle and its rate at the
``M + 1`` interval nodes as decision variables; the first node is held at the angle and rate the
winch has now. The NLP's parameters are everything that changes from one sample to the next: the
reduced state estimate, the forecast top position and velocity, the end offset (measured end minus
the reduced end, :mod:`.projection`), the clearance reference ``z_E(0) - z(E(0))`` and the end
force over the horizon. The seabed is known and built in.

Objective: ``1/H int e^2 dt + w 1/H int (r_D phi')^2 dt`` (trapezoidal on the RK4 grid),
``e = z_E + b_z - z_ref - z_sb(x_E + b_x, y_E + b_y)`` (eq. 39 with the offset ``b``); the winch
angle (with the top-element length) and, if the scene sets them, its rate and acceleration are
bounded at every RK4 point.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.control.ocp import interrupted_solve, ipopt_options
from cable_ocp.drive.controls import hermite_polynomials
from cable_ocp.drive.drive import stage_times as rk4_stage_times
from cable_ocp.model.cable import INPUT_SIZE, CableModel
from cable_ocp.simulation.integrate import step_function
from cable_ocp.simulation.seabed import seabed_height, trapezoid_weights

# Solve statuses that count as a solution.
SOLVED = ("Solve_Succeeded", "Solved_To_Acceptable_Level")


def hermite_basis(s: np.ndarray, width: float, intervals: int, left=None) -> tuple[np.ndarray, ...]:
    """``B0, B1, B2`` (len(s), 2 (intervals + 1)) of the Hermite angle on ``[0, intervals width]``.

    Parameters ``[phi_0 .. phi_M, phi'_0 .. phi'_M]`` at the nodes ``k width`` (rad, rad/s);
    ``phi(s) = B0 p``, ``phi'(s) = B1 p``, ``phi''(s) = B2 p``. Times beyond the last node hold
    the last cubic's end value (rate and acceleration 0). Where ``left`` (bool, or like ``s``) is
    true, a time on a node belongs to the interval that ends there (the end stage of an RK4 step).
    """
    s = np.atleast_1d(np.asarray(s, dtype=float))
    end = intervals * width
    beyond = s > end + 1e-9 * max(end, 1.0)
    s = np.clip(s, 0.0, end)
    k = (s / width + 1e-9).astype(int)
    if left is not None:
        k = np.where(left, np.ceil(s / width - 1e-9).astype(int) - 1, k)
    k = np.clip(k, 0, intervals - 1)
    u = s / width - k
    h00, h10, h01, h11 = hermite_polynomials(u)
    scale = np.array([1.0, 1.0 / width, 1.0 / width**2])[:, None]
    out = np.zeros((3, s.size, 2 * (intervals + 1)))
    rows = np.arange(s.size)
    for node, (value_basis, rate_basis) in ((k, (h00, h10)), (k + 1, (h01, h11))):
        for d in range(3):
            out[d, rows, node] += scale[d, 0] * value_basis[d]
            out[d, rows, intervals + 1 + node] += scale[d, 0] * width * rate_basis[d]
    out[1:, beyond] = 0.0
    return out[0], out[1], out[2]


@dataclass(frozen=True)
class ControllerSettings:
    """How the receding-horizon OCP is built.

    Attributes
    ----------
    horizon : float, s
    sample : float, s
        Also the length of a shooting interval and of a control interval.
    elements : int
        Elements of the reduced model.
    step : float, s
        Its RK4 step.
    rate_weight : float, s^2
        Weight of the pay-out speed ``(r_D phi')^2`` against ``e^2`` in the objective.
    max_iter : int
        IPOPT iterations per sample.
    tolerance : float
        IPOPT's ``tol``.
    """

    horizon: float
    sample: float
    elements: int
    step: float
    rate_weight: float = 1e-4
    max_iter: int = 100
    tolerance: float = 1e-6


@dataclass(frozen=True)
class Solve:
    """One solve of the receding-horizon OCP.

    Attributes
    ----------
    parameters : array (2 (M + 1),)
        Hermite angle parameters (rad, rad/s), time measured from the solve's start.
    nodes : array (state_size, M)
        Reduced states at the interval ends.
    status : str
    success : bool
    iterations : int
    solve_time : float, s
    """

    parameters: np.ndarray
    nodes: np.ndarray
    status: str
    success: bool
    iterations: int
    solve_time: float


class RecedingHorizon:
    """The receding-horizon NLP of a scene (see the module docstring).

    Parameters
    ----------
    scene : Scene
    settings : ControllerSettings
    bounds : list of (derivative, low, high)
        Winch bounds of the commanded angle (0: rad, 1: rad/s, 2: rad/s^2).
    """

    def __init__(self, scene, settings: ControllerSettings, bounds):
        started = time.perf_counter()
        self.settings = settings
        self.intervals = intervals = round(settings.horizon / settings.sample)
        self.per_interval = per_interval = round(settings.sample / settings.step)
        steps = intervals * per_interval
        h = settings.step
        self.model = model = CableModel.from_scene(scene, settings.elements)
        nx = model.state_size
        radius = scene.winch.drum_radius
        self.size = 2 * (intervals + 1)

        step_times = np.arange(steps) * h
        stage_times = rk4_stage_times(step_times, h)[0]
        grid = np.arange(steps + 1) * h
        b_stage = hermite_basis(stage_times, settings.sample, intervals)
        b_grid = hermite_basis(grid, settings.sample, intervals)

        winch = ca.MX.sym("winch", self.size)
        # Parameters: x0, top position, top velocity, end offset, z_ref, end force (3 x 3 steps).
        parameters = ca.MX.sym("parameters", nx + 10 + 9 * steps)
        x0, top, top_velocity = (
            parameters[:nx],
            parameters[nx : nx + 3],
            parameters[nx + 3 : nx + 6],
        )
        offset, reference = parameters[nx + 6 : nx + 9], parameters[nx + 9]
        force = ca.reshape(parameters[nx + 10 :], 3, 3 * steps)
        self.force_times = stage_times

        ones = ca.DM.ones(1, stage_times.size)
        positions = ca.repmat(top, 1, stage_times.size) + top_velocity @ ca.DM(stage_times).T
        length_rows = (
            ca.vertcat(*[(radius * ca.sparsify(ca.DM(b)) @ winch).T for b in b_stage])
            + ca.vertcat(model.spec.top_length, 0, 0) @ ones
        )
        stages = ca.vertcat(
            positions,
            ca.repmat(top_velocity, 1, stage_times.size),
            ca.DM.zeros(3, stage_times.size),
            length_rows,
            force,
        )
        # The winch enters each interval through its four node values only, so that the
        # Jacobian of an interval has 4 winch columns, not one per stage input (60x fewer).
        fixed = ca.vertcat(stages[:9, :], ca.DM.zeros(3, stage_times.size), force)
        local = ca.vertcat(
            winch[:intervals].T,
            winch[1 : intervals + 1].T,
            winch[intervals + 1 : 2 * intervals + 1].T,
            winch[intervals + 2 :].T,
        )
        interval = self._interval_function(scene.seabed.hills, per_interval, radius)
        nodes = ca.MX.sym("nodes", nx, intervals)
        starts = ca.horzcat(x0, nodes[:, :-1])
        ends, costs = interval.map(intervals)(starts, local, fixed, offset, reference)
        rates = ca.sparsify(ca.DM(b_grid[1])) @ winch
        effort = ca.dot(ca.DM(trapezoid_weights(h, steps + 1)), (radius * rates) ** 2)
        objective = (ca.sum2(costs) + settings.rate_weight * effort) / settings.horizon

        rows, lower, upper = [], [], []
        for derivative, low, high in bounds:
            rows.append(ca.sparsify(ca.DM(b_grid[derivative])) @ winch)
            lower.append(np.full(grid.size, low))
            upper.append(np.full(grid.size, high))
        continuity = ca.vec(ends - nodes)
        self.lbg = np.concatenate([np.zeros(continuity.numel()), *lower])
        self._angle_rows = slice(continuity.numel(), continuity.numel() + grid.size)
        self._margin_ramp = np.clip(grid / settings.sample, 0.0, 1.0)
        self.ubg = np.concatenate([np.zeros(continuity.numel()), *upper])
        variables = ca.vertcat(ca.vec(nodes), winch)
        options = {
            "ipopt": ipopt_options(
                "limited-memory",
                settings.max_iter,
                settings.tolerance,
                extra={"warm_start_init_point": "yes", "mu_init": 1e-3},
            ),
            "print_time": False,
            # IPOPT's trial points may blow the reduced model up (NaN); its line search backs
            # off, so CasADi's warning about them is noise (a real failure is in the status).
            "show_eval_warnings": False,
        }
        self.solver = ca.nlpsol(
            "receding_horizon",
            "ipopt",
            {"x": variables, "f": objective, "g": ca.vertcat(continuity, *rows), "p": parameters},
            options,
        )
        states = step_function(model, h, compiled=True, derivatives=True).mapaccum(steps)(
            x0, stages
        )
        self._rollout = ca.Function(
            "rollout", [parameters, winch], [states[:, per_interval - 1 :: per_interval]]
        )
        self.build_time = time.perf_counter() - started

    def _interval_function(self, hills, steps: int, radius: float) -> ca.Function:
        """``(x, winch, inputs, offset, z_ref) -> (x_end, int e^2 dt)`` over one interval.

        ``winch`` holds the interval's ``[phi_a, phi_b, phi'_a, phi'_b]``; ``inputs`` (15 x 3 steps)
        the stage inputs with zero top-element rows, which the winch fills in.
        """
        model, h = self.model, self.settings.step
        x = ca.MX.sym("x", model.state_size)
        winch = ca.MX.sym("winch", 4)
        fixed = ca.MX.sym("inputs", INPUT_SIZE, 3 * steps)
        local_times = rk4_stage_times(np.arange(steps) * h, h)[0]
        bases = hermite_basis(local_times, self.settings.sample, 1)
        lengths = ca.vertcat(*[(radius * ca.DM(b) @ winch).T for b in bases]) + ca.DM(
            [model.spec.top_length, 0.0, 0.0]
        ) @ ca.DM.ones(1, local_times.size)
        stages = fixed + ca.vertcat(
            ca.DM.zeros(9, local_times.size), lengths, ca.DM.zeros(3, local_times.size)
        )
        offset = ca.MX.sym("offset", 3)
        reference = ca.MX.sym("z_ref")
        states = step_function(model, h, compiled=True, derivatives=True).mapaccum(steps)(x, stages)
        points = ca.horzcat(x, states)
        xe = ca.SX.sym("xe", model.state_size)
        b = ca.SX.sym("b", 3)
        zr = ca.SX.sym("zr")
        error = xe[2] + b[2] - zr - seabed_height(hills, xe[0] + b[0], xe[1] + b[1])
        errors = ca.Function("e", [xe, b, zr], [error]).map(steps + 1)(points, offset, reference)
        cost = ca.mtimes(errors**2, ca.DM(trapezoid_weights(h, steps + 1)))
        return ca.Function("interval", [x, winch, fixed, offset, reference], [states[:, -1], cost])

    def parameters(self, x0, forecast, offset, reference, force) -> np.ndarray:
        """The NLP's parameter vector (see the module docstring)."""
        return np.concatenate(
            [x0, forecast.position, forecast.velocity, offset, [reference], force.ravel(order="F")]
        )

    def solve(
        self,
        parameters: np.ndarray,
        guess: np.ndarray,
        angle: float,
        rate: float,
        margin: float = 0.0,
    ) -> Solve:
        """Solve from the winch guess ``guess`` with the first node held at ``(angle, rate)``.

        The nodes' initial guess is the reduced model's forward run under ``guess``. ``margin``
        (rad) narrows the angle range on both sides, phased in over the first sample (the
        plan starts where the winch is): room kept for the heave feedback.
        """
        nx, m = self.model.state_size, self.intervals
        guess = np.array(guess, dtype=float)
        guess[0], guess[m + 1] = angle, rate
        nodes = np.array(self._rollout(parameters, guess))
        if not np.all(np.isfinite(nodes)):
            nodes = np.tile(parameters[:nx, None], (1, m))
        lbx = np.full(nx * m + self.size, -np.inf)
        ubx = np.full(nx * m + self.size, np.inf)
        for index, value in ((0, angle), (m + 1, rate)):
            lbx[nx * m + index] = ubx[nx * m + index] = value
        lbg, ubg = self.lbg.copy(), self.ubg.copy()
        lbg[self._angle_rows] += margin * self._margin_ramp
        ubg[self._angle_rows] -= margin * self._margin_ramp
        started = time.perf_counter()
        solution = interrupted_solve(
            self.solver,
            x0=np.concatenate([nodes.ravel(order="F"), guess]),
            p=parameters,
            lbx=lbx,
            ubx=ubx,
            lbg=lbg,
            ubg=ubg,
        )
        solve_time = time.perf_counter() - started
        stats = self.solver.stats()
        x = np.array(solution["x"]).ravel()
        status = stats["return_status"]
        return Solve(
            parameters=x[nx * m :],
            nodes=x[: nx * m].reshape(nx, m, order="F"),
            status=status,
            success=status in SOLVED,
            iterations=int(stats["iter_count"]),
            solve_time=solve_time,
        )

    def shifted(self, parameters: np.ndarray) -> np.ndarray:
        """A plan moved on by one sample: the nodes shift left, the last is held at rest."""
        m = self.intervals
        values, rates = parameters[: m + 1], parameters[m + 1 :]
        return np.concatenate([values[1:], values[-1:], rates[1:], [0.0]])
