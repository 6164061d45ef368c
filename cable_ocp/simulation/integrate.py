"""Fixed-step RK4 integration of the model as CasADi maps, with blow-up detection.

One RK4 step is one SX Function; a run is ``step.fold(k).mapaccum(m)``, evaluated in calls of
bounded size and wall time, so that progress can be shown, a run that blows up stops early with a
clear error (CONVENTIONS.md §5) and an interrupt (Ctrl-C) is acted on within a fraction of a
second. How a run is cut into calls does not change its numbers: every call steps the same RK4
step in the same order. :func:`reference_solution` integrates the same right-hand side adaptively
(DOP853) as an independent reference.
"""

from __future__ import annotations

import math
import threading
import time
from collections import OrderedDict
from collections.abc import Iterator
from dataclasses import dataclass, replace

import casadi as ca
import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model import structured
from cable_ocp.model.cable import INPUT_SIZE, CableModel
from cable_ocp.model.compile import CompileReport
from cable_ocp.model.compile import compiled as compile_function
from cable_ocp.model.parametric import ParametricModel
from cable_ocp.model.rk4 import parametric_rk4_step, rk4
from cable_ocp.simulation.figures import apart
from cable_ocp.simulation.progress import Progress

SEGMENTS = 40  # progress updates (and blow-up checks) per run, at least
# Blow-up checks per run without a progress bar: each costs a call and a bond check (about 3 ms at
# n = 15, as much as 50 RK4 steps), so a quiet run checks less often.
QUIET_SEGMENTS = 8
# Wall time (s) of one call of the RK4 loops: Python acts on a SIGINT only between calls.
CALL_SECONDS = 0.2
# Largest fold and mapaccum of one call: CasADi takes superlinear time to build them (the
# compiled step at n = 15: fold(1000) 0.15 s, fold(10000) 2 s; mapaccum(512) 0.009 s,
# mapaccum(1000) 0.34 s, mapaccum(10000) 8 s).
MAX_FOLD = 200
MAX_MAP = 500
MAX_CALL_STEPS = 20_000  # RK4 steps of one call: its stage inputs are 360 B a step
# Times per block of a run's grid (step_times): the inputs of a block are 120 B a time, so a run
# of 3.6e7 steps is checked in 4 MB blocks, not one 4.3 GB array.
TIME_BLOCK = 32_768
PROBE_STEPS = 20  # RK4 steps of the first call, which times a step
# Largest RK4 step (SX instructions) compiled as one flat Function. A larger 5-DOF model compiles
# its step around the structured right-hand side (loops over elements: at n = 100 it compiles in
# 2 s instead of 150 s and a call takes 56 us against 69 us); a larger torsion model its flat
# right-hand side.
WHOLE_STEP_LIMIT = 100_000
RK4_STAGES = 4
SIZE_PROBES = (3, 4)  # elements of the small models that give a structure's rhs size (affine in n)
# Largest twist (rad) between neighbouring elements before a torsion run counts as blown up.
MAX_RELATIVE_TWIST = np.pi


class SimulationError(RuntimeError):
    """A simulation became non-finite, left its bonds or reached a singular configuration."""


@dataclass(frozen=True)
class HealthFault:
    """Why a run's state cannot be trusted (:func:`health`), and what to change.

    Attributes
    ----------
    what : str
        What went wrong, where and when.
    remedy : str
        What to change (empty when nothing general helps).
    """

    what: str
    remedy: str = ""

    def __str__(self) -> str:
        return f"{self.what}. Remedy: {self.remedy}." if self.remedy else self.what


def rk4_step(model: CableModel, step: float) -> ca.Function:
    """One classical RK4 step of length ``step`` (s) of the model, as one SX Function.

    Inputs ``x`` and ``stage_inputs`` (15 x 3: ``u`` at ``t``, ``t + h/2``, ``t + h``).
    """
    x = ca.SX.sym("x", model.state_size)
    stages = ca.SX.sym("stage_inputs", INPUT_SIZE, 3)
    x_next = rk4(lambda state, u: model.rhs(state, u), x, stages, step)
    return ca.Function("rk4_step", [x, stages], [x_next], ["x", "stage_inputs"], ["x_next"])


