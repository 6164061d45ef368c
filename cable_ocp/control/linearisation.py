"""The clearance error of a winch problem and its exact Jacobian in the winch parameters.

One sweep of the horizon evaluates the compiled right-hand side with its Jacobian in the state and
the three winch inputs (top-element length, rate, acceleration) at the four stages of every RK4
step (:func:`rhs_jacobian`); the forward sensitivity ``S_k = dx_k/dp`` then runs through the stages
of every step as RK4 runs through its slopes (:func:`propagate_sensitivities`), ``D_k`` being the
(constant) map from the winch parameters to the step's nine winch inputs. (Chaining the stages
into each step's ``A_k`` and ``B_k`` first, batched over the steps, cost three times as much: the
full 40 x 40 products against the sensitivities' 86 x 40.) The error's Jacobian is then the
seabed's gradient at the end times the end's rows of ``S``. This is what a Gauss-Newton step needs
(:mod:`cable_ocp.control.gauss_newton`): one simulation with sensitivities, no second derivatives.

A closed loop's real-time iteration may take the stage Jacobians at the step ends only
(``stage_jacobians="ends"``): one mapped Jacobian at each RK4 point of a plain run, the first
stage's at the step's start, the last stage's at its end, the middle two their mean (second-order
in the step). On a thin whole-space rope's controller (2 elements, h = 0.111 s, 220 steps) the
Jacobian of the error moved by 3e-6 of its norm, and the sweep took 3 ms against 18 ms. Its
fixed point differs from the exact Gauss-Newton one by that much, so the open loop keeps the
exact sweep. The Jacobians are evaluated at every other point, those between taken as the mean
of their neighbours (the states vary over the forcing's seconds, not over one step): on a thin
rope's controller (h = 0.05 s, 400 steps) that moved the error's Jacobian by 6e-6 of its norm
(8e-6 from the exact one, against 3e-6 with every point), and on paper_hill's (h = 1 s) by
4e-6, for half the Jacobians (4.5 ms against 6.5 ms a sample). The sensitivities then run
through the steps in compiled C (:mod:`cable_ocp.control.step_end_tangent`).

The compiled Jacobian (gcc -Og, as every flat Function: 4.6 s to compile at n = 3 against 22.9 s
at -O1, for 40 us a call against 36 us, :func:`cable_ocp.model.compile.optimisation_flags`)
costs about seven right-hand sides (2.9e4 instructions at n = 2, 4.4e4 at n = 3, the right-hand
side 4.5e3 at n = 3), against two per direction and stage (33 directions at n = 2) for CasADi's
forward mode through the compiled step.
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from cable_ocp.control.parameters import ProblemParameters
from cable_ocp.control.step_end_tangent import StepEndTangent, step_end_kernel
from cable_ocp.control.sweep_scratch import sweep_scratch
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import (
    CompileReport,
    Library,
    compile_in_background,
    compiled_from,
)
from cable_ocp.model.layout import INPUTS
from cable_ocp.model.parametric import ParametricModel
from cable_ocp.simulation.integrate import evaluate_into, step_function
from cable_ocp.simulation.seabed import seabed_height

WINCH_ROWS = slice(INPUTS.top_length, INPUTS.top_length_acceleration + 1)
WINCH_INPUTS = 3  # top-element length, its rate and acceleration
RK4_STAGE_COLUMNS = (0, 1, 1, 2)  # stage-input column of each of the four RK4 stages
STAGE_JACOBIANS = ("every", "ends")  # where ErrorLinearisation evaluates the stage Jacobians


def rhs_jacobian(model: CableModel) -> tuple[ca.Function, CompileReport]:
    """``(x, u) -> (x', d x' / d [x; winch inputs])``, compiled to C (cached on disk).

    One library per model structure, the model's numbers bound as inputs.
    """
    functions, report = model.parametric.memo(
        ("rhs_jacobian",), lambda: compiled_from(_jacobian_library(model.parametric))
    )
    return model.memo(("rhs_jacobian",), lambda: model.bind(functions[0])), report


def compile_rhs_jacobian_in_background(model: CableModel) -> None:
    """Start compiling the library of :func:`rhs_jacobian` if it is not in the cache."""
    compile_in_background(_jacobian_library(model.parametric))


def _jacobian_library(parametric: ParametricModel) -> Library:
    """The Jacobian's library of :func:`~cable_ocp.model.compile.compiled_from`."""

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

    # Keyed by the code that derives it: a cache hit builds no right-hand side.
    description = f"{parametric.structure!r}|columns of d xdot / d [x; winch inputs]"
    return Library(lambda: [derive()], ["rhs_jacobian"], description, True, (__file__,))


