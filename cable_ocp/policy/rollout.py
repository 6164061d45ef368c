"""The safety net's rollout check: the policy's action against the MPC's, over one horizon.

At a sample, the controller's reduced model runs one horizon from the estimate, with the
controller's own RK4 map, forecast and clearance error
(:meth:`~cable_ocp.control.closed_loop.controller.RecedingHorizon.rollout`), under the plan the
MPC's solve would start from: its plan in force moved on to now, started at the drum's angle and
rate. About that run the clearance error is linear in the plan (its Jacobian, from a sensitivity
sweep at most :data:`AGE` samples old), so that the MPC's objective (its Omega^2 over the
horizon with its rate term, as :class:`~cable_ocp.control.gauss_newton.GaussNewton` states it) is
a least squares in the plan's free parameters (all but node 0):

- its minimum ``J*`` is what the MPC predicts it can reach from here (a Gauss-Newton step);
- held to the policy's angle at the next sample, ``phi(T_s) = phi(0) + a T_s``, its minimum is
  ``J(a) = J* + m^2 / (c' H^-1 c)``, with ``m`` the policy's miss of the optimum's angle at the
  next sample, ``c`` the angle's row at ``T_s`` and ``H`` the least squares' normal matrix: the
  cost of the policy's action to a controller that does its best after it.

The action is trusted when ``sqrt(J(a))`` is at most :data:`FACTOR` times ``sqrt(J*)`` plus
:data:`SLACK`, and the predicted error under that plan keeps the minimum clearance (the solver's
clearance rows, with their back-off). A policy that keeps the plant alive but lets the load
wander (hill_tow's held-out loops that succeeded with Omega 3.5-9 cm where the MPC held 0.3-3
cm) misses the optimum's angle; neither the envelope nor the bounds see that. A plan in force
rolled out as it is would not do as the yardstick: from the heave-driven state of the next
sample its Omega over the horizon is several times the one its solve predicted.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.linalg import cho_factor, cho_solve

from cable_ocp.control.gauss_newton import BREACH_TOLERANCE, DAMPING
from cable_ocp.control.linearisation import Linearised

# Samples a Jacobian serves before a sensitivity sweep refreshes it.
AGE = 5
# The policy's predicted Omega over the horizon may exceed the MPC's by this factor plus this
# slack (m).
FACTOR, SLACK = 1.25, 0.005


class RolloutCheck:
    """The rollout check of a closed loop's samples (module docstring).

    Parameters
    ----------
    controller : RecedingHorizon
        The loop's controller: its reduced model, forecast, plan in force and solver.
    sample : float, s
        The loop's sample.
    """

    def __init__(self, controller, sample: float):
        self.controller, self.sample = controller, sample
        control = controller.control
        self.start = list(control.node_indices(0))
        self.free = np.setdiff1d(np.arange(control.size), self.start)
        self.at_sample = control.basis(np.array([sample]))[0][0]  # phi(T_s) of the parameters
        self.nodes = control.breakpoints
        self.made = -np.inf  # s: when the Jacobian in use was swept
        self.jacobian = self.rows = self.factor = None
        self.sweeps = 0  # Jacobian sweeps made
        self.seconds: list[float] = []  # wall time of each check (s)

    @property
    def available(self) -> bool:
        """Whether the controller's solver has an RK4 map to roll out on (Gauss-Newton's)."""
        return getattr(self.controller.solver, "linearisation", None) is not None

    def reason(self, now: float, estimate, angle: float, rate: float, action: float) -> str:
        """Why the policy's ``action`` (rad/s) fails the check at ``now`` (empty: it passes)."""
        started = time.perf_counter()
        try:
            return self._reason(now, estimate, angle, rate, action)
        finally:
            self.seconds.append(time.perf_counter() - started)

    def _reason(self, now: float, estimate, angle: float, rate: float, action: float) -> str:
        """:meth:`reason`, untimed."""
        controller, solver = self.controller, self.controller.solver
        # The plan in force moved on to now (the solve's guess: the control's resampled, by its
        # faster evaluation), started at the drum's angle and rate.
        moved = now - controller.plan_start + self.nodes
        plan = np.concatenate(controller.control.evaluate(controller.plan, moved)[:2])
        plan[self.start] = angle, rate
        stale = now - self.made > (AGE - 0.5) * self.sample
        run = controller.rollout(now, estimate, plan, jacobian=stale)
        if not run.finite:
            return "the reduced model's rollout under the MPC's plan in force blew up"
        if stale:
            self._refresh(run.jacobian, now)
        jacobian, rows = self.jacobian, self.rows
        residual = np.concatenate([solver.weights * run.error, solver.rate_rows @ plan])
        step = -cho_solve(self.factor, rows.T @ residual)
        best = float(np.sum((residual + rows @ step) ** 2))
        row = self.at_sample[self.free]
        towards = cho_solve(self.factor, row)
        miss = float(row @ step) - (angle + action * self.sample - float(self.at_sample @ plan))
        curvature = float(row @ towards)
        held = step - towards * miss / curvature
        error = run.error + jacobian @ held
        breach = solver.breach(Linearised(run.states, error, jacobian, True))
        if breach > BREACH_TOLERANCE:
            return f"its plan's predicted run goes {breach:.3g} m under the minimum clearance"
        omega, mpc_omega = np.sqrt(best + miss**2 / curvature), np.sqrt(best)
        if omega > FACTOR * mpc_omega + SLACK:
            return (
                f"its predicted Omega over the horizon, {omega:.3g} m, exceeds {FACTOR:g} times "
                f"the MPC's ({mpc_omega:.3g} m) plus {SLACK:g} m"
            )
        return ""

    def _refresh(self, jacobian: np.ndarray, now: float) -> None:
        """Keep a swept Jacobian's free columns, the least squares' rows and their factor."""
        solver = self.controller.solver
        self.jacobian = jacobian[:, self.free]
        weighted = solver.weights[:, None] * self.jacobian
        self.rows = rows = np.vstack([weighted, solver.rate_rows[:, self.free]])
        normal = rows.T @ rows
        normal[np.diag_indices_from(normal)] += DAMPING * max(np.max(np.diag(normal)), 1e-30)
        self.factor = cho_factor(normal)
        self.made = now
        self.sweeps += 1