def step_function(
    model: CableModel, step: float, compiled: bool = False, derivatives: bool = False
) -> ca.Function:
    """The RK4 step ``(x, stage_inputs) -> x_next``, interpreted or compiled to C.

    Interpreted, it is the model's own SX step. Compiled, it calls the step of the model's
    structure (:func:`compiled_parametric_step`, cached on disk, :mod:`cable_ocp.model.compile`)
    with the model's numbers and ``step`` as inputs, so every scene of one structure and every step
    share one library. ``derivatives`` compiles the first derivatives too (for optimisation).
    The Function is kept on the model, so repeated runs (Nelder-Mead, studies) build it once;
    :func:`step_compile_report` tells whether the library came from the disk cache.
    """
    return _step_and_report(model, step, compiled, derivatives)[0]


def step_compile_report(model: CableModel, step: float, derivatives: bool = False) -> CompileReport:
    """How the compiled step of :func:`step_function` was obtained (cache hit, compile time)."""
    return _step_and_report(model, step, True, derivatives)[1]


def compiled_parametric_step(
    parametric: ParametricModel, derivatives: bool = False
) -> tuple[ca.Function, CompileReport]:
    """The RK4 step of a structure compiled to C: ``(x, stage_inputs, p, h) -> x_next``.

    A 5-DOF model's step (without derivatives) is the RK4 step of the structure's library
    (:func:`cable_ocp.model.structured.compiled_library`: the structured right-hand side, called
    four times from C), the library its statics and outputs use too: at n = 15 a step costs
    48 us against 60 us for the flat step compiled as one Function, and the library compiles in
    2 to 3.5 s at -O3, against 13 s at n = 15 and 6 s at n = 3 for the flat step.
    A torsion model's whole step is compiled as one flat Function while it is small enough
    (:func:`whole_step_fits`), else around its flat right-hand side. With derivatives the step is
    built around the compiled flat right-hand side and its derivatives: gcc spends superlinear
    time on one long function, so those compile about ten times faster than the flat step's, for
    the same nominal cost and a slightly slower reverse sweep. Built once per structure and
    process; the library is keyed by the structure, not by its numbers.
    """

    def build() -> tuple[ca.Function, CompileReport]:
        description = repr(parametric.structure)
        if not derivatives and structured.supports(parametric):
            return structured.compiled_library(parametric, "rk4_step")
        if not derivatives and whole_step_fits(parametric):
            return compile_function(parametric_rk4_step(parametric), description, derivatives)
        rhs, report = compile_function(parametric.rhs, description, derivatives)
        return parametric_rk4_step(parametric, rhs), report

    return parametric.memo(("rk4_step", derivatives), build)


def whole_step_fits(parametric: ParametricModel) -> bool:
    """Whether the RK4 step (four right-hand sides) is small enough to compile as one Function.

    Decided on the instructions of the right-hand side with its common subexpressions eliminated.
    Elimination removes 17-20 % of them (n = 2 to 100, in air and in water, with and without
    torsion), never half, so a right-hand side of more than twice the limit before it is too large
    either way, and the elimination (1.6 s at n = 100) is spared. A model whose size extrapolated
    from small ones (:func:`extrapolated_rhs_size`) is over twice that again is too large without
    building its own flat right-hand side at all (1 s at n = 100).
    """
    limit = WHOLE_STEP_LIMIT / RK4_STAGES

    def decide() -> bool:
        if extrapolated_rhs_size(parametric) > 4 * limit or parametric.rhs_size() > 2 * limit:
            return False
        return parametric.rhs.n_instructions() <= limit

    return parametric.memo(("whole_step_fits",), decide)


def extrapolated_rhs_size(parametric: ParametricModel) -> int:
    """:meth:`ParametricModel.rhs_size` of the structure, from the same structure at n = 3 and 4.

    Every element adds the same instructions: the size is affine in n, exactly, in air and in
    water, with and without torsion (measured at n = 2 to 100).
    """
    elements = parametric.spec.elements
    if elements <= SIZE_PROBES[-1]:
        return parametric.rhs_size()
    small, large = (
        ParametricModel(replace(parametric.structure, elements=k)).rhs_size() for k in SIZE_PROBES
    )
    return large + (large - small) * (elements - SIZE_PROBES[-1])


