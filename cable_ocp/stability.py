"""Stability study: RK4 step limits, Baumgarte gains, knots, the Euler-angle singularity.

Issue "stability study" (DESIGN.md §5, §9). Four parts, each a function returning a frozen
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
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from cable_ocp.drive import Drive
from cable_ocp.integrate import SimulationError
from cable_ocp.model import CableModel
from cable_ocp.nelder_mead import NelderMeadSettings
from cable_ocp.ocp import IpoptSettings
from cable_ocp.optimization import optimize_ipopt, optimize_nelder_mead
from cable_ocp.output import atomic_directory
from cable_ocp.scene import load_scene
from cable_ocp.simulation import simulate
from cable_ocp.statics import equilibrium
from cable_ocp.studies import end_difference
from cable_ocp.trajectory import Trajectory

# The end_force scene's push (10 kN along x ramped over 15 s, 5 kN sine along y) from t = 0.
PUSH = {"end.force_start": 0.0}
# The same push ramped up over 1 s: a violent start, for the Baumgarte drift.
SHARP_PUSH = {**PUSH, "end.force_ramp": 1.0}
# A twist angle beyond this (rad) marks a torsional blow-up: the push exerts no torque.
TWIST_LIMIT = math.pi
# Random initial twist (rad) of torsion models, so that an unstable torsional mode can grow.
TWIST_SEED = 1e-6
# |R(h lambda)| of RK4 may exceed its bound by this much (rounding) and count as stable.
GROWTH_SLACK = 1e-6


def table_cell(text: str) -> str:
    """Text safe inside a markdown table cell (``|`` escaped)."""
    return text.replace("|", "\\|")


# ----------------------------------------------------------------------------------------------
# Largest stable step
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StableStep:
    """The largest stable RK4 step of one model, found by bisection in ``log h``.

    Attributes
    ----------
    elements : int
        ``n``.
    torsion : bool
    step : float, s
        Largest step found stable: its run completes.
    unstable_step : float, s
        Smallest step found unstable (``step < unstable_step <= resolution * step``).
    duration : float, s
        Length of the run at ``step``.
    runs : int
        Runs made (bracketing and bisection).
    quarter_step_difference : float, m
        ``max_t |r_E(step) - r_E(step / 4)|``: small if the stable run is also accurate.
    end_excursion : float, m
        Largest distance of the end from its start in the run at ``step / 4``.
    failure : str
        Why the run at ``unstable_step`` is unstable.
    linearised_step : float, s
        Largest step at which RK4 is stable for the linearisations at states of the run at
        ``step`` (the smallest over the states sampled).
    compiled : bool
        Whether the runs used the model compiled to C.
    wall_time : float, s
    """

    elements: int
    torsion: bool
    step: float
    unstable_step: float
    duration: float
    runs: int
    quarter_step_difference: float
    end_excursion: float
    failure: str
    linearised_step: float
    compiled: bool
    wall_time: float


def pushed_scene(scene, elements: int, torsion: bool, push: dict = PUSH):
    """The scene with ``elements``, ``torsion`` and a push (scene overrides, :data:`PUSH`).

    The top-element length bounds are widened to admit ``Delta/2`` of this ``n`` (locked winch).
    """
    half = scene.cable.length / elements / 2
    return scene.updated(
        {
            **push,
            "model.elements": elements,
            "model.torsion": torsion,
            "winch.top_length_min": min(scene.winch.top_length_min, half),
            "winch.top_length_max": max(scene.winch.top_length_max, half),
        }
    )


def run_length(step: float, duration: float, min_steps: int) -> float:
    """Duration of a stability run (s): at least ``duration`` and ``min_steps`` steps of ``step``.

    Just above the RK4 limit a mode grows by a factor of about 1.2-2 per step, so ``min_steps``
    steps take rounding noise beyond the bond tolerance even where ``duration`` holds few steps.
    """
    return max(math.ceil(duration / step - 1e-9), min_steps) * step


def rk4_growth(z: np.ndarray) -> np.ndarray:
    """``|R(z)|`` of classical RK4, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``."""
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def linearised_step(model: CableModel, x: np.ndarray, u: np.ndarray, relative: float = 1e-7):
    """Largest RK4 step (s) stable for the linearisation of the model at ``(x, u)``.

    The Jacobian of the right-hand side is taken by forward differences (one batched call;
    building it symbolically takes minutes at n = 100). For each eigenvalue ``lambda`` the largest
    ``h`` with ``|R(h lambda)| <= max(1, |exp(h lambda)|)`` is found by bisection, and the smallest
    is returned: RK4 may grow no faster than the exact solution, so the slow modes that the
    differences leave slightly in the right half-plane do not count as unstable.

    Parameters
    ----------
    model : CableModel
    x : array (state_size,)
    u : array (15,)
    relative : float
        Difference step, relative to ``max(1, |x_j|)``.
    """
    size = model.state_size
    steps = relative * np.maximum(1.0, np.abs(x))
    probes = np.hstack([x[:, None], x[:, None] + np.diag(steps)])
    values = np.array(model.rhs.map(size + 1)(probes, np.tile(u[:, None], (1, size + 1))))
    eigenvalues = np.linalg.eigvals((values[:, 1:] - values[:, :1]) / steps)
    eigenvalues = eigenvalues[np.abs(eigenvalues) > 0]
    # The RK4 region lies inside |z| < 3, so h = 3 / |lambda| is unstable for every lambda.
    low, high = np.zeros(eigenvalues.size), 3.0 / np.abs(eigenvalues)
    for _ in range(60):
        middle = (low + high) / 2
        z = middle * eigenvalues
        stable = rk4_growth(z) <= np.maximum(1.0, np.exp(z.real)) + GROWTH_SLACK
        low, high = np.where(stable, middle, low), np.where(stable, high, middle)
    return float(low.min())


class _Runner:
    """Runs of one model from its equilibrium at any step (model and equilibrium built once).

    Torsion models get a random twist of ``twist_seed`` rad per element: the push exerts no
    torque, so without a seed the twist stays exactly zero and an unstable torsional mode never
    shows.
    """

    def __init__(self, scene, compiled: bool, quiet: bool, twist_seed: float):
        self.scene, self.compiled, self.quiet = scene, compiled, quiet
        self.model = CableModel.from_scene(scene)
        self.drive = Drive.from_scene(scene)
        self.x0 = equilibrium(self.model, self.drive)
        if scene.model.torsion:
            twist = self.model.twist_angle_index()
            rng = np.random.default_rng(0)
            self.x0[twist] += twist_seed * rng.standard_normal(self.x0[twist].size)

    def run(self, step: float, duration: float, output_every: int = 1) -> Trajectory:
        """The run at ``step`` over ``duration`` (raises :class:`SimulationError`)."""
        local = self.scene.updated(
            {
                "numerics.step": step,
                "numerics.duration": duration,
                "numerics.output_every": output_every,
            }
        )
        return simulate(
            local, model=self.model, initial_state=self.x0, quiet=self.quiet, compiled=self.compiled
        )

    def attempt(self, step: float, duration: float) -> Trajectory | str:
        """The run at ``step``, or why it is unstable.

        Unstable: :class:`SimulationError`, or a twist angle beyond :data:`TWIST_LIMIT`. The twist
        does not move the element axes, so a torsional blow-up leaves the bonds intact and stays
        finite for many steps: the integrator's own checks do not see it.
        """
        try:
            run = self.run(step, duration)
        except SimulationError as error:
            return str(error)
        if self.scene.model.torsion:
            twist = np.abs(run.states[:, self.model.twist_angle_index()]).max(axis=1)
            beyond = twist > TWIST_LIMIT
            if beyond.any():
                k = int(np.argmax(beyond))
                return (
                    f"twist angle {twist[k]:.3g} rad beyond {TWIST_LIMIT:g} rad at "
                    f"t = {run.time[k]:.6g} s with step h = {step:g} s (torsional mode unstable)"
                )
        return run


def largest_stable_step(
    scene,
    elements: int,
    torsion: bool,
    first_step: float | None = None,
    duration: float = 10.0,
    min_steps: int = 200,
    resolution: float = 1.1,
    tolerance: float = 1.0,
    twist_seed: float = TWIST_SEED,
    linearised_samples: int = 5,
    compiled: bool = False,
    quiet: bool = True,
) -> StableStep:
    """Largest RK4 step at which a pushed run of the scene stays stable (bisection in ``log h``).

    A run is stable if :func:`cable_ocp.simulation.simulate` completes without
    :class:`SimulationError` (non-finite state, or a bond residual beyond ``tolerance``) and, with
    torsion, no twist angle exceeds :data:`TWIST_LIMIT`. From ``first_step`` the step is doubled
    (or halved) until a stable and an unstable step bracket the limit; the bracket is then bisected
    in ``log h`` until its ratio is below ``resolution``. The stable end is compared with a run at
    a quarter of its step, so that a run that completes but is wrong shows up.

    Parameters
    ----------
    scene : Scene
        Usually ``end_force``; it is pushed from ``t = 0`` (:func:`pushed_scene`).
    elements : int
    torsion : bool
    first_step : float, optional, s
        Where the search starts (the scene's step by default).
    duration : float, s
        Shortest run; see :func:`run_length` for ``min_steps``.
    min_steps : int
    resolution : float
        Largest ratio ``unstable_step / step`` at the end (> 1).
    tolerance : float, m
        Bond residual that stops a run. The scene's own (0.1 mm for end_force) is an accuracy
        bound: at large steps the push alone exceeds it, and so would 1 cm at n = 5, so the
        search would measure accuracy, not stability. A blow-up passes any bound within a few
        steps; whether the stable run is also accurate is ``quarter_step_difference``.
    twist_seed : float, rad
        Random initial twist per element of a torsion model (see :class:`_Runner`).
    linearised_samples : int
        States of the stable run (evenly spaced, first and last included) at which
        :func:`linearised_step` is evaluated; the smallest is reported. The push raises the
        tension, and with it the frequencies, above those of the equilibrium.
    compiled : bool
        Integrate with the model compiled to C (for n >= 10 the right-hand side is compiled once
        for all steps; worth it when the runs are long).
    quiet : bool

    Returns
    -------
    StableStep
    """
    if resolution <= 1:
        raise ValueError(f"resolution = {resolution}: must be > 1")
    started = time.perf_counter()
    local = pushed_scene(scene, elements, torsion).updated(
        {"numerics.constraint_tolerance": tolerance}
    )
    runner = _Runner(local, compiled, quiet, twist_seed)
    trials: dict[float, Trajectory | str] = {}

    def stable(step: float) -> bool:
        trials[step] = runner.attempt(step, run_length(step, duration, min_steps))
        return not isinstance(trials[step], str)

    step = first_step or scene.numerics.step
    if stable(step):
        low, high = step, 2 * step
        while stable(high):
            low, high = high, 2 * high
    else:
        low, high = step / 2, step
        while not stable(low):
            low, high = low / 2, low
    while high / low > resolution:
        middle = math.sqrt(low * high)
        if stable(middle):
            low = middle
        else:
            high = middle
    coarse = trials[low]
    quarter = runner.run(low / 4, coarse.time[-1], output_every=4)
    samples = np.linspace(0, coarse.time.size - 1, linearised_samples).round().astype(int)
    return StableStep(
        elements=elements,
        torsion=torsion,
        step=low,
        unstable_step=high,
        duration=float(coarse.time[-1]),
        runs=len(trials),
        quarter_step_difference=end_difference(coarse, quarter),
        end_excursion=float(np.linalg.norm(quarter.end - quarter.end[0], axis=1).max()),
        failure=trials[high],
        linearised_step=min(
            linearised_step(runner.model, x, u)
            for x, u in zip(coarse.states[samples], coarse.inputs[samples], strict=True)
        ),
        compiled=compiled,
        wall_time=time.perf_counter() - started,
    )


def power_law(elements: Sequence[int], steps: Sequence[float]) -> tuple[float, float]:
    """Least-squares fit ``h = c n^slope`` in log-log: returns ``(slope, c)`` (c in s)."""
    slope, intercept = np.polyfit(np.log(elements), np.log(steps), 1)
    return float(slope), float(np.exp(intercept))


@dataclass(frozen=True)
class StepLimits:
    """Largest stable steps for several ``n``, with and without torsion.

    Attributes
    ----------
    results : tuple of StableStep
    tolerance : float, m
        Bond residual that stopped a run.
    """

    results: tuple[StableStep, ...]
    tolerance: float

    def of(self, torsion: bool) -> tuple[StableStep, ...]:
        """The results with or without torsion."""
        return tuple(r for r in self.results if r.torsion == torsion)

    def fit(self, torsion: bool) -> tuple[float, float]:
        """``(slope, c)`` of ``h_max = c n^slope`` (c in s); NaN with fewer than two ``n``."""
        chosen = self.of(torsion)
        if len(chosen) < 2:
            return float("nan"), float("nan")
        return power_law([r.elements for r in chosen], [r.step for r in chosen])

    def table(self) -> str:
        """Markdown table of the limits, the fitted slopes and the accuracy check."""
        lines = [
            "| torsion | n | h_max [s] | first unstable h [s] | linearised limit [s] | run [s] "
            "| runs | max end diff vs h_max/4 [m] | end excursion [m] | compiled | wall [s] |",
            "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|",
        ]
        for r in self.results:
            lines.append(
                f"| {'yes' if r.torsion else 'no'} | {r.elements} | {r.step:.4g} "
                f"| {r.unstable_step:.4g} | {r.linearised_step:.4g} | {r.duration:.4g} | {r.runs} "
                f"| {r.quarter_step_difference:.3g} | {r.end_excursion:.3g} "
                f"| {'yes' if r.compiled else 'no'} | {r.wall_time:.1f} |"
            )
        lines.append("")
        for torsion in (False, True):
            slope, c = self.fit(torsion)
            if math.isfinite(slope):
                lines.append(
                    f"- {'with' if torsion else 'without'} torsion: h_max = {c:.3g} s "
                    f"n^{slope:.2f} (least squares in log-log)"
                )
        lines.append("")
        lines.append("Why the largest unstable step failed:")
        lines.append("")
        lines += [
            f"- {'torsion' if r.torsion else 'no torsion'}, n = {r.elements}: {r.failure}"
            for r in self.results
        ]
        return "\n".join(lines)

    def chart(self, path=None):
        """Log-log chart of ``h_max`` against ``n`` with the fitted power laws."""
        import matplotlib.pyplot as plt
        from matplotlib.ticker import NullLocator

        fig, ax = plt.subplots(figsize=(10, 4.5))
        for torsion, colour in ((False, "tab:blue"), (True, "tab:red")):
            chosen = self.of(torsion)
            if not chosen:
                continue
            n = np.array([r.elements for r in chosen])
            label = "with torsion" if torsion else "without torsion"
            ax.loglog(n, [r.step for r in chosen], "o", color=colour, label=f"{label}: bisection")
            ax.loglog(
                n,
                [r.linearised_step for r in chosen],
                "x",
                color=colour,
                ms=9,
                label=f"{label}: linearised (smallest over the run)",
            )
            slope, c = self.fit(torsion)
            if math.isfinite(slope):
                grid = np.geomspace(n.min(), n.max(), 50)
                ax.loglog(
                    grid, c * grid**slope, "--", color=colour, label=f"fit: {c:.3g} s n^{slope:.2f}"
                )
        free = self.of(False)
        if free:
            n = np.array([r.elements for r in free])
            ax.loglog(n, free[0].step * (n / n[0]) ** -2.0, ":", color="grey", label="1/n^2 guide")
        all_n = sorted({r.elements for r in self.results})
        ax.set_xticks(all_n, [str(k) for k in all_n])
        ax.xaxis.set_minor_locator(NullLocator())
        ax.set_xlabel("elements n")
        ax.set_ylabel("largest stable RK4 step h_max [s]")
        ax.set_title("RK4 stability limit (end_force scene, pushed from t = 0)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0))
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
            plt.close(fig)
        return fig


def step_limits(
    scene,
    elements: Sequence[int],
    torsion_elements: Sequence[int],
    duration: float = 10.0,
    torsion_duration: float = 1.0,
    min_steps: int = 200,
    resolution: float = 1.1,
    tolerance: float = 1.0,
    linearised_samples: int = 5,
    compile_from: int | None = None,
    quiet: bool = True,
) -> StepLimits:
    """:func:`largest_stable_step` for each ``n``: ``elements`` without, ``torsion_elements`` with.

    Each search starts from the limit found at the previous ``n`` (the limit falls with ``n``),
    the first from the scene's step. Torsion runs are shorter (``torsion_duration``): their steps
    are tiny. Models with at least ``compile_from`` elements are compiled to C (None: none).
    """
    results = []
    for torsion, chosen, length in (
        (False, elements, duration),
        (True, torsion_elements, torsion_duration),
    ):
        previous = None
        for n in chosen:
            result = largest_stable_step(
                scene,
                n,
                torsion,
                first_step=previous,
                duration=length,
                min_steps=min_steps,
                resolution=resolution,
                tolerance=tolerance,
                linearised_samples=linearised_samples,
                compiled=compile_from is not None and n >= compile_from,
                quiet=quiet,
            )
            results.append(result)
            previous = result.step
    return StepLimits(tuple(results), tolerance)


# ----------------------------------------------------------------------------------------------
# Baumgarte gains
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class GainRun:
    """One run of the drift study.

    Attributes
    ----------
    alpha, beta : float, 1/s
    time : array (k,), s
        Output times (empty if the run was stopped).
    residual : array (k,), m
        ``max_j |Phi_j|`` at each output time.
    end_difference : float, m
        ``max_t |r_E - r_E(reference)|`` (NaN if stopped).
    failure : str
        Why the run was stopped; empty if it completed.
    """

    alpha: float
    beta: float
    time: np.ndarray
    residual: np.ndarray
    end_difference: float
    failure: str = ""

    @property
    def label(self) -> str:
        """``(alpha, beta)`` as text, marking the default and no stabilisation."""
        text = f"(alpha, beta) = ({self.alpha:g}, {self.beta:g})"
        if self.alpha == 0 and self.beta == 0:
            return f"{text}, none"
        return text


def bond_residuals(model: CableModel, run: Trajectory) -> np.ndarray:
    """Largest bond residual ``max_j |Phi_j|`` (m) at each output time of a run."""
    residual = model.outputs.map(run.time.size)(run.states.T, run.inputs.T)[2]
    return np.abs(np.array(residual)).max(axis=0)


@dataclass(frozen=True)
class BaumgarteDrift:
    """Bond drift and end error for several Baumgarte gains at one step.

    Attributes
    ----------
    elements : int
    step : float, s
    reference_step : float, s
        Step of the reference run (default gains of the scene).
    duration : float, s
    reference_gains : tuple of float, 1/s
    runs : tuple of GainRun
    """

    elements: int
    step: float
    reference_step: float
    duration: float
    reference_gains: tuple[float, float]
    runs: tuple[GainRun, ...]

    def table(self) -> str:
        """Markdown table: largest and final residual, end error, or why the run stopped."""
        lines = [
            f"end_force scene, push from t = 0 ramped over 1 s, n = {self.elements}, "
            f"h = {self.step:g} s, {self.duration:g} s; reference: (alpha, beta) = "
            f"{self.reference_gains} at h = {self.reference_step:g} s",
            "",
            "| alpha [1/s] | beta [1/s] | max abs(Phi) [m] | final abs(Phi) [m] "
            "| max end diff vs reference [m] | stopped |",
            "|---:|---:|---:|---:|---:|---|",
        ]
        for r in self.runs:
            if r.failure:
                lines.append(f"| {r.alpha:g} | {r.beta:g} | - | - | - | {table_cell(r.failure)} |")
            else:
                lines.append(
                    f"| {r.alpha:g} | {r.beta:g} | {r.residual.max():.3g} | {r.residual[-1]:.3g} "
                    f"| {r.end_difference:.3g} | no |"
                )
        return "\n".join(lines)

    def chart(self, path=None):
        """Residual against time per gain (log scale), and residual and end error per gain."""
        import matplotlib.pyplot as plt

        fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
        for r in self.runs:
            if r.failure:
                left.plot([], [], " ", label=f"{r.label}: stopped (see table)")
            else:
                default = (r.alpha, r.beta) == self.reference_gains
                label = f"{r.label}, scene default" if default else r.label
                left.semilogy(r.time[1:], np.maximum(r.residual[1:], 1e-16), label=label)
        left.set_xlabel("t [s]")
        left.set_ylabel("max bond residual |Phi| [m]")
        left.set_title(f"constraint drift, n = {self.elements}, h = {self.step:g} s")
        left.grid(alpha=0.3, which="both")
        left.legend(fontsize=7)

        done = [r for r in self.runs if not r.failure]
        positions = np.arange(len(done))
        right.bar(positions - 0.2, [r.residual.max() for r in done], 0.4, label="max |Phi|")
        right.bar(
            positions + 0.2,
            [r.end_difference for r in done],
            0.4,
            label=f"max end diff vs reference (h = {self.reference_step:g} s)",
        )
        right.set_yscale("log")
        right.set_xticks(positions, [f"({r.alpha:g}, {r.beta:g})" for r in done])
        right.set_xlabel("Baumgarte gains (alpha, beta) [1/s]")
        right.set_ylabel("[m]")
        right.set_title("drift and accuracy per gain (completed runs)")
        right.grid(alpha=0.3, which="both", axis="y")
        right.legend(fontsize=8)
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
            plt.close(fig)
        return fig


def baumgarte_drift(
    scene,
    gains: Sequence[tuple[float, float]],
    elements: int = 15,
    step: float = 0.05,
    reference_step: float = 0.005,
    duration: float = 30.0,
    quiet: bool = True,
) -> BaumgarteDrift:
    """Bond residual over time and end error for each ``(alpha, beta)`` of ``gains``.

    The scene (usually end_force) is pushed sharply (:data:`SHARP_PUSH`). Its
    ``numerics.constraint_tolerance`` is raised to the cable length, so that only a blow-up stops
    a run (its message, with the time, is kept); the reference uses the scene's own gains at
    ``reference_step``.
    """
    base = pushed_scene(scene, elements, scene.model.torsion, SHARP_PUSH).updated(
        {
            "numerics.duration": duration,
            "numerics.constraint_tolerance": scene.cable.length,
            "numerics.output_every": 1,
        }
    )
    every = max(1, round(step / reference_step))
    reference = simulate(
        base.updated({"numerics.step": step / every, "numerics.output_every": every}), quiet=quiet
    )
    runs = []
    for alpha, beta in gains:
        local = base.updated(
            {
                "numerics.step": step,
                "numerics.baumgarte_alpha": alpha,
                "numerics.baumgarte_beta": beta,
            }
        )
        model = CableModel.from_scene(local)
        try:
            run = simulate(local, model=model, quiet=quiet)
        except SimulationError as error:
            empty = np.zeros(0)
            runs.append(GainRun(alpha, beta, empty, empty, float("nan"), str(error)))
            continue
        runs.append(
            GainRun(
                alpha, beta, run.time, bond_residuals(model, run), end_difference(run, reference)
            )
        )
    numerics = scene.numerics
    return BaumgarteDrift(
        elements=elements,
        step=step,
        reference_step=step / every,
        duration=duration,
        reference_gains=(numerics.baumgarte_alpha, numerics.baumgarte_beta),
        runs=tuple(runs),
    )


# ----------------------------------------------------------------------------------------------
# Nelder-Mead against IPOPT in the number of knots
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class KnotRun:
    """One optimisation of the knots study.

    Attributes
    ----------
    knots : int
    method : str
        ``"ipopt"`` or ``"nelder-mead"``.
    omega : float, m
        Verified on the scene's full model (NaN if the last iterate cannot be simulated).
    omega_model : float, m
        On the optimisation model.
    success : bool
    status : str
    iterations : int
    evaluations : int
    wall_time : float, s
    history : tuple of float
        Nelder-Mead: best Omega after each evaluation (m); IPOPT: Omega^2 per iteration (m^2).
    """

    knots: int
    method: str
    omega: float
    omega_model: float
    success: bool
    status: str
    iterations: int
    evaluations: int
    wall_time: float
    history: tuple[float, ...]

    def evaluations_to_within(self, fraction: float) -> int:
        """Evaluations until the best Omega came within ``fraction`` of its last value."""
        history = np.asarray(self.history)
        return int(np.argmax(history <= history[-1] * (1 + fraction))) + 1


@dataclass(frozen=True)
class KnotsComparison:
    """IPOPT (spline control) and Nelder-Mead for several numbers of knots.

    Attributes
    ----------
    scene_name : str
    duration : float, s
    elements : int
        Elements of the optimisation model (Omega verified on the scene's own).
    step : float, s
        RK4 step of the optimisation model.
    evaluation_cap : int
        Nelder-Mead's ``max_evaluations``.
    iteration_cap : int
        IPOPT's ``max_iter``.
    refinements : int
        Model-correction solves after the first of the ``"ipopt + correction"`` runs.
    runs : tuple of KnotRun
    progress_fraction : float
        "Within this fraction of the final best Omega" marks where Nelder-Mead stopped gaining.
    """

    scene_name: str
    duration: float
    elements: int
    step: float
    evaluation_cap: int
    iteration_cap: int
    refinements: int
    runs: tuple[KnotRun, ...]
    progress_fraction: float = 0.01

    def table(self) -> str:
        """Markdown table of both methods per number of knots."""
        percent = f"{100 * self.progress_fraction:g} %"
        lines = [
            f"{self.scene_name}, T = {self.duration:g} s; optimisation model n = {self.elements}, "
            f"h = {self.step:g} s; Omega verified on the scene's model. Nelder-Mead capped at "
            f"{self.evaluation_cap} evaluations, IPOPT at {self.iteration_cap} iterations per "
            "solve. `ipopt` and `nelder-mead` minimise the same reduced-model objective, so "
            "'Omega on opt. model' compares the optimisers; their verified Omega also carries "
            "the reduced model's bias. `ipopt + correction` (the front door's default) adds up "
            f"to {self.refinements} model-correction solves against the scene's model. IPOPT's "
            "evaluations are its iterations + 1 per solve.",
            "",
            "| knots | method | Omega verified [m] | Omega on opt. model [m] | success | status "
            f"| iterations | evaluations | evaluations to within {percent} of final | wall [s] |",
            "|---:|---|---:|---:|---|---|---:|---:|---:|---:|",
        ]
        for r in self.runs:
            searching = r.method == "nelder-mead" and r.history
            within = r.evaluations_to_within(self.progress_fraction) if searching else "-"
            lines.append(
                f"| {r.knots} | {r.method} | {r.omega:.3g} | {r.omega_model:.3g} | {r.success} "
                f"| {table_cell(r.status)} | {r.iterations} | {r.evaluations} | {within} "
                f"| {r.wall_time:.1f} |"
            )
        return "\n".join(lines)

    def chart(self, path=None):
        """Nelder-Mead's best Omega per evaluation, and Omega and wall time against knots."""
        import matplotlib.pyplot as plt
        from matplotlib.ticker import NullLocator

        fig, (history, quality, cost) = plt.subplots(1, 3, figsize=(15, 4.5))
        knots = sorted({r.knots for r in self.runs})
        colours = dict(zip(knots, plt.cm.viridis(np.linspace(0, 0.85, len(knots))), strict=True))
        for r in self.runs:
            if r.method == "nelder-mead" and r.history:
                history.semilogy(
                    np.arange(1, len(r.history) + 1),
                    r.history,
                    color=colours[r.knots],
                    label=f"Nelder-Mead, p = {r.knots}",
                )
            elif r.method == "ipopt" and math.isfinite(r.omega_model):
                history.axhline(
                    r.omega_model,
                    color=colours[r.knots],
                    ls="--",
                    lw=1,
                    label=f"IPOPT, p = {r.knots} (final)",
                )
        history.set_xlabel("objective evaluations")
        history.set_ylabel("best Omega on the optimisation model [m]")
        history.set_title("Nelder-Mead progress")
        history.grid(alpha=0.3, which="both")
        history.legend(fontsize=7)

        styles = (
            ("ipopt", "o", "tab:blue"),
            ("ipopt + correction", "^", "tab:green"),
            ("nelder-mead", "s", "tab:orange"),
        )
        for method, marker, colour in styles:
            chosen = [r for r in self.runs if r.method == method]
            failed = [r for r in chosen if not r.success]
            for axis, value in ((quality, "omega"), (cost, "wall_time")):
                axis.plot(
                    [r.knots for r in chosen],
                    [getattr(r, value) for r in chosen],
                    marker + "-",
                    color=colour,
                    label=method,
                )
                axis.plot(
                    [r.knots for r in failed],
                    [getattr(r, value) for r in failed],
                    marker,
                    ls="none",
                    mfc="white",
                    mec=colour,
                )
        quality.plot([], [], "o", mfc="white", mec="grey", ls="none", label="hollow: not converged")
        for axis, title, ylabel in (
            (quality, "verified Omega", "Omega on the scene's model [m]"),
            (cost, "wall time", "wall time [s]"),
        ):
            axis.set_xscale("log", base=2)
            axis.set_yscale("log")
            axis.set_xticks(knots, [str(k) for k in knots])
            axis.xaxis.set_minor_locator(NullLocator())
            axis.set_xlabel("knots p")
            axis.set_ylabel(ylabel)
            axis.set_title(title)
            axis.grid(alpha=0.3, which="both")
            axis.legend(fontsize=8)
        fig.tight_layout()
        if path is not None:
            fig.savefig(path, dpi=120)
            plt.close(fig)
        return fig


def _knot_run(knots: int, method: str, result) -> KnotRun:
    return KnotRun(
        knots=knots,
        method=method,
        omega=result.omega,
        omega_model=result.omega_model,
        success=result.success,
        status=result.status,
        iterations=result.iterations,
        evaluations=result.evaluations,
        wall_time=result.wall_time,
        history=tuple(result.history),
    )


def knots_comparison(
    scene,
    knots: Sequence[int] = (7, 14, 28, 56),
    elements: int = 3,
    step: float = 0.5,
    max_evaluations: int = 600,
    max_iter: int = 300,
    refinements: int = 3,
    compiled: bool = True,
    quiet: bool = True,
) -> KnotsComparison:
    """IPOPT with the paper's spline control and Nelder-Mead, for each number of knots.

    Both optimise on a reduced model (``elements``, ``step``) as the front door's defaults do,
    and so minimise the same objective (methods ``"ipopt"``, ``"nelder-mead"``). With
    ``refinements > 0`` IPOPT is also run with that many model-correction solves against the
    scene's model (``"ipopt + correction"``, see :func:`cable_ocp.optimization.optimize_ipopt`).
    ``compiled``: the optimisers simulate with the RK4 step compiled to C (cached on disk). A
    failed solve is kept with its status.
    """
    runs = []
    for p in knots:
        local = scene.updated({"winch.knots": p})
        ipopt = IpoptSettings(
            elements=elements, step=step, control="spline", max_iter=max_iter, compiled=compiled
        )
        plain = optimize_ipopt(local, ipopt, refinements=0, quiet=quiet)
        runs.append(_knot_run(p, "ipopt", plain))
        if refinements > 0:
            corrected = optimize_ipopt(local, ipopt, refinements=refinements, quiet=quiet)
            runs.append(_knot_run(p, "ipopt + correction", corrected))
        search = NelderMeadSettings(
            elements=elements, step=step, max_evaluations=max_evaluations, compiled=compiled
        )
        runs.append(_knot_run(p, "nelder-mead", optimize_nelder_mead(local, search, quiet=quiet)))
    return KnotsComparison(
        scene_name=scene.name,
        duration=scene.numerics.duration,
        elements=elements,
        step=step,
        evaluation_cap=max_evaluations,
        iteration_cap=max_iter,
        refinements=refinements,
        runs=tuple(runs),
    )


# ----------------------------------------------------------------------------------------------
# Euler-angle singularity
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class SingularCase:
    """What was tried with a singular state, and what the toolkit answered.

    Attributes
    ----------
    tried : str
    rejected : bool
    message : str
    """

    tried: str
    rejected: bool
    message: str


def singular_states(scene, element: int = 2) -> tuple[SingularCase, ...]:
    """Simulate from the scene's equilibrium with ``theta_element = +-pi/2`` (along +-y).

    Returns
    -------
    tuple of SingularCase
        One per sign; ``rejected`` is False if the run went ahead (it must not).
    """
    model = CableModel.from_scene(scene)
    x0 = equilibrium(model, Drive.from_scene(scene))
    cases = []
    for sign, name in ((1, "+"), (-1, "-")):
        x = x0.copy()
        x[model.state_names.index(f"theta_{element}")] = sign * np.pi / 2
        tried = (
            f"simulate {scene.name} (n = {model.spec.elements}) from its equilibrium with "
            f"theta_{element} = {name}pi/2 (element {element} along {name}y)"
        )
        try:
            simulate(scene, model=model, initial_state=x)
        except (ValueError, SimulationError) as error:
            cases.append(SingularCase(tried, True, f"{type(error).__name__}: {error}"))
        else:
            cases.append(SingularCase(tried, False, "no error: the run went ahead"))
    return tuple(cases)


# ----------------------------------------------------------------------------------------------
# The whole study
# ----------------------------------------------------------------------------------------------
@dataclass(frozen=True)
class StabilitySettings:
    """Sizes of the study (see the functions of each part for the meaning).

    Attributes
    ----------
    elements, torsion_elements : tuple of int
        ``n`` of the step limits without and with torsion.
    duration, torsion_duration : float, s
        Shortest stability run without and with torsion. Without torsion it covers the push's
        ramp (15 s in end_force), since the rising tension raises the frequencies; torsion runs
        are short for cost (the twist modes do not depend on the push).
    min_steps : int
    resolution : float
    tolerance : float, m
    linearised_samples : int
    compile_from : int or None
    drift_elements : int
    drift_step, drift_reference_step, drift_duration : float, s
    gains : tuple of (alpha, beta), 1/s
    knots : tuple of int
    knots_duration : float or None, s
        Horizon of the knots study (None: the scene's).
    optimisation_elements : int
    optimisation_step : float, s
    max_evaluations : int
        Nelder-Mead's cap.
    max_iter : int
        IPOPT's cap.
    refinements : int
        Model-correction solves of the ``"ipopt + correction"`` runs (0: none).
    compiled : bool
        Optimisers simulate with the RK4 step compiled to C.
    singular_scene : str
        Scene file (in the models folder) of the singularity check.
    """

    elements: tuple[int, ...] = (5, 10, 15, 30, 60, 100)
    torsion_elements: tuple[int, ...] = (5, 10, 15, 30, 60)
    duration: float = 20.0
    torsion_duration: float = 1.0
    min_steps: int = 200
    resolution: float = 1.1
    tolerance: float = 1.0
    linearised_samples: int = 5
    compile_from: int | None = None
    drift_elements: int = 15
    drift_step: float = 0.05
    drift_reference_step: float = 0.005
    drift_duration: float = 30.0
    gains: tuple[tuple[float, float], ...] = (
        (0.0, 0.0),
        (0.5, 0.5),
        (1.0, 1.0),
        (5.0, 5.0),
        (20.0, 20.0),
        (50.0, 50.0),
    )
    knots: tuple[int, ...] = (7, 14, 28, 56)
    knots_duration: float | None = None
    optimisation_elements: int = 3
    optimisation_step: float = 0.5
    max_evaluations: int = 1000
    max_iter: int = 300
    refinements: int = 3
    compiled: bool = True
    singular_scene: str = "hanging.toml"

    @classmethod
    def quick(cls) -> StabilitySettings:
        """A tiny version for tests and notebooks (seconds, not minutes)."""
        return cls(
            elements=(5, 10),
            torsion_elements=(5,),
            duration=2.0,
            torsion_duration=0.5,
            min_steps=50,
            resolution=1.5,
            drift_elements=5,
            drift_step=0.1,
            drift_reference_step=0.01,
            drift_duration=10.0,
            gains=((0.0, 0.0), (1.0, 1.0), (5.0, 5.0)),
            knots=(3, 5),
            knots_duration=21.0,
            max_evaluations=10,
            max_iter=2,
            refinements=0,
            compiled=False,
        )


@dataclass(frozen=True)
class StabilityStudy:
    """All four parts of the study, with their wall times.

    Attributes
    ----------
    steps : StepLimits
    drift : BaumgarteDrift
    knots : KnotsComparison
    singular : tuple of SingularCase
    settings : StabilitySettings
    part_times : dict of str to float, s
    wall_time : float, s
    """

    steps: StepLimits
    drift: BaumgarteDrift
    knots: KnotsComparison
    singular: tuple[SingularCase, ...]
    settings: StabilitySettings
    part_times: dict = field(default_factory=dict)
    wall_time: float = 0.0

    def markdown(self, quick: bool) -> str:
        """The report: every table, with what was measured and how."""
        s = self.settings
        times = ", ".join(f"{k} {v:.0f} s" for k, v in self.part_times.items())
        singular = [
            "| tried | rejected | message |",
            "|---|---|---|",
            *[
                f"| {table_cell(c.tried)} | {c.rejected} | {table_cell(c.message)} |"
                for c in self.singular
            ],
        ]
        return "\n".join(
            [
                f"# Stability study{' (quick settings)' if quick else ''}",
                "",
                f"Wall time {self.wall_time:.0f} s ({times}). Written by "
                "`cable_ocp.stability.run_stability`.",
                "",
                "## Largest stable RK4 step",
                "",
                "end_force scene with its push (F_x ramp over 15 s, F_y sine) starting at t = 0. "
                f"A run lasts at least {s.duration:g} s (torsion: {s.torsion_duration:g} s, "
                f"for cost) and {s.min_steps} steps. Stable: it completes with the bond residual "
                f"below {s.tolerance:g} m, finite, and (torsion) every twist angle within "
                f"{TWIST_LIMIT:.4g} rad; torsion models start with a {TWIST_SEED:g} rad random "
                f"twist. Bisection in log h to a ratio of {s.resolution:g}. Cross-checks: the end "
                "trajectory at h_max/4, and the linearised limit: the largest step for which the "
                "eigenvalues of the Jacobian (forward differences) at "
                f"{s.linearised_samples} evenly spaced states of the stable run (first and last "
                "included) lie in RK4's stability region (the smallest over them).",
                "",
                self.steps.table(),
                "",
                "![stable step](stable_step.png)",
                "",
                "## Baumgarte gains and constraint drift",
                "",
                self.drift.table(),
                "",
                "![drift](baumgarte_drift.png)",
                "",
                "## Nelder-Mead against IPOPT as the knots grow",
                "",
                self.knots.table(),
                "",
                "![knots](knots.png)",
                "",
                "## Euler-angle singularity",
                "",
                *singular,
                "",
            ]
        )


def run_stability(
    out: Path, models_dir: Path, quick: bool = False, quiet: bool = True
) -> StabilityStudy:
    """Run the whole study and write ``stability.md`` and the charts into ``out`` atomically.

    Parameters
    ----------
    out : Path
        Folder to (re)create: ``stability.md``, ``stable_step.png``, ``baumgarte_drift.png``,
        ``knots.png``.
    models_dir : Path
        Folder of the scene files (``end_force.toml``, ``paper_flat.toml``, ``hanging.toml``).
    quick : bool
        :meth:`StabilitySettings.quick` instead of the full sizes.
    quiet : bool
        No progress bars or solver logs.

    Returns
    -------
    StabilityStudy
    """
    settings = StabilitySettings.quick() if quick else StabilitySettings()
    models_dir = Path(models_dir)
    started = time.perf_counter()
    times = {}

    def timed(name, compute):
        begun = time.perf_counter()
        value = compute()
        times[name] = time.perf_counter() - begun
        return value

    end_force = load_scene(models_dir / "end_force.toml")
    flat = load_scene(models_dir / "paper_flat.toml")
    if settings.knots_duration is not None:
        flat = flat.updated({"numerics.duration": settings.knots_duration})
    steps = timed(
        "step limits",
        lambda: step_limits(
            end_force,
            settings.elements,
            settings.torsion_elements,
            duration=settings.duration,
            torsion_duration=settings.torsion_duration,
            min_steps=settings.min_steps,
            resolution=settings.resolution,
            tolerance=settings.tolerance,
            linearised_samples=settings.linearised_samples,
            compile_from=settings.compile_from,
            quiet=quiet,
        ),
    )
    drift = timed(
        "Baumgarte",
        lambda: baumgarte_drift(
            end_force,
            settings.gains,
            elements=settings.drift_elements,
            step=settings.drift_step,
            reference_step=settings.drift_reference_step,
            duration=settings.drift_duration,
            quiet=quiet,
        ),
    )
    singular = timed(
        "singularity",
        lambda: singular_states(load_scene(models_dir / settings.singular_scene)),
    )
    knots = timed(
        "knots",
        lambda: knots_comparison(
            flat,
            settings.knots,
            elements=settings.optimisation_elements,
            step=settings.optimisation_step,
            max_evaluations=settings.max_evaluations,
            max_iter=settings.max_iter,
            refinements=settings.refinements,
            compiled=settings.compiled,
            quiet=quiet,
        ),
    )
    study = StabilityStudy(
        steps, drift, knots, singular, settings, times, time.perf_counter() - started
    )
    with atomic_directory(out) as folder:
        (folder / "stability.md").write_text(study.markdown(quick))
        steps.chart(folder / "stable_step.png")
        drift.chart(folder / "baumgarte_drift.png")
        knots.chart(folder / "knots.png")
    return study
