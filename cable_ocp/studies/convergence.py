"""Convergence and validation studies of simulated scenes (issue: scenes; CONVENTIONS.md §8).

Each study returns its numbers as a dataclass with a ``table()`` for printing; ``cable-ocp study``
runs them and writes the tables and charts to a folder.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.run import simulate
from cable_ocp.studies.figures import finished_chart
from cable_ocp.studies.uniform import locked_uniform


def end_difference(a, b) -> float:
    """Largest distance between the ends of two trajectories at the times of ``a`` (m)."""
    other = np.vstack([np.interp(a.time, b.time, b.end[:, k]) for k in range(3)]).T
    return float(np.max(np.linalg.norm(a.end - other, axis=1)))


@dataclass(frozen=True)
class StepHalving:
    """End trajectory at step h against h/2 on the same output grid.

    Attributes
    ----------
    step : float, s
        The scene's RK4 step h.
    max_difference : float, m
        ``max_t |r_E(h) - r_E(h/2)|`` over the output grid.
    rise : float, m
        Largest rise of the end above its start (at step h).
    omega : float, m
        Omega of the run at step h (winch locked).
    """

    step: float
    max_difference: float
    rise: float
    omega: float

    def table(self) -> str:
        """Readable summary."""
        return (
            f"h = {self.step:g} s: end rise {self.rise:.3f} m, Omega = {self.omega:.4f} m; "
            f"max |r_E(h) - r_E(h/2)| = {self.max_difference:.3g} m"
        )


def step_halving(scene, quiet: bool = True) -> StepHalving:
    """Simulate a scene at its step and at half of it (locked winch) and compare the ends."""
    coarse = simulate(scene, quiet=quiet)
    half = scene.updated(
        {
            "numerics.step": scene.numerics.step / 2,
            "numerics.output_every": 2 * scene.numerics.output_every,
        }
    )
    fine = simulate(half, quiet=quiet)
    return StepHalving(
        step=scene.numerics.step,
        max_difference=end_difference(coarse, fine),
        rise=float(coarse.end[:, 2].max() - coarse.end[0, 2]),
        omega=coarse.omega,
    )


@dataclass(frozen=True)
class ElementConvergence:
    """End trajectory for several numbers of elements against a finer reference.

    Attributes
    ----------
    elements : tuple of int
        The numbers of elements n compared.
    reference_elements : int
        n of the reference run.
    max_difference : tuple of float, m
        ``max_t |r_E(n) - r_E(reference)|`` per ``n``.
    omega : tuple of float, m
        Omega of each run (winch locked), per ``n``.
    reference_omega : float, m
        Omega of the reference run.
    step : float, s
        RK4 step h of every run.
    """

    elements: tuple[int, ...]
    reference_elements: int
    max_difference: tuple[float, ...]
    omega: tuple[float, ...]
    reference_omega: float
    step: float

    def table(self) -> str:
        """Markdown table of the errors."""
        lines = [
            f"End trajectory against n = {self.reference_elements} (h = {self.step:g} s); "
            f"reference Omega = {self.reference_omega:.4f} m",
            "",
            "| n | max end difference [m] | Omega [m] |",
            "|---:|---:|---:|",
        ]
        lines += [
            f"| {n} | {d:.4f} | {o:.4f} |"
            for n, d, o in zip(self.elements, self.max_difference, self.omega, strict=True)
        ]
        return "\n".join(lines)

    def chart(self, path=None):
        """Log-log chart of the error against n."""
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6, 4))
        ax.loglog(self.elements, self.max_difference, "o-")
        ax.set_xlabel("elements n")
        ax.set_ylabel(f"max |r_E(n) - r_E({self.reference_elements})| [m]")
        ax.set_title("convergence of the end trajectory in n")
        ax.grid(alpha=0.3, which="both")
        return finished_chart(fig, path)


def element_convergence(
    scene,
    elements: Sequence[int] = (5, 10, 15, 30, 60),
    reference_elements: int = 100,
    step: float | None = None,
    quiet: bool = True,
) -> ElementConvergence:
    """Locked-winch end trajectories for several ``n`` against ``reference_elements``.

    The winch is locked, on the uniform mesh of every ``n``.
    """
    step = step or scene.numerics.step
    every = max(1, round(scene.numerics.step * scene.numerics.output_every / step))
    base = locked_uniform(
        scene,
        [*elements, reference_elements],
        {"numerics.step": step, "numerics.output_every": every},
    )

    def run(n):
        local = base.updated({"model.elements": n})
        return simulate(local, model=CableModel.from_scene(local), quiet=quiet)

    reference = run(reference_elements)
    runs = [run(n) for n in elements]
    return ElementConvergence(
        elements=tuple(elements),
        reference_elements=reference_elements,
        max_difference=tuple(end_difference(r, reference) for r in runs),
        omega=tuple(r.omega for r in runs),
        reference_omega=reference.omega,
        step=step,
    )


# The paper's Table 1 settings on the end_force scene (n = 100): without torsion at three steps, and
# with torsion at 1e-3 s, near its RK4 stability limit (torsional modes of 3 m steel elements).
END_FORCE_SETTINGS = (
    ("no torsion, h = 1e-3", {"numerics.step": 1e-3, "numerics.output_every": 100}),
    ("no torsion, h = 1e-2", {"numerics.step": 1e-2, "numerics.output_every": 10}),
    ("no torsion, h = 2e-2", {"numerics.step": 2e-2, "numerics.output_every": 5}),
    (
        "torsion, h = 1e-3",
        {"model.torsion": True, "numerics.step": 1e-3, "numerics.output_every": 100},
    ),
)


@dataclass(frozen=True)
class EndPositionTable:
    """End positions at chosen times for several settings (the paper's Table 1).

    Attributes
    ----------
    times : tuple of float, s
        Times of the table's columns.
    labels : tuple of str
        One per setting (step, torsion).
    positions : array (settings, times, 3), m
        The end's position r_E per setting and time.
    """

    times: tuple[float, ...]
    labels: tuple[str, ...]
    positions: np.ndarray

    def table(self) -> str:
        """Markdown table of x_E, y_E per setting, and the differences to the first setting."""
        head = "| t [s] | " + " | ".join(f"{lb}: x_E, y_E [m]" for lb in self.labels) + " |"
        lines = [head, "|---:|" + "---:|" * len(self.labels)]
        for k, t in enumerate(self.times):
            cells = [f"{p[k, 0]:.3f}, {p[k, 1]:.3f}" for p in self.positions]
            lines.append(f"| {t:g} | " + " | ".join(cells) + " |")
        first = self.positions[0]
        # Relative to the largest horizontal excursion: the end starts at the origin, so a
        # pointwise relative error would divide by zero at t = 10 s.
        scale = np.linalg.norm(first[:, :2], axis=1).max()
        lines.append("")
        for label, p in zip(self.labels[1:], self.positions[1:], strict=True):
            difference = np.linalg.norm(p[:, :2] - first[:, :2], axis=1).max()
            lines.append(
                f"max difference {label} vs {self.labels[0]}: {difference:.3e} m = "
                f"{100 * difference / scale:.5f} % of the largest excursion ({scale:.2f} m)"
            )
        return "\n".join(lines)


def end_positions(
    scene,
    settings: Sequence[tuple[str, dict]],
    times: Sequence[float] = (10, 25, 50, 75, 100),
    quiet: bool = True,
    compiled: bool = False,
) -> EndPositionTable:
    """End positions at ``times`` for each ``(label, scene overrides)`` setting."""
    positions = []
    for _, overrides in settings:
        local = scene.updated(overrides)
        run = simulate(local, quiet=quiet, compiled=compiled)
        idx = [int(np.argmin(np.abs(run.time - t))) for t in times]
        positions.append(run.end[idx])
    return EndPositionTable(tuple(times), tuple(lb for lb, _ in settings), np.array(positions))