def _step_and_report(
    model: CableModel, step: float, compiled: bool, derivatives: bool
) -> tuple[ca.Function, CompileReport | None]:
    def build() -> tuple[ca.Function, CompileReport | None]:
        if not compiled:
            return rk4_step(model, step), None
        function, report = compiled_parametric_step(model.parametric, derivatives)
        return model.bind(function, h=step), report

    return model.memo(("rk4_step", step, compiled, derivatives), build)


def step_count(duration: float, step: float) -> int:
    """Number of RK4 steps in ``duration``; the step must divide it."""
    count = round(duration / step)
    if count < 1 or abs(count * step - duration) > 1e-9 * max(duration, 1.0):
        raise ValueError(
            f"numerics.step = {step} s must divide numerics.duration = {duration} s into a whole "
            "number of steps"
        )
    return count


def step_times(duration: float, step: float) -> Iterator[np.ndarray]:
    """The times of a run's RK4 grid, ``0, h, ..., T`` (s), in blocks of :data:`TIME_BLOCK`.

    Together they are ``np.linspace(0, duration, count + 1)``, without the array of all of them.
    """
    count = int(round(duration / step))
    spacing = duration / count
    for first in range(0, count + 1, TIME_BLOCK):
        stop = min(first + TIME_BLOCK, count + 1)
        times = np.arange(first, stop) * spacing
        if stop == count + 1:
            times[-1] = duration  # as linspace ends
        yield times


def stage_inputs(drive: Drive, times: np.ndarray, step: float) -> np.ndarray:
    """Inputs at the RK4 stages of the steps starting at ``times``: array (15, 3 len(times))."""
    return drive.stage_inputs(times, step)


@dataclass(frozen=True)
class RawRun:
    """States of a run at its output times, with the inputs there.

    Attributes
    ----------
    time : array (k,), s
        The output times, ``0`` to the run's duration.
    states : array (k, state_size)
        The state at each output time.
    inputs : array (k, 15)
        The model's inputs there (:data:`cable_ocp.model.layout.INPUTS`).
    bond_residual : float, m
        Largest bond residual of the states after the first (checked as the run went).
    """

    time: np.ndarray
    states: np.ndarray
    inputs: np.ndarray
    bond_residual: float = float("nan")


