"""Stability study: RK4 step limits, Baumgarte gains, knots, the Euler-angle singularity.

Issue "stability study" (CONVENTIONS.md §5, §9). Four parts, each a function returning a frozen
dataclass with a markdown ``table()`` and, where it has one, a ``chart()``:

- :func:`step_limits`: the largest stable RK4 step against ``n``, with and without torsion, by
  bisection in ``log h`` (:func:`largest_stable_step`), cross-checked by the step at which the
  linearisation at states of the run leaves RK4's stability region (:func:`linearised_step`);
- :func:`baumgarte_drift`: the bond residual over time for several Baumgarte gains, with the end
  trajectory's error against a fine reference;
- :func:`knots_comparison`: IPOPT (spline control) against the paper's Nelder-Mead as the number
  of knots grows;
- :func:`singular_states`: states with an element along +-y, rejected with the model's message.

:func:`run_stability` runs them all and writes ``stability.md`` and the charts atomically.

The step limit and the drift are measured on the ``end_force`` scene with its push moved to
``t = 0`` (:data:`PUSH`): the scene starts from a static equilibrium, so without a push a run would
only amplify rounding noise, and the end force acts on the shortest element (``Delta/2``), whose
modes are the fastest.

Modules, one job each:

- ``push``: the pushed scene (:data:`PUSH`, :data:`SHARP_PUSH`, :func:`pushed_scene`);
- the RK4 step limit of a linearisation, :func:`linearised_step`, lives in
  :mod:`cable_ocp.simulation.stability` (model correction picks its step by it);
- ``stable_step``: the largest stable step of one model (:func:`largest_stable_step`);
- ``limits``: the step limits against ``n`` and their fits (:func:`step_limits`);
- ``baumgarte``: the drift for several Baumgarte gains (:func:`baumgarte_drift`);
- ``knots``: IPOPT against Nelder-Mead in the knots (:func:`knots_comparison`);
- ``singular``: the Euler-angle singularity (:func:`singular_states`);
- ``study``: settings, run and report (:func:`run_stability`);
- ``markdown``: markdown helpers (:func:`table_cell`).
"""

from cable_ocp.simulation.stability import GROWTH_SLACK, linearised_step, rk4_growth
from cable_ocp.studies.stability.baumgarte import (
    BaumgarteDrift,
    DriftSizes,
    GainRun,
    baumgarte_drift,
    bond_residuals,
)
from cable_ocp.studies.stability.knots import KnotRun, KnotsComparison, KnotsSizes, knots_comparison
from cable_ocp.studies.stability.limits import StepLimits, power_law, step_limits
from cable_ocp.studies.stability.markdown import table_cell
from cable_ocp.studies.stability.push import PUSH, SHARP_PUSH, pushed_scene
from cable_ocp.studies.stability.singular import SingularCase, singular_states
from cable_ocp.studies.stability.stable_step import (
    TWIST_LIMIT,
    TWIST_SEED,
    StableStep,
    StepSearch,
    largest_stable_step,
    run_length,
)
from cable_ocp.studies.stability.study import StabilitySettings, StabilityStudy, run_stability

__all__ = [
    "BaumgarteDrift",
    "DriftSizes",
    "GROWTH_SLACK",
    "GainRun",
    "KnotRun",
    "KnotsComparison",
    "KnotsSizes",
    "PUSH",
    "SHARP_PUSH",
    "SingularCase",
    "StabilitySettings",
    "StabilityStudy",
    "StableStep",
    "StepLimits",
    "StepSearch",
    "TWIST_LIMIT",
    "TWIST_SEED",
    "baumgarte_drift",
    "bond_residuals",
    "knots_comparison",
    "largest_stable_step",
    "linearised_step",
    "power_law",
    "pushed_scene",
    "rk4_growth",
    "run_length",
    "run_stability",
    "singular_states",
    "step_limits",
    "table_cell",
]
