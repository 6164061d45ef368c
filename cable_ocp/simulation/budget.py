"""What a run will cost in memory, estimated from the scene before any work, and the refusal.

Before its first step, a run builds its model: the hanging line's statics and, compiled, the C
library of its right-hand side, whose memory and time grow with the number of elements
(:data:`MODEL_BUILD`, :func:`model_build`; at the schema's 1000 elements, gigabytes).

A simulation streams its RK4 steps (:func:`cable_ocp.simulation.integrate.integrate` calls the
step in chunks of bounded size) and keeps only every ``numerics.output_every``-th state, so its
memory is the kept outputs: the states, the inputs, the joints, the tensions and the clearance
(:class:`~cable_ocp.simulation.trajectory.Trajectory`), about twice over while the run is turned
into a labelled Dataset. An optimiser keeps every RK4 step of its horizon: the states, the
control's basis at the three stage times of every step
(:meth:`cable_ocp.drive.controls.HermiteIntervals.basis`: three dense arrays, plus the array
they are cut from, and the winch map stacked from them), and for Gauss-Newton the stage
Jacobians and the forward sensitivities of every step (:mod:`cable_ocp.control.linearisation`).

:func:`simulation_memory` and :func:`optimisation_memory` give a :class:`MemoryEstimate`;
:func:`check_memory` refuses one that cannot fit in the memory available now, in one line that
names the scene's field to change and the limit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from cable_ocp.model.layout import INPUT_SIZE
from cable_ocp.scene.bathymetry import available_memory

FLOAT = 8  # bytes of a float64
COPIES = 2  # a run's kept outputs are held about twice while they become a Dataset
RK4_STAGE_TIMES = 3  # the control is evaluated at t, t + h/2 and t + h of every step
RK4_STAGES = 4  # stage Jacobians per step
WINCH_INPUTS = 3  # top-element length, its rate and its acceleration
TOUCHED = 8  # parameters whose basis covers one step, at most (4 of a Hermite control), and a spare
# Share of the available memory a run may plan to use: the rest is for the model, CasADi's
# Functions, the interpreter and what else runs on the machine.
USABLE_SHARE = 0.8
# Building a model of n elements before its first step (the statics of the hanging line and, for
# the compiled model, its C library), measured on paper_flat on a loaded 2-core machine (cold
# cache; peak memory of the process and the compiler): (n, bytes, seconds) at two sizes, and
# extrapolated between and beyond them as a power of n (the symbolic statics of the interpreted
# model grow faster than n).
MODEL_BUILD = {
    True: ((100, 0.40e9, 38.0), (300, 0.68e9, 99.0)),  # compiled
    False: ((100, 0.56e9, 37.0), (300, 3.30e9, 257.0)),  # interpreted (SX virtual machine)
}


@dataclass(frozen=True)
class MemoryEstimate:
    """A run's planned memory, by what holds it.

    Attributes
    ----------
    steps : int
        How many RK4 steps the run takes over its duration (a count).
    kept : int
        How many states the run holds at once: its outputs, or every step for an optimiser
        (a count).
    parts : tuple of (str, int), bytes
        Each holder of memory by name (``"states"``, ``"control basis"``, ...) with its size.
    """

    steps: int
    kept: int
    parts: tuple[tuple[str, int], ...]

    @property
    def total(self) -> int:
        """All the parts, bytes."""
        return sum(size for _, size in self.parts)

    @property
    def per_kept(self) -> float:
        """Bytes per kept state (the total over ``kept``)."""
        return self.total / max(self.kept, 1)

    def describe(self) -> str:
        """The total and its largest parts in words, e.g. ``27.6 GB (states 23 GB, ...)``."""
        largest = sorted(self.parts, key=lambda part: -part[1])[:3]
        parts = ", ".join(f"{name} {_gigabytes(size)}" for name, size in largest if size)
        return f"{_gigabytes(self.total)} ({parts})"


def _gigabytes(size: float) -> str:
    return f"{size / 1e9:.3g} GB"


def state_size(scene, elements: int | None = None) -> int:
    """Size of the model's state ``[q; q']``: ``2 dofs (n + 1)`` (5 DOF, 6 with torsion)."""
    n = elements or scene.model.elements
    return 2 * (6 if scene.model.torsion else 5) * (n + 1)


def _steps(scene, step: float | None = None) -> int:
    """RK4 steps over the scene's ``numerics.duration`` at ``step`` (s; default its own)."""
    step = scene.numerics.step if step is None else step
    return max(1, round(scene.numerics.duration / step))


def simulation_memory(scene, elements: int | None = None) -> MemoryEstimate:
    """The memory of :func:`cable_ocp.simulation.run.simulate` on ``scene``, bytes.

    Its steps and outputs are the scene's (``numerics``); ``elements`` is n of the model
    (default: the scene's).
    """
    steps = _steps(scene)
    n = elements or scene.model.elements
    kept = steps // max(scene.numerics.output_every, 1) + 1
    rows = {
        "states": state_size(scene, n),
        "inputs": INPUT_SIZE,
        "joints": 3 * (n + 2),
        "tensions": n + 1,
        "time, winch and clearance": 3,
    }
    parts = tuple((name, COPIES * FLOAT * kept * size) for name, size in rows.items())
    return MemoryEstimate(steps, kept, parts)