def sweep_step_function(model: CableModel, step: float) -> ca.Function:
    """``(x, stage inputs (15, 3)) -> (x_next, stage Jacobians)``: one RK4 step, ``step`` in s.

    The stage Jacobians are ``nx x 4 (nx + 3)``, the four stages side by side. A horizon is swept
    by calling it step after step (:class:`ErrorLinearisation`): CasADi's ``mapaccum`` over the
    420 steps of paper_hill took 1 s to build, for outputs of 3e6 numbers.
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
        return ca.Function(
            "sweep_step", [x, stages], [ca.densify(x_next), ca.densify(ca.horzcat(*jacobians))]
        )

    return model.memo(("sweep_step", step), build)


def point_jacobian_function(model: CableModel, count: int) -> ca.Function:
    """``(states (nx, count), inputs (15, count)) -> Jacobians (nx, count (nx + 3))``, dense.

    :func:`rhs_jacobian` mapped over ``count`` points, in the layout the sweep writes.
    """

    def build() -> ca.Function:
        mapped = rhs_jacobian(model)[0].map(count, "thread", 2)
        states = ca.MX.sym("states", model.state_size, count)
        inputs = ca.MX.sym("inputs", INPUTS.end_force.stop, count)
        return ca.Function(
            "point_jacobians", [states, inputs], [ca.densify(mapped(states, inputs)[1])]
        )

    return model.memo(("point_jacobians", count), build)


def propagate_sensitivities(
    transposed: np.ndarray | tuple[np.ndarray, ...],
    winch: np.ndarray,
    step: float,
    kept: int | None = None,
) -> np.ndarray:
    """Forward sensitivities ``S_k = d x_k / d p`` of the RK4 steps, stage by stage.

    Parameters
    ----------
    transposed : array (K, 4, nx + 3, nx), or four arrays (K, nx + 3, nx)
        The stage Jacobians ``[d x'/d x, d x'/d w]`` of every step, each transposed (the layout
        the compiled sweep writes), or each stage's apart (the step ends' Jacobians and their
        mean, :meth:`ErrorLinearisation._step_ends`, with no copy into the stages' layout; the
        same array for two stages is forced once).
    winch : array (K, 9, size)
        ``D_k`` of :func:`winch_map`.
    step : float, s
    kept : int, optional
        Return only the first ``kept`` state components of ``S_k`` (default: all ``nx``).

    Returns
    -------
    array (K + 1, size, kept)
        ``S_k`` transposed, ``S_0 = 0``: the stage slopes' derivatives
        ``dk_i = J_x,i (S + c_i h dk_(i-1)) + J_w,i D_k`` combined as RK4 combines the slopes.

    A parameter's sensitivity is zero until the first step its input touches, and each step
    touches only the few parameters whose basis functions cover it (four of a Hermite
    control's). The rows are therefore ranked by their first touched step, then by their last:
    step k propagates only the rows already touched (half of them on average, for a local
    basis), and the rows it touches form one window of ranks, into which its forcing is added
    (the window of a Hermite control's interval is its two nodes' four rows). On a 3-element
    model over 3120 steps with 162 parameters this took 0.33 s against 1.8 s for the dense
    products, and 18 MB of forcing against 580 MB; over a controller's 220 steps (2 elements,
    10 parameters), 14 ms against 19 ms for the touched rows taken one by one.
    """
    if isinstance(transposed, np.ndarray):
        transposed = tuple(transposed[:, stage] for stage in range(4))
    count, _, nx = transposed[0].shape
    size = winch.shape[2]
    kept = nx if kept is None else kept
    by_column = winch.reshape(count, 3, WINCH_INPUTS, size)[:, list(RK4_STAGE_COLUMNS)]
    touched = np.any(by_column != 0.0, axis=(1, 2))  # (K, size)
    ever = touched.any(axis=0)
    first = np.where(ever, touched.argmax(axis=0), count)
    last = np.where(ever, count - 1 - touched[::-1].argmax(axis=0), count)
    order = np.lexsort((last, first))
    active = np.searchsorted(first[order], np.arange(count), side="right")
    ranked = touched[:, order]
    low = ranked.argmax(axis=1)
    high = size - ranked[:, ::-1].argmax(axis=1)
    spans = np.where(ranked.any(axis=1), high - low, 0)  # a step that touches no row: none
    width = max(int(spans.max()), 1)
    low = np.minimum(low, size - width)  # rows past the touched ones get zero forcing
    window = low[:, None] + np.arange(width)
    taken = np.take_along_axis(by_column[..., order], window[:, None, None, :], axis=3)
    forced = []  # each stage's (K, width, nx)
    for stage, jacobians in enumerate(transposed):
        if stage == 2 and jacobians is transposed[1]:  # the middle stages share their inputs
            forced.append(forced[1])
        else:
            forced.append(np.swapaxes(taken[:, stage], 1, 2) @ jacobians[:, nx:, :])
    state_parts = [jacobians[:, :nx, :] for jacobians in transposed]
    work = np.zeros((size, nx))
    slopes = np.zeros((4, size, nx))  # the slopes' rows past the active ones are never read
    scratch = np.empty((size, nx))
    ranked_out = np.zeros((count + 1, size, kept))
    half, whole, sixth = step / 2, step, step / 6
    # The loop is a few dozen small products and sums a step, so the views it works on are made
    # once per active count and per window, and np.dot (the same dgemm as np.matmul, bitwise)
    # takes a quarter less time per call: over a controller's 160 steps, 3.8 ms against 5.5 ms.
    active, low = active.tolist(), low.tolist()
    by_active = {m: (work[:m], scratch[:m], *slopes[:, :m], ranked_out[:, :m]) for m in set(active)}
    by_window = {start: tuple(slopes[:, start : start + width]) for start in set(low)}
    steps = zip(active, low, *state_parts, *forced, strict=True)
    for k, (m, start, j1, j2, j3, j4, p1, p2, p3, p4) in enumerate(steps):
        current, point, k1, k2, k3, k4, out = by_active[m]
        w1, w2, w3, w4 = by_window[start]
        source = current  # each of the first three slopes sets the point the next is taken at
        for jacobian, forcing, window, slope, reach in (
            (j1, p1, w1, k1, half),
            (j2, p2, w2, k2, half),
            (j3, p3, w3, k3, whole),
        ):
            np.dot(source, jacobian, slope)
            window += forcing
            np.multiply(slope, reach, point)
            point += current
            source = point
        np.dot(point, j4, k4)
        w4 += p4
        np.add(k2, k3, point)
        point *= 2
        np.add(k1, point, point)
        point += k4
        point *= sixth
        current += point
        out[k + 1] = current[:, :kept]
    sensitivities = np.empty((count + 1, size, kept))
    sensitivities[:, order] = ranked_out
    return sensitivities


def winch_map(control, times: np.ndarray, left: np.ndarray, radius: float) -> np.ndarray:
    """``D_k`` (K, 9, size): winch parameters to the nine winch inputs of each step (m, m/s^2)."""
    bases = control.basis(times, left)  # three arrays (3 K, size)
    stacked = np.stack(bases, axis=1)  # (3 K, 3, size): stage, derivative
    stacked *= radius  # in place: 47 MB on 1400 steps and 468 parameters, a third of the map
    return stacked.reshape(times.size // 3, 3 * WINCH_INPUTS, -1)


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
    stage_jacobians : {"every", "ends"}
        Evaluate the right-hand side's Jacobian at every RK4 stage (the exact sensitivities),
        or at the step ends only (module docstring).
    """

    def __init__(
        self, model, step, steps, control, radius, seabed, times, left, stage_jacobians="every"
    ):
        self.model, self.step, self.steps = model, step, steps
        self.at_ends = stage_jacobians == "ends"  # checked by GaussNewtonSettings
        self.run = model.memo(
            ("rk4_run", step, steps),
            lambda: step_function(model, step, compiled=True).mapaccum(steps),
        )  # 0.04 s to build on 2016 steps: the adaptive grid's solvers on one model share it
        # The step ends' Jacobians at every other point and the last (module docstring).
        self._evaluated = np.unique(np.r_[np.arange(0, steps + 1, 2), steps])
        evaluated = self._evaluated.size
        self.point_jacobians = point_jacobian_function(model, evaluated) if self.at_ends else None
        self.winch = winch_map(control, times, left, radius)
        self.slope = error_slope_function(seabed, steps + 1)
        # The sweep writes into numpy arrays in place (CasADi's column-major layout: a C-order
        # array of the transposed shape), which spares converting 1.7e6 numbers through DM; the
        # arrays and the views of every step are shared by the linearisations of one shape.
        nx, width = model.state_size, model.state_size + WINCH_INPUTS
        self._scratch = sweep_scratch(steps, nx, INPUTS.end_force.stop, width, self.at_ends)
        if self.at_ends:
            kernel, size = step_end_kernel(nx), self.winch.shape[2]
            self._tangent = kernel and StepEndTangent(kernel, steps, nx, size, 3, step)
            return
        self._buffer, self._run = sweep_step_function(model, step).buffer()
        # The last sweep's number in the scratch, its seabed slope and the Jacobian it gave.
        self._swept: tuple[int, np.ndarray, np.ndarray] | None = None

    def _sweep(self) -> None:
        """Step the model over the horizon from the scratch's first state under its inputs."""
        buffer, run = self._buffer, self._run
        for start, inputs, end, jacobians in self._scratch.views:
            buffer.set_arg(0, start)
            buffer.set_arg(1, inputs)
            buffer.set_res(0, end)
            buffer.set_res(1, jacobians)
            run()

    def _step_ends(self) -> bool:
        """The run from the scratch's first state under its inputs and the Jacobians at its points.

        Evaluated at every other point (and the last); each between is the mean of its two
        neighbours. Returns whether the Jacobians are finite.
        """
        scratch = self._scratch
        states, inputs, points = scratch.states, scratch.inputs, scratch.jacobians
        flat = inputs.reshape(-1, INPUTS.end_force.stop)
        evaluate_into(self.run, [states[0], flat], [states[1:]])
        at_points = np.concatenate([inputs[:, 0], inputs[-1:, 2]])
        chosen = self._evaluated
        evaluated = np.empty((chosen.size, *points.shape[1:]))
        evaluate_into(self.point_jacobians, [states[chosen], at_points[chosen]], [evaluated])
        points[chosen] = evaluated
        odd = points[1:-1:2][: self.steps // 2]
        np.add(points[0:-2:2][: odd.shape[0]], points[2::2][: odd.shape[0]], out=odd)
        odd *= 0.5
        return bool(np.all(np.isfinite(points)))

    def _step_end_sensitivities(self) -> np.ndarray:
        """``S_k`` (K + 1, size, 3) from the Jacobians at the points (compiled, or numpy)."""
        points = self._scratch.jacobians
        if self._tangent:
            return self._tangent(points, self.winch)
        mean = 0.5 * (points[:-1] + points[1:])
        return propagate_sensitivities(
            (points[:-1], mean, mean, points[1:]), self.winch, self.step, 3
        )

    def stage_inputs(self, values: ProblemParameters, parameters: np.ndarray) -> np.ndarray:
        """The stage inputs (15, 3 K) under the winch parameters."""
        inputs = values.stage_inputs().copy()
        rows = np.einsum("kjs,s->kj", self.winch, parameters)  # (K, 9)
        inputs[WINCH_ROWS] += rows.reshape(-1, WINCH_INPUTS).T
        return inputs

    def error(self, values: ProblemParameters, parameters: np.ndarray) -> Linearised:
        """The error at ``parameters`` from a run without sensitivities (an empty Jacobian).

        Its run takes the compiled RK4 step (the structured right-hand side), the same model as
        the sweep's to round-off, at about a twentieth of the sweep's cost.
        """
        count = self.steps
        states = np.empty((count + 1, self.model.state_size))
        states[0] = values.initial_state
        inputs = self.stage_inputs(values, parameters).T
        evaluate_into(self.run, [values.initial_state, inputs], [states[1:]])
        if not np.all(np.isfinite(states)):
            return Linearised(states, np.full(count + 1, np.nan), np.zeros((0, 0)), False)
        error, _ = self._error_and_slope(values, states)
        return Linearised(states, error, np.zeros((0, 0)), True)

    def __call__(self, values: ProblemParameters, parameters: np.ndarray) -> Linearised:
        """Error and Jacobian at ``parameters`` (rad, rad/s) for the parameter values."""
        count, scratch = self.steps, self._scratch
        inputs = self.stage_inputs(values, parameters).T
        with scratch.lock:  # another linearisation of this shape may share the arrays
            scratch.states[0] = values.initial_state
            scratch.inputs.reshape(-1, INPUTS.end_force.stop)[:] = inputs
            if self.at_ends:
                finite = self._step_ends()
            else:
                self._sweep()
                scratch.sweeps += 1
                finite = np.all(np.isfinite(scratch.jacobians))
            states = scratch.states.copy()
            if not (np.all(np.isfinite(states)) and finite):
                empty = np.zeros((count + 1, self.winch.shape[2]))
                return Linearised(states, np.full(count + 1, np.nan), empty, False)
            if self.at_ends:
                sensitivities = self._step_end_sensitivities()
            else:
                sensitivities = self._swept_sensitivities(self.winch)
        error, slope = self._error_and_slope(values, states)
        jacobian = _error_jacobian(slope, sensitivities)
        if not self.at_ends:
            self._swept = (scratch.sweeps, slope, jacobian)
        return Linearised(states, error, jacobian, True)

    def carried(
        self, source: ErrorLinearisation, jacobian: np.ndarray, columns: np.ndarray | None = None
    ) -> np.ndarray | None:
        """The Jacobian of ``source``'s sweep that gave ``jacobian``, in this control's parameters.

        The sweep's stage Jacobians do not depend on the control, only their map onto its
        parameters (``D_k``) does: on the same model, step and stage times, they are propagated
        through this linearisation's map, at the cost of the propagation alone (the adaptive
        grid's coarsening among finer candidates on whole-space seed 0 case 8 took 0.43 s so,
        against 0.52-0.56 s with a sweep of their own; case 25 0.34-0.36 s against 0.41-0.52 s).
        The result is what this linearisation's own sweep would give at the profile that
        ``source`` swept, the control's nodes holding ``source``'s. None where ``jacobian`` is
        not ``source``'s last sweep's, another sweep has written the arrays since, or the two
        differ in model, step or grid. ``columns``: only those parameters' (None: all).
        """
        swept = source._swept
        same = (
            swept is not None
            and swept[2] is jacobian
            and source._scratch is self._scratch
            and source.model is self.model
            and (source.step, source.steps) == (self.step, self.steps)
            and not self.at_ends
        )
        if not same:
            return None
        count, slope, _ = swept
        with self._scratch.lock:
            if self._scratch.sweeps != count:
                return None
            winch = self.winch if columns is None else self.winch[:, :, columns]
            sensitivities = self._swept_sensitivities(winch)
        return _error_jacobian(slope, sensitivities)

    def _swept_sensitivities(self, winch: np.ndarray) -> np.ndarray:
        """The end's ``S_k`` (K + 1, size, 3) of the sweep in the scratch, through ``winch``."""
        return propagate_sensitivities(self._scratch.jacobians, winch, self.step, kept=3)

    def _error_and_slope(
        self, values: ProblemParameters, states: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``e + bias`` (K + 1,) of a run's states and ``de/d end`` (3, K + 1) there."""
        count = self.steps + 1
        error, slope = np.empty(count), np.empty((count, 3))  # CasADi's (1, K + 1), (3, K + 1)
        # The mapped Function takes every point's offset and reference (a call through DM
        # repeats them itself; the buffer does not).
        offsets = np.broadcast_to(values.end_offset, (count, 3))
        arguments = [states[:, :3], offsets, np.full(count, values.reference)]
        evaluate_into(self.slope, arguments, [error, slope])
        return error + values.bias, np.ascontiguousarray(slope.T)


def _error_jacobian(slope: np.ndarray, sensitivities: np.ndarray) -> np.ndarray:
    """``de/dp`` (K + 1, size): the seabed slope (K + 1, 3) times the end's sensitivities."""
    return np.einsum("ik,ksi->ks", slope, sensitivities)
