"""The direct-shooting transcription of the winch problem (CONVENTIONS.md §5, paper §5).

The horizon ``[0, T]`` is cut into intervals, each a fold of RK4 steps of the (possibly reduced)
model. With single shooting (the default) the intervals are chained from the initial state and
the winch parameters are the only decision variables: the objective's gradient is one reverse
sweep through the RK4 steps. With multiple shooting the state at every node is a decision
variable too and continuity constraints join the intervals: its constraint Jacobian needs one
forward sweep per state and parameter colour (about 45 at n = 3), so it costs far more per
iteration, for more robustness on strongly nonlinear problems. The winch angle is linear in its
parameters (:mod:`cable_ocp.drive.controls`), so the angle, rate, acceleration and top-element
length bounds are linear constraints; they hold between the RK4 samples too
(:mod:`cable_ocp.drive.bounds`), within :data:`cable_ocp.drive.bounds.BOUND_TOLERANCE`. The
objective is ``Omega^2`` of eq. 39 by the trapezoidal rule over the RK4 steps.
"""

from __future__ import annotations

import math
from dataclasses import replace

import casadi as ca
import numpy as np

from cable_ocp.control import defaults
from cable_ocp.control.hermite_nodes import HermiteNodes, check_nodes
from cable_ocp.control.linearisation import (
    clearance_error_function,
    compile_rhs_jacobian_in_background,
)
from cable_ocp.control.problem import Control, WinchProblem
from cable_ocp.control.settings import ModelSettings, OcpSettings
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.drive import stage_times
from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel
from cable_ocp.model.compile import CompileReport
from cable_ocp.model.layout import INPUT_SIZE
from cable_ocp.scene.records import control_size
from cable_ocp.scene.schema import whole_steps
from cable_ocp.simulation.budget import check_memory, optimisation_memory
from cable_ocp.simulation.integrate import step_compile_report, step_function
from cable_ocp.simulation.seabed import trapezoid_weights


def make_control(scene, settings: OcpSettings) -> Control:
    """The control parametrisation the settings ask for (Hermite on given nodes too)."""
    duration = scene.numerics.duration
    if settings.control == "spline":
        return KnotSpline(duration, scene.winch.knots)
    if settings.grid.nodes is not None:
        return HermiteNodes(np.array(settings.grid.nodes))
    return HermiteIntervals(duration, settings.control_intervals)


