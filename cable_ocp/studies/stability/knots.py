"""IPOPT (spline control) against the paper's Nelder-Mead as the number of knots grows."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.nelder_mead import NelderMeadSettings
from cable_ocp.control.optimization import OcpResult, optimize
from cable_ocp.control.settings import GridSettings, ModelSettings, TranscriptionSettings
from cable_ocp.control.solvers import ocp_settings, solver_named
from cable_ocp.studies.figures import finished_chart
from cable_ocp.studies.solve_record import kept
from cable_ocp.studies.stability.markdown import table_cell


@dataclass(frozen=True)
class KnotRun:
    """One optimisation of the knots study.

    Attributes
    ----------
    knots : int
        The spline's number of knots p.
    corrected : bool
        Whether model-correction solves against the scene's model followed the first solve.
    result : OcpResult
        What ``optimize`` returned, its figures (``omega``, ``success``, ``history``, ...)
        without the verified trajectory (:func:`~cable_ocp.studies.solve_record.kept`): the
        solver's ``history`` is Nelder-Mead's best Omega after each evaluation, IPOPT's Omega
        per iteration (m).
    """

    knots: int
    corrected: bool
    result: OcpResult

    @property
    def method(self) -> str:
        """The run as the table names it: the solver, ``+ correction`` when corrected."""
        solver = self.result.solver
        return f"{solver} + correction" if self.corrected else solver

    @property
    def searched(self) -> bool:
        """Its history is a best Omega per evaluation: the knots' search, which does not shoot."""
        return bool(self.result.history) and not solver_named(self.result.solver).shootings

    def evaluations_to_within(self, fraction: float) -> int:
        """Evaluations until the best Omega came within ``fraction`` of its last value."""
        history = np.asarray(self.result.history)
        return int(np.argmax(history <= history[-1] * (1 + fraction))) + 1


@dataclass(frozen=True)
class KnotsComparison:
    """IPOPT (spline control) and Nelder-Mead for several numbers of knots.

    Attributes
    ----------
    scene_name : str
        The scene optimised.
    duration : float, s
        Its horizon T.
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
        Every optimisation, in the order run (per knots: IPOPT, corrected, Nelder-Mead).
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
        for run in self.runs:
            within = run.evaluations_to_within(self.progress_fraction) if run.searched else "-"
            r = run.result
            lines.append(
                f"| {run.knots} | {run.method} | {r.omega:.3g} | {r.omega_model:.3g} | {r.success} "
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
        for run in self.runs:
            r = run.result
            entry = solver_named(r.solver)
            if run.searched:
                history.semilogy(
                    np.arange(1, len(r.history) + 1),
                    r.history,
                    color=colours[run.knots],
                    label=f"{entry.label}, p = {run.knots}",
                )
            elif entry.shootings and not run.corrected and math.isfinite(r.omega_model):
                history.axhline(
                    r.omega_model,
                    color=colours[run.knots],
                    ls="--",
                    lw=1,
                    label=f"{entry.label}, p = {run.knots} (final)",
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
            failed = [r for r in chosen if not r.result.success]
            for axis, value in ((quality, "omega"), (cost, "wall_time")):
                axis.plot(
                    [r.knots for r in chosen],
                    [getattr(r.result, value) for r in chosen],
                    marker + "-",
                    color=colour,
                    label=method,
                )
                axis.plot(
                    [r.knots for r in failed],
                    [getattr(r.result, value) for r in failed],
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
        return finished_chart(fig, path)


def _knot_run(knots: int, corrected: bool, result: OcpResult) -> KnotRun:
    return KnotRun(knots=knots, corrected=corrected, result=kept(result))


@dataclass(frozen=True)
class KnotsSizes:
    """How each optimisation of the knots study runs.

    Attributes
    ----------
    elements : int
        ``n`` of the reduced optimisation model (Omega verified on the scene's own).
    step : float, s
        RK4 step of that model.
    max_evaluations : int
        Nelder-Mead's cap.
    max_iter : int
        IPOPT's cap per solve.
    refinements : int
        Model-correction solves of the ``"ipopt + correction"`` runs (0: no such runs).
    compiled : bool
        The optimisers simulate with the RK4 step compiled to C (cached on disk).
    """

    elements: int = 3
    step: float = 0.5
    max_evaluations: int = 600
    max_iter: int = 300
    refinements: int = 3
    compiled: bool = True


def knots_comparison(
    scene,
    knots: Sequence[int] = (7, 14, 28, 56),
    sizes: KnotsSizes | None = None,
    quiet: bool = True,
) -> KnotsComparison:
    """IPOPT with the paper's spline control and Nelder-Mead, for each number of knots.

    Both optimise on a reduced model (``sizes.elements``, ``sizes.step``; ``sizes`` is
    ``KnotsSizes()`` by default) as the front door's defaults do, and so minimise the same
    objective (methods ``"ipopt"``, ``"nelder-mead"``). With ``sizes.refinements > 0`` IPOPT is
    also run with that many model-correction solves against the scene's model
    (``"ipopt + correction"``, see :func:`cable_ocp.control.optimization.solve_verified`). A
    failed solve is kept with its status.
    """
    sizes = sizes or KnotsSizes()
    elements, step, refinements = sizes.elements, sizes.step, sizes.refinements
    runs = []
    for p in knots:
        local = scene.updated({"winch.knots": p})
        model = ModelSettings(elements, step)
        transcription = TranscriptionSettings(compiled=sizes.compiled)
        ipopt = ocp_settings("ipopt", IpoptSettings(max_iter=sizes.max_iter), model,
                             GridSettings(control="spline"), transcription)  # fmt: skip
        plain = optimize(local, settings=ipopt, refinements=0, quiet=quiet)
        runs.append(_knot_run(p, False, plain))
        if refinements > 0:
            corrected = optimize(local, settings=ipopt, refinements=refinements, quiet=quiet)
            runs.append(_knot_run(p, True, corrected))
        search = NelderMeadSettings(max_evaluations=sizes.max_evaluations)
        searched = optimize(local, "nelder-mead", search, model=model, transcription=transcription,
                            quiet=quiet)  # fmt: skip
        runs.append(_knot_run(p, False, searched))
    return KnotsComparison(
        scene_name=scene.name,
        duration=scene.numerics.duration,
        elements=elements,
        step=step,
        evaluation_cap=sizes.max_evaluations,
        iteration_cap=sizes.max_iter,
        refinements=refinements,
        runs=tuple(runs),
    )