def integrate(
    model: CableModel,
    x0: np.ndarray,
    drive: Drive,
    duration: float,
    step: float,
    output_every: int = 1,
    tolerance: float = 1e-6,
    quiet: bool = True,
    compiled: bool = False,
    time_origin: float = 0.0,
) -> RawRun:
    """Integrate the model by RK4 from ``x0`` over ``[0, duration]``.

    Parameters
    ----------
    model : CableModel
        The rope's model (its state layout, right-hand side and bonds).
    x0 : array (state_size,)
        The state at t = 0.
    drive : Drive
        The inputs over time: the top's motion, the winch, the end force.
    duration : float, s
        How long to run; a whole number of steps.
    step : float, s
        The RK4 step ``h``.
    output_every : int
        Keep every k-th step (the last kept time must be ``duration``).
    tolerance : float, m
        Largest bond residual allowed before the run is stopped.
    quiet : bool
        No progress bar when true.
    compiled : bool
        Use the RK4 step compiled to C (cached on disk).
    time_origin : float, s
        Where this run's t = 0 lies on the caller's clock (a pay-out segment's start): the
        times of an error are given on that clock.

    Raises
    ------
    SimulationError
        When the state becomes non-finite, a bond residual exceeds ``tolerance``, or an element
        reaches the singular set of the Euler chart; the message gives the time and a remedy.
    """
    count = step_count(duration, step)
    if count % output_every:
        raise ValueError(
            f"numerics.output_every = {output_every} must divide the {count} steps of the run"
        )
    x0 = np.asarray(x0, dtype=float).ravel()
    model.check_regular(x0)
    outputs = count // output_every
    # An output is `repeats` calls' units of `inner` RK4 steps, folded into one Function.
    inner = largest_divisor(output_every, MAX_FOLD)
    repeats = output_every // inner
    units = outputs * repeats
    per_segment = max(1, math.ceil(outputs / (QUIET_SEGMENTS if quiet else SEGMENTS))) * repeats
    most = max(1, min(per_segment, MAX_MAP, MAX_CALL_STEPS // inner))
    all_times = np.arange(outputs + 1) * output_every * step
    all_inputs = drive.inputs(all_times).T
    # Row k is the state at all_times[k]: the C-ordered rows of a block are CasADi's columns, so
    # the compiled code writes each call straight into its rows (no conversion of the states).
    states = np.empty((outputs + 1, x0.size))
    states[0] = x0
    scratch = np.empty((most, x0.size)) if repeats > 1 else None
    progress = Progress("simulate", duration, quiet)
    largest, done, size = 0.0, 0, max(1, min(most, PROBE_STEPS // inner))
    current = x0.copy()  # the state after `done` units
    while done < units:
        size = min(size, units - done)
        steps = np.arange(done * inner, (done + size) * inner) * step
        target = states[done + 1 : done + 1 + size] if repeats == 1 else scratch[:size]
        started = time.perf_counter()
        step_states(
            model, current, stage_inputs(drive, steps, step).T, step, inner, compiled, target
        )
        elapsed = time.perf_counter() - started
        ends = np.arange(done + 1, done + size + 1)
        last = ends % repeats == 0
        kept = ends[last] // repeats  # the output rows this call completed
        if repeats > 1:
            states[kept] = target[last]
        current = target[size - 1].copy()
        done += size
        if kept.size:
            block = slice(int(kept[0]), int(kept[-1]) + 1)
            norms = np.empty(kept.size)
            evaluate_into(
                _residual_norms(model, kept.size, compiled),
                [states[block], all_inputs[block]],
                [norms],
            )
            when = all_times[block] + time_origin
            _check_block(model, states[block], norms, when, step, tolerance)
            largest = max(largest, float(norms.max()))
        progress.update(done * inner * step)  # also within an output of many calls
        # The next call takes about CALL_SECONDS at this one's wall time per step; its size a power
        # of two (or `most`), so that few Functions are built.
        wanted = CALL_SECONDS * size / max(elapsed, 1e-9)
        size = most if wanted >= most else 2 ** max(0, int(math.log2(max(wanted, 1.0))))
    progress.close()
    return RawRun(all_times, states, all_inputs, largest)


def step_states(
    model: CableModel,
    x0: np.ndarray,
    stages: np.ndarray,
    step: float,
    every: int,
    compiled: bool,
    out: np.ndarray,
) -> np.ndarray:
    """RK4 steps from ``x0``, the state kept after every ``every`` of them, written into ``out``.

    The runner of :func:`integrate` and of the closed loop's plant: one call of the step folded
    ``every`` times and mapped ``len(out)`` times (:func:`_segment_function`).

    Parameters
    ----------
    model : CableModel
    x0 : array (state_size,)
    stages : array (3 every len(out), 15)
        The inputs at the stages of each step (:func:`stage_inputs`, transposed).
    step : float, s
    every : int
        RK4 steps between two kept states.
    compiled : bool
        The step compiled to C (cached on disk).
    out : array (k, state_size)
        Row ``j`` becomes the state after ``(j + 1) every`` steps.

    Returns
    -------
    array (k, state_size)
        ``out``.
    """
    function = _segment_function(model, step, compiled, every, out.shape[0])
    evaluate_into(function, [x0, stages], [out])
    return out


def largest_divisor(number: int, most: int) -> int:
    """The largest divisor of ``number`` that is at most ``most`` (1 at least)."""
    return max(k for k in range(1, min(number, most) + 1) if number % k == 0)


def evaluate_into(
    function: ca.Function, arguments: list[np.ndarray], results: list[np.ndarray]
) -> None:
    """Evaluate a Function on numpy arrays, writing its outputs into ``results``.

    Each array holds a CasADi matrix column by column as C-ordered rows (its transpose), so no
    conversion through CasADi's DM is needed: at n = 100 that conversion cost a third of a run.
    """
    buffer, evaluate = _buffer(function, len(arguments), len(results))
    arguments = [np.ascontiguousarray(a, dtype=float) for a in arguments]
    for k, argument in enumerate(arguments):
        buffer.set_arg(k, memoryview(argument))
    for k, result in enumerate(results):
        buffer.set_res(k, memoryview(result))
    evaluate()
    if buffer.ret() != 0:
        raise SimulationError(f"evaluating {function.name()} failed (code {buffer.ret()})")


# Each thread's evaluation buffers of the Functions it evaluated last (a sweep's Dask workers
# may be threads of one process): making a buffer costs 0.16 ms (its work arrays), a tenth of a
# thin rope's controller evaluations. At most BUFFERS_KEPT are kept, the oldest dropped.
BUFFERS_KEPT = 64
_BUFFERS = threading.local()


def _buffer(function: ca.Function, inputs: int, outputs: int):
    """A buffer and its evaluation for ``function``, reused when every argument is set."""
    if inputs < function.n_in() or outputs < function.n_out():
        return function.buffer()  # one left unset would keep an earlier call's pointer
    kept = getattr(_BUFFERS, "kept", None)
    if kept is None:
        kept = _BUFFERS.kept = OrderedDict()
    entry = kept.get(id(function))
    if entry is None:
        entry = kept[id(function)] = (function, *function.buffer())  # keeps the id unique
        if len(kept) > BUFFERS_KEPT:
            kept.popitem(last=False)
    else:
        kept.move_to_end(id(function))
    return entry[1], entry[2]


def _segment_function(
    model: CableModel, step: float, compiled: bool, output_every: int, size: int
) -> ca.Function:
    """``size`` states ``output_every`` RK4 steps apart, in one call.

    Compiled, the structure's library is folded and mapped first and the numbers bound once
    around the loops, not at every step.
    """

    def build() -> ca.Function:
        if not compiled:
            return step_function(model, step).fold(output_every).mapaccum(size)
        library = compiled_parametric_step(model.parametric)[0]
        loops = model.parametric.memo(
            ("segment", output_every, size), lambda: library.fold(output_every).mapaccum(size)
        )
        return model.bind(loops, h=step)

    return model.memo(("segment", step, compiled, output_every, size), build)


def _residual_norms(model: CableModel, count: int, compiled: bool) -> ca.Function:
    """Largest bond residual (m) of each of ``count`` states (compiled along with the step)."""

    def parametric_norm() -> ca.Function:
        parametric = model.parametric
        if structured.supports(parametric):
            # Stepped by the structured loops: its bonds too, without the flat graph.
            return structured.compiled_library(parametric, "bond_norm")[0]
        x, u, p = parametric.x, parametric.u, parametric.p
        norm = ca.Function(
            "bond_norm",
            [x, u, p],
            [ca.mmax(ca.fabs(parametric.bond_residual()))],
            ["x", "u", "p"],
            ["norm"],
            {"cse": True},
        )
        return compile_function(norm, repr(parametric.structure), derivatives=False)[0]

    def build() -> ca.Function:
        if not compiled:
            x, u = ca.SX.sym("x", model.state_size), ca.SX.sym("u", INPUT_SIZE)
            residual = model.outputs(x=x, u=u)["bond_residual"]
            return ca.Function("bond_norm", [x, u], [ca.mmax(ca.fabs(residual))]).map(count)
        library = model.parametric.memo(("bond_norm",), parametric_norm)
        return model.bind(model.parametric.memo(("bond_norm", count), lambda: library.map(count)))

    return model.memo(("bond_norm", compiled, count), build)


def bond_residuals(
    model: CableModel, states: np.ndarray, inputs: np.ndarray, compiled: bool = False
) -> np.ndarray:
    """Largest bond residual (m) of each state of a run: array (k,).

    Parameters
    ----------
    model : CableModel
    states : array (k, state_size)
    inputs : array (k, 15)
    compiled : bool
        Evaluate the compiled residual (as :func:`integrate` checks it).
    """
    norms = np.empty(states.shape[0])
    evaluate_into(_residual_norms(model, norms.size, compiled), [states, inputs], [norms])
    return norms


def health(
    model: CableModel,
    block: np.ndarray,
    norms: np.ndarray,
    times: np.ndarray,
    step: float,
    tolerance: float,
) -> HealthFault | None:
    """The first fault of a block of states, or None: the health check of every run.

    A state that is non-finite, off its bonds by more than ``tolerance``, twisted apart (a
    torsion model, :func:`_twist_fault`) or at the singular set of the Euler chart.

    Parameters
    ----------
    model : CableModel
    block : array (k, state_size)
        States at ``times``.
    norms : array (k,), m
        Their largest bond residuals (:func:`bond_residuals`).
    times : array (k,), s
    step : float, s
        The RK4 step they were integrated with (for the message).
    tolerance : float, m
        ``numerics.constraint_tolerance``.
    """
    finite = np.all(np.isfinite(block), axis=1)
    with np.errstate(invalid="ignore"):
        off_bonds = norms > tolerance
    first_non_finite = int(np.argmin(finite)) if not finite.all() else times.size
    first_off_bonds = int(np.argmax(off_bonds)) if off_bonds.any() else times.size
    if first_non_finite < times.size and first_non_finite <= first_off_bonds:
        return HealthFault(
            f"the state became non-finite at t = {times[first_non_finite]:.6g} s with step "
            f"h = {step:g} s: the RK4 step is beyond its stability limit",
            "a smaller numerics.step, more damping (cable.bending_damping), or fewer elements "
            "(model.elements)",
        )
    if first_off_bonds < times.size:
        k = first_off_bonds
        residual, limit = apart(float(norms[k]), tolerance)
        return HealthFault(
            f"bond residual {residual} m exceeds numerics.constraint_tolerance = "
            f"{limit} m at t = {times[k]:.6g} s with step h = {step:g} s",
            "a smaller numerics.step or other Baumgarte gains (numerics.baumgarte_alpha/beta); "
            "if the run is otherwise sound, a larger numerics.constraint_tolerance",
        )
    if model.spec.element.torsion:
        twisted = _twist_fault(model, block, times, step)
        if twisted is not None:
            return twisted
    try:
        model.check_regular(block.T)
    except ValueError as error:
        return HealthFault(f"at t <= {times[-1]:.6g} s: {error}")
    return None


def _check_block(model, block, norms, times, step, tolerance) -> None:
    """Raise on the first state of a block (rows) that is non-finite or off its bonds."""
    fault = health(model, block, norms, times, step, tolerance)
    if fault is not None:
        raise SimulationError(str(fault))


def _twist_fault(
    model: CableModel, block: np.ndarray, times: np.ndarray, step: float
) -> HealthFault | None:
    """Neighbouring elements twisted apart by more than half a turn, or None.

    A torsional instability leaves the bonds intact and the state finite (the twist does not
    move the axes): measured at n = 15, h = 0.27 s, the twist grew to 1e6 rad unseen by the other
    checks. Torsion springs hold neighbours within far less than pi of each other.
    """
    twist = np.abs(np.diff(block[:, model.twist_angle_index()], axis=1)).max(axis=1)
    if not np.any(twist > MAX_RELATIVE_TWIST):
        return None
    k = int(np.argmax(twist > MAX_RELATIVE_TWIST))
    return HealthFault(
        f"neighbouring elements twisted apart by {twist[k]:.3g} rad at t = {times[k]:.6g} s "
        f"with step h = {step:g} s: a torsional instability",
        "a smaller numerics.step (torsion needs about 0.12 s / n, cable_ocp.studies.stability), "
        "or torsion off (model.torsion = false) if the scene does not need it",
    )


def reference_solution(
    model: CableModel,
    x0: np.ndarray,
    drive: Drive,
    times: np.ndarray,
    rtol: float = 1e-10,
    atol: float = 1e-10,
) -> np.ndarray:
    """The same model integrated by SciPy's adaptive DOP853 at tight tolerances.

    Returns
    -------
    array (len(times), state_size)
    """
    from scipy.integrate import solve_ivp  # here: importing SciPy's integrators takes ~1 s

    rhs = model.rhs

    def f(t, x):
        return np.array(rhs(x, drive.inputs(np.array([t]))[:, 0])).ravel()

    solution = solve_ivp(
        f,
        (times[0], times[-1]),
        np.asarray(x0, float),
        method="DOP853",
        t_eval=times,
        rtol=rtol,
        atol=atol,
    )
    if not solution.success:
        raise SimulationError(f"reference integrator failed: {solution.message}")
    return solution.y.T
