"""Numerical settings that follow from the scene: what the optimiser and the controller work on.

A user states a scene (a rope, a payload, a tow, a duration); the numbers the optimisation needs
beside it (the reduced model's elements and RK4 step, the control grid; the controller's model,
step and sample) are derived from that scene here, and every result says how
(:func:`describe`). CONVENTIONS.md §5 ("numerical settings") gives the rules:

- **Control grid** from the duration: intervals of about :data:`CONTROL_INTERVAL` seconds
  (42 on the paper's 210 s), the count nearest ``T / 5 s`` that divides the scene's RK4 steps,
  so that the nodes (where the Hermite acceleration jumps) fall on step ends of every model.
  Where no such count is within :data:`GRID_SLACK` of ``T / 5 s`` (T = 449 s at h = 0.05 s:
  20 or 449 intervals), the count is ``T / 5 s`` and the full model's runs take the largest
  step up to the scene's that puts the nodes on step ends (:func:`on_nodes`).
- **Reduced model's step** from its RK4 limit along the run it will make: the locked winch's run
  of the reduced model, linearised at :data:`~cable_ocp.simulation.stability.LIMIT_PROBES`
  states (drag stiffens the model as it moves through the water, so the limit at rest says too
  little), times :data:`~cable_ocp.simulation.stability.STABLE_SHARE`, at most
  :data:`STEP_CAP`, and a whole fraction of the control interval, so that the steps divide
  every interval.
- **Reduced model's elements**: :data:`REDUCED_ELEMENTS`, and more on a long rope, so that no
  element is longer than :data:`REDUCED_ELEMENT_LENGTH`; never more than the scene's.

A step the user fixes is checked against the same limit before the solve: above it, the error
names the setting, the limit and the remedy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cable_ocp.drive import winch
from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import whole_steps
from cable_ocp.simulation.integrate import step_count
from cable_ocp.simulation.stability import STABLE_SHARE, limit_along_run
from cable_ocp.simulation.statics import starting_state

# s: intervals of the Hermite control (paper_hill's 210 s in 42), and of the controller's plan.
CONTROL_INTERVAL = 5.0
# The reduced model: 3 elements (at n_ocp = 3, 5, 8 the verified Omega of paper_flat was 8.9e-6,
# 7.4e-6, 7.3e-6 m for 39, 105, 222 s of IPOPT: README, "speed against accuracy"), and no element
# longer than this (m), so that a long rope keeps its shape.
REDUCED_ELEMENTS = 3
# Share by which the control grid may stray from intervals of CONTROL_INTERVAL to fit the
# scene's steps; beyond it the full model's step is shortened instead (20 intervals of 22.4 s
# on a 449 s whole-space case left Omega 1.43 m, 10 % over its reach floor; 90 intervals on the
# same scene at T = 450 s, 1.34 m).
GRID_SLACK = 0.2
REDUCED_ELEMENT_LENGTH = 150.0
# s: the reduced model's step is never coarser than this, the step that served the paper's rope
# (its limit along the run is 1.02 s at n = 3), whatever a stiff-free scene would allow.
STEP_CAP = 0.5
# The fitted step's search: at most this many times the first count of steps per interval.
FIT_SEARCH = 64


@dataclass(frozen=True)
class StepChoice:
    """A step chosen from a model's RK4 limit along a run.

    Attributes
    ----------
    step : float, s
        The step chosen: a whole fraction of its unit within :data:`STABLE_SHARE` of ``limit``.
    limit : float, s
        The smallest linearised RK4 limit along the run.
    limit_time : float, s
        When the run reached it.
    """

    step: float
    limit: float
    limit_time: float

    def describe(self, what: str) -> str:
        """One phrase: the step and where it came from."""
        return (
            f"{what} h = {self.step:.4g} s (RK4 limit {self.limit:.3g} s along the locked run, "
            f"at t = {self.limit_time:.0f} s; at most {STABLE_SHARE:g} of it)"
        )


def reduced_elements(scene) -> int:
    """Elements of the reduced optimisation model of a scene (module docstring)."""
    by_length = math.ceil(scene.cable.length / REDUCED_ELEMENT_LENGTH)
    return min(scene.model.elements, max(REDUCED_ELEMENTS, by_length))


def model_elements(scene, elements: int | None) -> tuple[int, list[str]]:
    """The open loop's model elements: those given, else :func:`reduced_elements`, and how.

    Returns
    -------
    (int, list of str)
        The elements and the phrases that say what was derived (none when they were given).
    """
    if elements is not None:
        return elements, []
    elements = reduced_elements(scene)
    return elements, [f"reduced model of {elements} elements"]


def model_step(
    scene,
    elements: int,
    step: float | None,
    unit: float | None,
    cap: float,
    compiled: bool,
    name: str,
    what: str = "at",
) -> tuple[float, list[str]]:
    """The RK4 step of a reduced model (the open loop's or the controller's), and how.

    One derivation for the three resolvers (``optimize``'s two transcriptions and the closed
    loop): the model's RK4 limit along the scene's locked run (:func:`run_limit`); a ``step``
    given is refused above it (:func:`check_step`, naming the setting ``name``); an unset one is
    the largest whole fraction of ``unit`` (s) within :data:`STABLE_SHARE` of it, at most ``cap``
    (s) (:func:`step_within`).

    Parameters
    ----------
    scene : Scene
        The scene whose locked run is linearised (the open loop's, heave compensated).
    elements : int
        Elements of the model.
    step : float or None, s
        The step given, or None to derive it.
    unit : float or None, s
        What the derived step divides (a control interval, the duration, the sample); unused
        when ``step`` is given.
    cap : float, s
        The largest step derived.
    compiled : bool
        Run the locked run compiled.
    name : str
        The setting, as an error names it (``"step"``, ``"model.step"``).
    what : str
        How the phrase introduces the step (``"at"``: "at h = 0.5 s (...)").

    Returns
    -------
    (float, list of str)
        The step (s) and the phrases that say how it was derived (none when it was given).

    Raises
    ------
    ValueError
        A step given above the model's RK4 limit along the locked run.
    """
    limit, at = run_limit(scene, elements, scene.numerics.duration, compiled)
    if step is not None:
        check_step(step, limit, name, "leave it unset to derive one, or give a smaller step")
        return step, []
    step = step_within(limit, unit, cap)
    return step, [StepChoice(step, limit, at).describe(what)]


def control_intervals(duration: float, interval: float = CONTROL_INTERVAL) -> int:
    """Hermite intervals of about ``interval`` (s; :data:`CONTROL_INTERVAL`) over ``duration``."""
    return max(1, round(duration / interval))


def control_grid(duration: float, scene_step: float, interval: float = CONTROL_INTERVAL) -> int:
    """Hermite intervals of a duration (s) whose RK4 steps are ``scene_step`` (s) long.

    The count nearest ``duration / interval`` (:data:`CONTROL_INTERVAL` by default; an adaptive
    grid's finest is finer) that divides the steps, if it is within :data:`GRID_SLACK` of it;
    that count itself otherwise (:func:`on_nodes` then fits the step).
    """
    wanted = control_intervals(duration, interval)
    fitting = intervals_for(duration, scene_step, wanted)
    return fitting if abs(fitting - wanted) <= GRID_SLACK * wanted else wanted


def candidate_split(duration: float, scene_step: float, intervals: int, finest: int) -> int:
    """In how many an adaptive grid's candidates split each default interval: ``finest`` or 1.

    ``finest`` where the scene's RK4 steps (``scene_step``, s) in each of the default grid's
    ``intervals`` over ``duration`` divide by it, so that every candidate is a step end of the
    full model and the first solve, on every ``finest``-th candidate, is on the uniform
    default's grid; 1 otherwise: the candidates are the default grid's nodes. On the
    whole-space scenes of seeds 0 and 1 (2026-12-05), 13 of the 34 with finer candidates had an
    odd number of steps in an interval and took the count nearest ``duration / 2.5 s`` instead:
    their first solve ran on every other candidate (seed 1 case 44: 96 intervals where the
    default grid has 115), and the adaptive Omega came out 1.7 times the uniform one's. The
    candidates' optimisation model derives its own step from their interval
    (:func:`cable_ocp.control.shooting.candidate_settings`), the first solve keeping the default
    grid's. Requiring the default step to split as well (an even number of it in a default
    interval) left finer candidates to 2 of the first 29 whole-space scenes of seeds 0 and 1
    (10 before), and the median parameters of seed 1's first 16 at 106 of 186 (2026-12-06).
    """
    fits = step_count(duration, scene_step) % (finest * intervals) == 0
    return finest if fits else 1


def on_nodes(scene, intervals: int):
    """The scene with its step shortened so that ``intervals`` nodes fall on step ends.

    The full model's runs (the verification, the model correction) then take the largest
    whole fraction of an interval up to ``numerics.step`` whose step count
    ``numerics.output_every`` divides, so that the Hermite acceleration jumps only on step ends
    (inside a step it kicks the bonds).

    Returns
    -------
    (Scene, str)
        The scene (the same one when its steps already fit) and a phrase that says what changed
        (empty when nothing did).
    """
    numerics = scene.numerics
    if step_count(numerics.duration, numerics.step) % intervals == 0:
        return scene, ""
    width = numerics.duration / intervals
    per_interval = math.ceil(width / numerics.step * (1 - 1e-12))
    # The run's samples (numerics.output_every steps apart) must divide its steps too: a
    # 79 s landing took 1584 steps, which 10 does not divide; and a landing's land_time must end
    # a step (a landing of 82 s landing at 22 s was refused at h = 82/1680 s).
    first = per_interval
    while (intervals * per_interval) % numerics.output_every or not _lands_on_a_step(
        scene, width / per_interval
    ):
        per_interval += 1
        if per_interval > FIT_SEARCH * first:
            raise ValueError(
                f"no RK4 step up to numerics.step = {numerics.step:g} s puts the {intervals} "
                f"control nodes and lowering.land_time = {scene.lowering.land_time:g} s on step "
                f"ends: make land_time a multiple of {width:.6g} s"
            )
    step = width / per_interval
    note = (
        f"the full model's runs at h = {step:.6g} s instead of the scene's {numerics.step:g} s, "
        f"so that the {intervals} control nodes ({width:.4g} s apart) fall on step ends"
    )
    return scene.updated({"numerics.step": step}), note


def _lands_on_a_step(scene, step: float) -> bool:
    """Whether a landing scene's ``lowering.land_time`` is a whole number of ``step`` (s)."""
    lowering = scene.lowering
    return lowering is None or whole_steps(lowering.land_time, step) is not None


def run_limit(scene, elements: int, duration: float, compiled: bool = True) -> tuple[float, float]:
    """The RK4 limit (s) of a scene's model of ``elements`` along its locked run, and when (s)."""
    model = CableModel.from_scene(scene, elements)
    drive = Drive.from_scene(scene, winch.locked, elements=elements)
    start = starting_state(model, drive, compiled=compiled)
    return limit_along_run(model, start, drive, duration, compiled=compiled)


def step_within(limit: float, unit: float, cap: float) -> float:
    """The largest whole fraction ``unit / k`` (s) of ``unit`` within the share of ``limit``."""
    target = min(cap, STABLE_SHARE * limit)
    return unit / max(1, math.ceil(unit / target * (1 - 1e-12)))


def check_step(step: float, limit: float, name: str, remedy: str) -> None:
    """Refuse a step the user fixed above the model's RK4 limit (ValueError naming it)."""
    if step > limit:
        raise ValueError(
            f"{name} = {step:g} s is above the RK4 limit of the model it steps, {limit:.3g} s "
            f"along the locked run (the drag's linearisation sets it): {remedy}"
        )


def intervals_for(duration: float, step: float, wanted: int) -> int:
    """Intervals nearest ``wanted`` that divide the ``duration / step`` RK4 steps."""
    steps = step_count(duration, step)
    small = [k for k in range(1, math.isqrt(steps) + 1) if steps % k == 0]
    divisors = small + [steps // k for k in small]
    return min(divisors, key=lambda k: (abs(k - wanted), -k))
