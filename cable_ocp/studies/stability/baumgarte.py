"""Bond drift and end error of the pushed scene for several Baumgarte gains."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.studies.convergence import end_difference
from cable_ocp.studies.figures import finished_chart
from cable_ocp.studies.stability.markdown import table_cell
from cable_ocp.studies.stability.push import SHARP_PUSH, pushed_scene


@dataclass(frozen=True, eq=False)
class GainRun:
    """One run of the drift study.

    Attributes
    ----------
    alpha, beta : float, 1/s
        The Baumgarte gains of the run.
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
class DriftSizes:
    """The runs of the drift study: one model, one step, one length, against a finer reference.

    Attributes
    ----------
    elements : int
        ``n`` of the model.
    step : float, s
        RK4 step of every compared run.
    reference_step : float, s
        Step of the reference run (the scene's own gains), a whole fraction of ``step``.
    duration : float, s
        Simulated time of each run.
    """

    elements: int = 15
    step: float = 0.05
    reference_step: float = 0.005
    duration: float = 30.0


@dataclass(frozen=True)
class BaumgarteDrift:
    """Bond drift and end error for several Baumgarte gains at one step.

    Attributes
    ----------
    sizes : DriftSizes
        As run: the reference's step is the whole fraction of ``step`` it took.
    reference_gains : tuple of float, 1/s
        The scene's own ``(alpha, beta)``, those of the reference run.
    runs : tuple of GainRun
        One per compared pair of gains.
    """

    sizes: DriftSizes
    reference_gains: tuple[float, float]
    runs: tuple[GainRun, ...]

    def table(self) -> str:
        """Markdown table: largest and final residual, end error, or why the run stopped."""
        sizes = self.sizes
        lines = [
            f"end_force scene, push from t = 0 ramped over 1 s, n = {sizes.elements}, "
            f"h = {sizes.step:g} s, {sizes.duration:g} s; reference: (alpha, beta) = "
            f"{self.reference_gains} at h = {sizes.reference_step:g} s",
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
        left.set_title(f"constraint drift, n = {self.sizes.elements}, h = {self.sizes.step:g} s")
        left.grid(alpha=0.3, which="both")
        left.legend(fontsize=7)

        done = [r for r in self.runs if not r.failure]
        positions = np.arange(len(done))
        right.bar(positions - 0.2, [r.residual.max() for r in done], 0.4, label="max |Phi|")
        right.bar(
            positions + 0.2,
            [r.end_difference for r in done],
            0.4,
            label=f"max end diff vs reference (h = {self.sizes.reference_step:g} s)",
        )
        right.set_yscale("log")
        right.set_xticks(positions, [f"({r.alpha:g}, {r.beta:g})" for r in done])
        right.set_xlabel("Baumgarte gains (alpha, beta) [1/s]")
        right.set_ylabel("[m]")
        right.set_title("drift and accuracy per gain (completed runs)")
        right.grid(alpha=0.3, which="both", axis="y")
        right.legend(fontsize=8)
        return finished_chart(fig, path)


def baumgarte_drift(
    scene,
    gains: Sequence[tuple[float, float]],
    sizes: DriftSizes | None = None,
    quiet: bool = True,
) -> BaumgarteDrift:
    """Bond residual over time and end error for each ``(alpha, beta)`` of ``gains``.

    The scene (usually end_force) is pushed sharply (:data:`SHARP_PUSH`). Its
    ``numerics.constraint_tolerance`` is raised to the cable length, so that only a blow-up stops
    a run (its message, with the time, is kept); the reference uses the scene's own gains at
    ``sizes.reference_step`` (``sizes``: ``DriftSizes()`` by default).
    """
    sizes = sizes or DriftSizes()
    elements, step, duration = sizes.elements, sizes.step, sizes.duration
    base = pushed_scene(scene, elements, scene.model.torsion, SHARP_PUSH).updated(
        {
            "numerics.duration": duration,
            "numerics.constraint_tolerance": scene.cable.length,
            "numerics.output_every": 1,
        }
    )
    every = max(1, round(step / sizes.reference_step))
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
        sizes=replace(sizes, reference_step=step / every),
        reference_gains=(numerics.baumgarte_alpha, numerics.baumgarte_beta),
        runs=tuple(runs),
    )