def control_of(label: str, duration: float, nodes=None) -> Control:
    """The control a result names (``"hermite(84)"``, ``"spline(14)"``) over ``duration`` (s).

    ``nodes``: the Hermite control's node times (s) where they are not equally spaced (an
    adaptive grid's; None or empty: equal intervals).
    """
    size = control_size(label)
    if label.startswith("spline"):
        return KnotSpline(duration, size)
    if nodes is not None and len(nodes):
        control = HermiteNodes(np.asarray(nodes, dtype=float))
        if control.size != size or not np.isclose(control.duration, duration):
            raise ValueError(
                f"nodes: {len(nodes)} node times to {control.duration:g} s do not fit control "
                f"= {label!r} over {duration:g} s"
            )
        return control
    return HermiteIntervals(duration, size // 2)


def full_model_scene(scene, settings: OcpSettings):
    """The scene that the full model's runs take under resolved settings, and what changed.

    Its step is shortened where the Hermite nodes would fall inside the scene's steps
    (:func:`cable_ocp.control.defaults.on_nodes`); a spline (C2) needs no such fit.

    Returns
    -------
    (Scene, str)
    """
    if settings.control == "spline":
        return scene, ""
    if settings.grid.nodes is None:
        return defaults.on_nodes(scene, settings.control_intervals)
    fitted, note = defaults.on_nodes(scene, settings.intervals)
    check_nodes_on_steps(settings.grid.nodes, fitted.numerics.step, "the full model's runs")
    return fitted, note


def check_nodes_on_steps(nodes, step: float, what: str) -> None:
    """Refuse Hermite nodes (s) that do not fall on the RK4 step ends (``step``, s) of ``what``.

    Raises
    ------
    ValueError
        Naming ``GridSettings.nodes``, the first node off the steps and the step.
    """
    for node in nodes[1:]:  # node 0 starts the run
        if whole_steps(node, step) is None:
            raise ValueError(
                f"GridSettings.nodes: t = {node:g} s is not on an RK4 step end of {what} "
                f"(h = {step:.6g} s); the Hermite acceleration jumps at the nodes: take them "
                "from the steps' ends (multiples of the shooting intervals fit every model)"
            )


def steps_per_interval(duration: float, step: float, intervals: int) -> int:
    """RK4 steps in each shooting interval; ``intervals`` must divide the steps of the run."""
    total_steps = round(duration / step)
    if total_steps < 1 or abs(total_steps * step - duration) > 1e-9 * max(duration, 1.0):
        raise ValueError(
            f"step = {step:g} s (of the optimisation model) must divide numerics.duration = "
            f"{duration:g} s into whole RK4 steps: leave step unset to derive it"
        )
    if total_steps % intervals:
        raise ValueError(
            f"intervals = {intervals} must divide the {total_steps} RK4 steps "
            f"(T = {duration:g} s, step = {step:g} s): leave intervals or step unset to derive it"
        )
    return total_steps // intervals


def resolved(scene, settings: OcpSettings, compiled: bool | None = None):
    """The settings with every number left unset derived from the scene, and how (a phrase).

    Elements, RK4 step and intervals follow :mod:`cable_ocp.control.defaults`; a step the user
    fixed is refused when it is above the model's RK4 limit along the locked run, and one that
    does not divide the duration (or the intervals) is refused too, both naming the setting.

    Returns
    -------
    (OcpSettings, str)

    Raises
    ------
    ValueError
        A fixed setting that cannot work. RuntimeError (the locked run's statics or blow-up)
        passes through: :func:`cable_ocp.optimize` reports it as a failed result.
    """
    compiled = settings.compiled if compiled is None else compiled
    duration = scene.numerics.duration
    elements, notes = defaults.model_elements(scene, settings.elements)
    if settings.step is not None and settings.intervals is not None:
        steps_per_interval(duration, settings.step, settings.intervals)
    unit = None  # what a derived step divides: a control interval
    grid = settings.grid
    if settings.step is not None:
        _check_memory(scene, settings, elements, settings.step, settings.intervals)
    else:
        # Nodes on the scene's step ends too: the Hermite acceleration jumps there, and a jump
        # inside an RK4 step of the verifying model costs its bonds (1e-4 m, not converging
        # with h, on a whole-space case with nodes 5.04 s apart at h = 0.1 s). Where no grid
        # of about 5 s fits the scene's steps, the full model's step is shortened to fit it
        # (full_model_scene).
        intervals = settings.intervals or defaults.control_grid(duration, scene.numerics.step)
        unit = duration / intervals
    open_loop, _ = WinchProblem.open_loop_scene(scene)
    step, derived = defaults.model_step(
        open_loop, elements, settings.step, unit, defaults.STEP_CAP, compiled, "step"
    )
    notes += derived
    if settings.step is not None:
        steps_per_interval(duration, step, 1)
        intervals = settings.intervals or defaults.intervals_for(
            duration, step, defaults.control_intervals(duration)
        )
    if settings.intervals is None:
        notes.append(f"{intervals} intervals of {duration / intervals:.3g} s")
    if grid.adaptive and grid.adaptive_finest > 1:
        grid, split = _candidates_split(scene, grid, intervals, settings.step)
        notes += split
    if settings.grid.nodes is not None:
        check_nodes(settings.grid.nodes, duration)
        check_nodes_on_steps(settings.grid.nodes, step, "the optimisation model")
    _check_memory(scene, settings, elements, step, intervals)
    chosen = replace(
        settings,
        model=ModelSettings(elements, step),
        grid=replace(grid, control=settings.control, intervals=intervals),
    )
    text = "derived settings: " + ", ".join(notes) if notes else ""
    return chosen, text


def _candidates_split(scene, grid, intervals: int, fixed_step: float | None):
    """The adaptive grid with ``adaptive_finest`` 1 where its candidates cannot split.

    Each of the ``intervals`` must split on the scene's steps
    (:func:`cable_ocp.control.defaults.candidate_split`), and on the model's step where the user
    fixed it; a derived step is derived for the candidates apart (:func:`candidate_settings`).
    Returns the grid settings and the notes (a list of phrases).
    """
    duration, finest = scene.numerics.duration, grid.adaptive_finest
    if defaults.candidate_split(duration, scene.numerics.step, intervals, finest) < finest:
        steps = "the scene's steps"
    elif fixed_step is not None and steps_per_interval(duration, fixed_step, intervals) % finest:
        steps = "the optimisation model's fixed steps"
    else:
        return grid, []
    return replace(grid, adaptive_finest=1), [
        f"the adaptive grid's candidates are the default grid's nodes (its intervals do not "
        f"split in {finest} on {steps})"
    ]


def candidate_settings(scene, requested: OcpSettings, settings: OcpSettings) -> OcpSettings:
    """The adaptive grid's candidates: ``settings``' intervals split in ``adaptive_finest``.

    ``requested`` are the settings that :func:`resolved` resolved into ``settings`` (the default
    grid's). A model step it derived is derived for the candidates alike, the largest whole
    fraction of their interval within the same limit (:func:`cable_ocp.control.defaults.
    step_within`): with ``n`` steps in a default interval, ``ceil(n / adaptive_finest)`` in a
    candidate's, the same step where ``adaptive_finest`` divides ``n`` (38 of the 50 whole-space
    scenes of seed 0), 2-11 % shorter on the other 12, which only the solves on the candidates
    pay. A step the user fixed is kept (:func:`resolved` checked that the candidates end its
    steps).
    """
    duration, finest = scene.numerics.duration, settings.grid.adaptive_finest
    intervals = settings.intervals * finest
    step = settings.step
    if requested.step is None:
        per_interval = steps_per_interval(duration, step, settings.intervals)
        step = duration / intervals / math.ceil(per_interval / finest)
    _check_memory(scene, settings, settings.elements, step, intervals)
    return replace(
        settings,
        model=replace(settings.model, step=step),
        grid=replace(settings.grid, intervals=intervals),
    )


def _check_memory(scene, settings: OcpSettings, elements: int, step: float, intervals) -> None:
    """Refuse a transcription whose arrays cannot fit in memory, naming the step."""
    intervals = intervals or defaults.control_intervals(scene.numerics.duration)
    size = scene.winch.knots if settings.control == "spline" else 2 * intervals
    estimate = optimisation_memory(scene, step, elements=elements, parameters=size)
    check_memory(
        estimate,
        f"step = {step:g} s of the optimisation model",
        "give a larger step, or leave it unset to derive one",
    )


def winch_problem(scene, settings: OcpSettings, jacobian: bool = False) -> WinchProblem:
    """The scene's winch problem with the control, model and step of resolved settings.

    ``settings`` come from :func:`resolved` (every number set); with compiled models, the
    libraries that the solve and its verification load start compiling first
    (:func:`compile_ahead`, the model's Jacobian too when the solver needs it: ``jacobian``).
    """
    steps_per_interval(scene.numerics.duration, settings.step, settings.intervals)
    if settings.compiled:
        compile_ahead(scene, settings.elements, jacobian)
    return WinchProblem.from_scene(
        scene, make_control(scene, settings), settings.elements, settings.step, settings.compiled
    )


def compile_ahead(scene, elements: int | None, jacobian: bool) -> None:
    """Start compiling, side by side, the libraries that a solve and its verification load.

    Those not in the disk cache: Gauss-Newton's Jacobian first (``jacobian``; the solve waits for
    it), then the structured libraries of the optimisation model (of ``elements``) and of the
    scene's model (the verification's, a closed loop's plant). Their C compilers run at once
    while the problem and the transcription are built (on paper_hill with an empty cache the
    default ``optimize`` took 7.5 and 8.7 s against 12.9 and 13.1 s compiling one after the other).
    """
    reduced = CableModel.from_scene(scene, elements)
    if jacobian:
        compile_rhs_jacobian_in_background(reduced)
    structured.compile_library_in_background(reduced.parametric)
    structured.compile_library_in_background(CableModel.from_scene(scene).parametric)


def ocp_step(
    model: CableModel, step: float, compiled: bool
) -> tuple[ca.Function, CompileReport | None]:
    """The RK4 step ``(x, stage_inputs) -> x_next`` with first derivatives, for the NLP.

    Compiled, the step of :func:`cable_ocp.simulation.integrate.step_function` with its
    derivatives; interpreted, the model's SX step (second derivatives too). The report is None
    when nothing was compiled.
    """
    if not compiled:
        return step_function(model, step), None
    function = step_function(model, step, compiled=True, derivatives=True)
    return function, step_compile_report(model, step, derivatives=True)


def interval_function(step_function, step, steps, seabed) -> ca.Function:
    """``(x, stage inputs, bias, end offset, reference) -> (x_end, int e^2 dt, e)`` on an interval.

    ``e = z_E + b_z - z_ref - z_sb(x_E + b_x, y_E + b_y) + bias`` at the RK4 points (eq. 39
    with the named parameters of :mod:`cable_ocp.control.parameters`); ``e`` after the start.
    """
    size = step_function.size1_in(0)
    x = ca.MX.sym("x", size)
    stages = ca.MX.sym("stages", INPUT_SIZE, 3 * steps)
    bias = ca.MX.sym("bias", 1, steps + 1)
    offset = ca.MX.sym("offset", 3)
    reference = ca.MX.sym("reference")
    states = step_function.mapaccum(steps)(x, stages)
    points = ca.horzcat(x, states)
    errors = clearance_error_function(seabed).map(steps + 1)(points[:3, :], offset, reference)
    errors = errors + bias
    cost = ca.mtimes(errors**2, ca.DM(trapezoid_weights(step, steps + 1)))
    return ca.Function(
        "interval", [x, stages, bias, offset, reference], [states[:, -1], cost, errors[1:]]
    )


def stage_matrix(problem: WinchProblem, named: dict, winch: ca.MX) -> ca.MX:
    """The stage inputs (15, 3 K) of the NLP: the named parameters plus the winch profile.

    The winch adds ``r_D (phi, phi', phi'')`` of its control to the top-element rows at the RK4
    stages (:func:`cable_ocp.drive.drive.stage_times`, end stages from the left).
    """
    times, left = stage_times(problem.grid[:-1], problem.step)
    radius = problem.scene.winch.drum_radius
    basis = problem.control.basis(times, left)
    profile = ca.vertcat(*[(radius * ca.sparsify(ca.DM(b)) @ winch).T for b in basis])
    return ca.vertcat(named["top_motion"], named["winch_base"] + profile, named["end_force"])
