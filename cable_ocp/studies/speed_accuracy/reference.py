"""The reference end trajectory (DOP853 on a fine model, checked by RK4); errors against it."""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from cable_ocp.model import structured
from cable_ocp.model.compile import compiled as compile_function
from cable_ocp.simulation.integrate import reference_solution
from cable_ocp.studies.speed_accuracy.model_setup import Setup
from cable_ocp.studies.speed_accuracy.plan import StudyPlan
from cable_ocp.studies.speed_accuracy.timing import timed


@dataclass(frozen=True)
class Reference:
    """The converged end trajectory of a scene.

    Attributes
    ----------
    elements : int
        ``n`` of the reference model.
    time : array (k,), s
        The output times.
    end : array (k, 3), m
        The end's position ``r_E`` at those times.
    tolerance : float
        DOP853 ``rtol = atol``.
    cpu_time, wall_time : float, s
        Of the DOP853 integration.
    check_step : float, s
        The RK4 step of the run that checks the reference.
    check_difference : float, m
        ``max_t |r_E,RK4 - r_E,ref|`` with RK4 at ``check_step`` on the same model: the
        reference's own uncertainty.
    """

    elements: int
    time: np.ndarray
    end: np.ndarray
    tolerance: float
    cpu_time: float
    wall_time: float
    check_step: float
    check_difference: float


def reference_run(scene, plan: StudyPlan) -> Reference:
    """DOP853 on the (compiled) right-hand side of the reference model, checked by RK4."""
    setup = Setup.build(scene, plan.reference_elements)
    model = setup.model
    if plan.compiled:
        # The structured form (equal to model.rhs) compiles in seconds where the flat one takes
        # minutes; reference_solution reads only ``model.rhs``: hand it the compiled one.
        if structured.supports(model):
            rhs = structured.compiled_structured(model, "rhs")
        else:
            rhs = compile_function(model.rhs, repr(model.spec), derivatives=False)[0]
        model = SimpleNamespace(rhs=rhs)
    duration = scene.numerics.duration
    times = np.linspace(0.0, duration, 1 + round(duration / plan.output_interval))
    states, cpu, wall = timed(
        lambda: reference_solution(
            model,
            setup.x0,
            setup.drive,
            times,
            rtol=plan.reference_tolerance,
            atol=plan.reference_tolerance,
        )
    )
    _, end, _, _ = setup.run(plan.reference_check_step, plan.output_interval, plan.compiled)
    return Reference(
        elements=plan.reference_elements,
        time=times,
        end=states[:, :3],
        tolerance=plan.reference_tolerance,
        cpu_time=cpu,
        wall_time=wall,
        check_step=plan.reference_check_step,
        check_difference=end_error(end, states[:, :3]),
    )


def end_error(end: np.ndarray, reference_end: np.ndarray) -> float:
    """``max_t |r_E - r_E,ref|`` over common output times (m)."""
    return float(np.max(np.linalg.norm(end - reference_end, axis=1)))
