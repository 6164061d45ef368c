"""The clearance error of a winch problem and its exact Jacobian in the winch parameters.

One sweep of the horizon evaluates the compiled right-hand side with its Jacobian in the state and
the three winch inputs (top-element length, rate, acceleration) at the four stages of every RK4
step (:func:`rhs_jacobian`); the stage Jacobians are chained into the step's ``A_k = dx_{k+1}/dx_k``
and ``B_k = dx_{k+1}/dw_k`` (numpy, batched over the steps), and the forward sensitivity
``S_{k+1} = A_k S_k + B_k D_k`` runs over the steps, ``D_k`` being the (constant) map from the winch
parameters to the step's nine winch inputs. The error's Jacobian is then the seabed's gradient at
the end times the end's rows of ``S``. This is what a Gauss-Newton step needs
(:mod:`cable_ocp.control.gauss_newton`): one simulation with sensitivities, no second derivatives.

The compiled Jacobian (gcc -O1, as every flat Function: -O0 compiles in half the time but runs
3.6x slower) costs about seven right-hand sides (2.9e4 instructions at n = 2, 4.4e4 at n = 3,
the right-hand side 4.5e3 at n = 3), against two per direction and stage (33 directions at n =
2) for CasADi's forward mode through the compiled step.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import CompileReport, compiled_from
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.seabed import seabed_height

WINCH_ROWS = slice(INPUTS.top_length, INPUTS.top_length_acceleration + 1)
WINCH_INPUTS = 3  # top-element length, its rate and acceleration
RK4_STAGE_COLUMNS = (0, 1, 1, 2)  # stage-input column of each of the four RK4 stages


def rhs_jacobian(model: CableModel) -> tuple[ca.Function, CompileReport]:
    """``(x, u) -> (x', d x' / d [x; winch inputs])``, compiled to C (cached on disk).

    One library per model structure, the model's numbers bound as inputs.
    """
    parametric = model.parametric

    def derive() -> ca.Function:
        x, u, p = parametric.x, parametric.u, parametric.p
        xdot = parametric.rhs(x, u, p)
        wrt = ca.vertcat(x, u[WINCH_ROWS])
        # Column by column (a forward sweep each): 2.9e4 instructions at n = 2 and 4.4e4 at
        # n = 3, against 9.0e4 and 1.6e5 for CasADi's Jacobian of all columns at once, and 2.5
        # to 6x faster per call.
        jacobian = ca.horzcat(*[ca.jacobian(xdot, wrt[i]) for i in range(wrt.numel())])
        return ca.Function(
            "rhs_jacobian", [x, u, p], [xdot, jacobian], ["x", "u", "p"], ["xdot", "jacobian"],
            {"cse": True},
        )  # fmt: skip

    def build() -> tuple[ca.Function, CompileReport]:
        # Keyed by the right-hand side: a cache hit does not derive the Jacobian again.
        description = f"{parametric.structure!r}|columns of d xdot / d [x; winch inputs]"
        return compiled_from(derive, "rhs_jacobian", parametric.rhs, description)

    function, report = parametric.memo(("rhs_jacobian",), build)
    return model.memo(("rhs_jacobian",), lambda: model.bind(function)), report


def sweep_function(model: CableModel, step: float, steps: int) -> ca.Function:
    """``(x0, stage inputs (15, 3 steps)) -> (states (nx, steps), stage Jacobians)``.

    The stage Jacobians are ``nx x 4 (nx + 3)`` per step, the four stages side by side.
    """

    def build() -> ca.Function:
        jacobian = rhs_jacobian(model)[0]
        x = ca.MX.sym("x", model.state_size)
        stages = ca.MX.sym("stages", INPUTS.end_force.stop, 3)
        rates, jacobians, point = [], [], x
        for stage, column in enumerate(RK4_STAGE_COLUMNS):
            if stage:
                point = x + (step if stage == 3 else step / 2) * rates[-1]
            rate, matrix = jacobian(point, stages[:, column])
            rates.append(rate)
            jacobians.append(matrix)
        x_next = x + step / 6 * (rates[0] + 2 * rates[1] + 2 * rates[2] + rates[3])
        one = ca.Function(
            "sweep_step", [x, stages], [ca.densify(x_next), ca.densify(ca.horzcat(*jacobians))]
        )
        return one.mapaccum(steps)

    return model.memo(("sweep", step, steps), build)


def chain_stages(jacobians: np.ndarray, step: float) -> tuple[np.ndarray, np.ndarray]:
    """``A_k`` (K, nx, nx) and ``B_k`` (K, nx, 9) of the RK4 steps from their stage Jacobians.

    ``jacobians``: (K, 4, nx, nx + 3), stage ``i`` of step ``k``. The nine winch inputs of a step
    are the three winch rows at its three stage-input columns (index ``3 column + row``).
    """
    count, _, nx, _ = jacobians.shape
    width = nx + 3 * WINCH_INPUTS
    identity = np.zeros((nx, width))
    identity[:, :nx] = np.eye(nx)
    total = np.zeros((count, nx, width))
    slope = None
    for stage, (weight, column) in enumerate(zip((1, 2, 2, 1), RK4_STAGE_COLUMNS, strict=True)):
        state_part, winch_part = jacobians[:, stage, :, :nx], jacobians[:, stage, :, nx:]
        if stage == 0:
            slope = np.zeros((count, nx, width))
            slope[:, :, :nx] = state_part
        else:
            fraction = step if stage == 3 else step / 2
            slope = state_part @ (identity + fraction * slope)
        slope[:, :, nx + 3 * column : nx + 3 * column + 3] += winch_part
        total += weight * slope
    total = identity + step / 6 * total
    return total[:, :, :nx], total[:, :, nx:]


def winch_map(control, times: np.ndarray, left: np.ndarray, radius: float) -> np.ndarray:
    """``D_k`` (K, 9, size): winch parameters to the nine winch inputs of each step (m, m/s^2)."""
    bases = control.basis(times, left)  # three arrays (3 K, size)
    stacked = np.stack(bases, axis=1)  # (3 K, 3, size): stage, derivative
    return radius * stacked.reshape(times.size // 3, 3 * WINCH_INPUTS, -1)


def clearance_error_function(seabed) -> ca.Function:
    """``(end (3), offset (3), reference) -> e``, the transcription's clearance error (m).

    ``e = z_E + b_z - r - z_sb(x_E + b_x, y_E + b_y)`` (eq. 39 with the end offset ``b`` and the
    reference ``r`` of :mod:`cable_ocp.control.parameters`): one expression for both solvers.
    """
    end, offset, reference = ca.SX.sym("end", 3), ca.SX.sym("offset", 3), ca.SX.sym("reference")
    height = seabed_height(seabed, end[0] + offset[0], end[1] + offset[1])
    error = end[2] + offset[2] - reference - height
    return ca.Function("clearance_error", [end, offset, reference], [error])


def error_slope_function(seabed, count: int) -> ca.Function:
    """``(ends (3, count), offset, reference) -> (e (1, count), de/d end (3, count))``."""
    error = clearance_error_function(seabed)
    end, offset, reference = ca.SX.sym("end", 3), ca.SX.sym("offset", 3), ca.SX.sym("reference")
    value = error(end, offset, reference)
    one = ca.Function("error_slope", [end, offset, reference], [value, ca.gradient(value, end)])
    return one.map(count)


@dataclass(frozen=True)
class Linearised:
    """The clearance error on the RK4 grid and its Jacobian, at one set of winch parameters.

    Attributes
    ----------
    states : array (K + 1, nx)
        The optimisation model's run, the initial state first.
    error : array (K + 1,), m
        ``e + bias`` at the RK4 points.
    jacobian : array (K + 1, size), m/rad
        Its derivative in the winch parameters (zero in the first row).
    finite : bool
        Whether the run stayed finite (if not, the other fields are not to be used).
    """

    states: np.ndarray
    error: np.ndarray
    jacobian: np.ndarray
    finite: bool


class ErrorLinearisation:
    """Evaluates :class:`Linearised` for a problem's model, grid and control.

    Parameters
    ----------
    model : CableModel
    step : float, s
    steps : int
        RK4 steps of the horizon.
    control : KnotSpline or HermiteIntervals
    radius : float, m
        Drum radius ``r_D``.
    seabed
        The scene's seabed (hills), as :func:`cable_ocp.simulation.seabed.seabed_height` takes it.
    times, left : array
        The stage times and their left flags (:func:`cable_ocp.drive.drive.stage_times`).
    """

    def __init__(self, model, step, steps, control, radius, seabed, times, left):
        self.model, self.step, self.steps = model, step, steps
        self.sweep = sweep_function(model, step, steps)
        self.winch = winch_map(control, times, left, radius)
        self.slope = error_slope_function(seabed, steps + 1)
        self.compile_report = rhs_jacobian(model)[1]
        # The sweep writes into numpy arrays in place (CasADi's column-major layout: a C-order
        # array of the transposed shape), which spares converting 1.7e6 numbers through DM.
        nx, width = model.state_size, model.state_size + WINCH_INPUTS
        self._start = np.zeros(nx)
        self._inputs = np.zeros((3 * steps, INPUTS.end_force.stop))
        self._states = np.zeros((steps, nx))
        self._jacobians = np.zeros((steps, 4, width, nx))
        self._buffer, self._run = self.sweep.buffer()
        for index, array in enumerate((self._start, self._inputs)):
            self._buffer.set_arg(index, memoryview(array))
        for index, array in enumerate((self._states, self._jacobians)):
            self._buffer.set_res(index, memoryview(array))

    def stage_inputs(self, values: ProblemParameters, parameters: np.ndarray) -> np.ndarray:
        """The stage inputs (15, 3 K) under the winch parameters."""
        inputs = values.stage_inputs().copy()
        rows = np.einsum("kjs,s->kj", self.winch, parameters)  # (K, 9)
        inputs[WINCH_ROWS] += rows.reshape(-1, WINCH_INPUTS).T
        return inputs

    def __call__(self, values: ProblemParameters, parameters: np.ndarray) -> Linearised:
        """Error and Jacobian at ``parameters`` (rad, rad/s) for the parameter values."""
        nx, count = self.model.state_size, self.steps
        self._start[:] = values.initial_state
        self._inputs[:] = self.stage_inputs(values, parameters).T
        self._run()
        states = np.vstack([values.initial_state, self._states])
        jacobians = self._jacobians.transpose(0, 1, 3, 2)  # (K, 4, nx, nx + 3)
        if not (np.all(np.isfinite(states)) and np.all(np.isfinite(jacobians))):
            empty = np.zeros((count + 1, self.winch.shape[2]))
            return Linearised(states, np.full(count + 1, np.nan), empty, False)
        a, b = chain_stages(jacobians, self.step)
        forced = b @ self.winch  # (K, nx, size)
        end_rows = np.zeros((count + 1, 3, self.winch.shape[2]))
        sensitivity = np.zeros((nx, self.winch.shape[2]))
        for k in range(count):
            sensitivity = a[k] @ sensitivity + forced[k]
            end_rows[k + 1] = sensitivity[:3]
        error, slope = self.slope(states[:, :3].T, values.end_offset, values.reference)
        error = np.asarray(error).ravel() + values.bias
        jacobian = np.einsum("ik,kis->ks", np.asarray(slope), end_rows)
        return Linearised(states, error, jacobian, True)
