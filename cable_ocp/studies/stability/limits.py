"""Largest stable RK4 steps against ``n``, with and without torsion, and their power-law fits."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from cable_ocp.studies.figures import finished_chart
from cable_ocp.studies.stability.stable_step import StableStep, StepSearch, largest_stable_step


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
        One per model searched (each ``n``, without and with torsion).
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
        return finished_chart(fig, path)


def step_limits(
    scene,
    elements: Sequence[int],
    torsion_elements: Sequence[int],
    search: StepSearch | None = None,
    torsion_duration: float = 1.0,
    compile_from: int | None = None,
    quiet: bool = True,
) -> StepLimits:
    """:func:`largest_stable_step` for each ``n``: ``elements`` without, ``torsion_elements`` with.

    Each search starts from the limit found at the previous ``n`` (the limit falls with ``n``),
    the first from the scene's step. Torsion runs are shorter (``torsion_duration``, s, in place
    of ``search.duration``): their steps are tiny. Models with at least ``compile_from`` elements
    are compiled to C (None: none). ``search`` is ``StepSearch()`` by default.
    """
    search = search or StepSearch()
    results = []
    for torsion, chosen, length in (
        (False, elements, search.duration),
        (True, torsion_elements, torsion_duration),
    ):
        previous = None
        for n in chosen:
            result = largest_stable_step(
                scene,
                n,
                torsion,
                first_step=previous,
                search=replace(search, duration=length),
                compiled=compile_from is not None and n >= compile_from,
                quiet=quiet,
            )
            results.append(result)
            previous = result.step
    return StepLimits(tuple(results), search.tolerance)