def optimisation_memory(
    scene,
    step: float | None = None,
    elements: int | None = None,
    parameters: int | None = None,
) -> MemoryEstimate:
    """The memory of an optimiser's run of the scene's horizon at ``step``, bytes (module doc).

    Parameters
    ----------
    scene : Scene
    step : float, optional, s
        The optimiser's RK4 step (default: the scene's ``numerics.step``).
    elements : int, optional
        Elements n of the optimiser's model (default: the scene's).
    parameters : int, optional
        Winch parameters of the control (default: ``2 winch.knots``, the Hermite angles and
        rates of as many intervals).
    """
    steps = _steps(scene, step)
    nx = state_size(scene, elements)
    size = parameters or 2 * scene.winch.knots
    stage_times = RK4_STAGE_TIMES * steps
    parts = (
        ("states", FLOAT * (steps + 1) * nx),
        ("stage inputs", FLOAT * stage_times * INPUT_SIZE),
        # basis(): the (3, 3K, size) array and its three parts; the winch map stacked from them.
        ("control basis", FLOAT * stage_times * size * (2 * 3 + 3)),
        ("stage Jacobians", FLOAT * steps * RK4_STAGES * (nx + WINCH_INPUTS) * nx),
        # propagate_sensitivities(): the kept sensitivities (K + 1, size, 3) twice (ranked and
        # in order), the forcing of the rows each step touches (K, 4, a few, nx).
        ("sensitivities", FLOAT * (steps + 1) * (2 * size * 3 + RK4_STAGES * TOUCHED * nx)),
    )
    return MemoryEstimate(steps, steps + 1, parts)


def check_memory(
    estimate: MemoryEstimate, field: str, remedy: str, available: int | None = None
) -> None:
    """Refuse a run whose estimate is over the usable memory, in one line naming ``field``.

    Parameters
    ----------
    estimate : MemoryEstimate
    field : str
        What to change, with its value, e.g. ``"numerics.step = 0.0001 s"``.
    remedy : str
        What would make it fit, said after the figures.
    available : int, optional, bytes
        Default: :func:`~cable_ocp.scene.bathymetry.available_memory` now.

    Raises
    ------
    ValueError
        The estimate's total is over ``USABLE_SHARE`` of the available memory.
    """
    available = available_memory() if available is None else available
    limit = USABLE_SHARE * available
    if estimate.total > limit:
        raise ValueError(
            f"{field}: {estimate.steps:.3g} RK4 steps keeping {estimate.kept:.3g} states need "
            f"about {estimate.describe()}, over the limit of {_gigabytes(limit)} "
            f"({USABLE_SHARE:.0%} of the {_gigabytes(available)} available); {remedy}"
        )


def model_build(elements: int, compiled: bool = True) -> tuple[float, float]:
    """Peak memory (bytes) and time (s) of building a model of ``elements`` (:data:`MODEL_BUILD`).

    Parameters
    ----------
    elements : int
        Elements n of the model.
    compiled : bool
        The model compiled to C (else CasADi's SX virtual machine).
    """
    (n0, bytes0, seconds0), (n1, bytes1, seconds1) = MODEL_BUILD[compiled]
    ratio = math.log(elements / n0) / math.log(n1 / n0)
    return bytes0 * (bytes1 / bytes0) ** ratio, seconds0 * (seconds1 / seconds0) ** ratio


def _most_elements(compiled: bool, limit: float) -> int:
    """The most elements whose model builds within ``limit`` bytes (at least 1)."""
    (n0, bytes0, _), (n1, bytes1, _) = MODEL_BUILD[compiled]
    power = math.log(bytes1 / bytes0) / math.log(n1 / n0)
    return max(1, int(n0 * (limit / bytes0) ** (1 / power)))


def check_simulation_memory(
    scene,
    elements: int | None = None,
    available: int | None = None,
    compiled: bool = True,
) -> None:
    """Refuse a simulation of ``scene`` that cannot fit in memory, naming the fields, before work.

    First its kept outputs: the remedy names the smallest ``numerics.output_every`` that fits
    (the steps themselves are streamed), or a longer ``numerics.step`` / shorter
    ``numerics.duration``. Then the building of its model (:func:`model_build`): the remedy
    names the most ``model.elements`` that fit, and the compiled model for an interpreted run.

    Parameters
    ----------
    scene : Scene
    elements : int, optional
        Elements n of the model that runs (default: the scene's).
    available : int, optional, bytes
        Default: the memory available now.
    compiled : bool
        The run's model is compiled to C (else interpreted).

    Raises
    ------
    ValueError
        See :func:`check_memory`; or the model's build, with its estimate (bytes and seconds).
    """
    available = available_memory() if available is None else available
    _check_outputs(scene, elements, available)
    n = elements or scene.model.elements
    size, seconds = model_build(n, compiled)
    limit = USABLE_SHARE * available
    if size > limit:
        model = "compiled" if compiled else "interpreted"
        other = "" if compiled else ", or the compiled model (not --interpreted)"
        raise ValueError(
            f"model.elements = {n}: building the {model} model (its statics"
            f"{' and C library' if compiled else ''}) needs about {_gigabytes(size)} and "
            f"{seconds:.3g} s, over the limit of {_gigabytes(limit)} ({USABLE_SHARE:.0%} of the "
            f"{_gigabytes(available)} available); model.elements = "
            f"{_most_elements(compiled, limit)} or fewer fits{other}"
        )


def _check_outputs(scene, elements: int | None, available: int) -> None:
    """The kept outputs' check of :func:`check_simulation_memory`."""
    numerics = scene.numerics
    estimate = simulation_memory(scene, elements=elements)
    fits = int(USABLE_SHARE * available / estimate.per_kept)
    every = -(-estimate.steps // max(fits - 1, 1))
    while estimate.steps % every:  # the smallest divisor of the steps that fits
        every += 1
    check_memory(
        estimate,
        f"numerics.output_every = {numerics.output_every} (numerics.step = {numerics.step!r} "
        f"s, numerics.duration = {numerics.duration!r} s)",
        f"keep at most {fits:.3g} states: numerics.output_every = {every} or more (dividing the "
        f"{estimate.steps} steps), or a longer numerics.step or a shorter numerics.duration",
        available,
    )
