"""The whole stability study: its settings, the run of all four parts and the report."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

from cable_ocp.scene.output import atomic_directory
from cable_ocp.scene.schema import load_scene
from cable_ocp.studies.stability.baumgarte import BaumgarteDrift, DriftSizes, baumgarte_drift
from cable_ocp.studies.stability.knots import KnotsComparison, KnotsSizes, knots_comparison
from cable_ocp.studies.stability.limits import StepLimits, step_limits
from cable_ocp.studies.stability.markdown import table_cell
from cable_ocp.studies.stability.singular import SingularCase, singular_states
from cable_ocp.studies.stability.stable_step import TWIST_LIMIT, TWIST_SEED, StepSearch


@dataclass(frozen=True)
class StabilitySettings:
    """Sizes of the study (see the functions of each part for the meaning).

    Attributes
    ----------
    elements, torsion_elements : tuple of int
        ``n`` of the step limits without and with torsion.
    search : StepSearch
        How each largest stable step is searched. Its runs without torsion cover the push's ramp
        (15 s in end_force), since the rising tension raises the frequencies.
    torsion_duration : float, s
        Shortest stability run with torsion, short for cost (the twist modes do not depend on
        the push).
    compile_from : int or None
        Models of at least this ``n`` are compiled to C (None: none).
    drift : DriftSizes
        The drift study's model, steps and length.
    gains : tuple of (alpha, beta), 1/s
        The Baumgarte gains the drift study compares.
    knots : tuple of int
        The numbers of knots the optimisers are compared at.
    knots_duration : float or None, s
        Horizon of the knots study (None: the scene's).
    optimisation : KnotsSizes
        How each optimisation of the knots study runs.
    singular_scene : str
        Scene file (in the models folder) of the singularity check.
    """

    elements: tuple[int, ...] = (5, 10, 15, 30, 60, 100)
    torsion_elements: tuple[int, ...] = (5, 10, 15, 30, 60)
    search: StepSearch = StepSearch(duration=20.0)
    torsion_duration: float = 1.0
    compile_from: int | None = None
    drift: DriftSizes = DriftSizes()
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
    optimisation: KnotsSizes = KnotsSizes(max_evaluations=1000)
    singular_scene: str = "hanging.toml"

    @classmethod
    def quick(cls) -> StabilitySettings:
        """A tiny version for tests and notebooks (seconds, not minutes)."""
        return cls(
            elements=(5, 10),
            torsion_elements=(5,),
            search=StepSearch(duration=2.0, min_steps=50, resolution=1.5),
            torsion_duration=0.5,
            drift=DriftSizes(elements=5, step=0.1, reference_step=0.01, duration=10.0),
            gains=((0.0, 0.0), (1.0, 1.0), (5.0, 5.0)),
            knots=(3, 5),
            knots_duration=21.0,
            optimisation=KnotsSizes(max_evaluations=10, max_iter=2, refinements=0, compiled=False),
        )


@dataclass(frozen=True)
class StabilityStudy:
    """All four parts of the study, with their wall times.

    Attributes
    ----------
    steps : StepLimits
        The largest stable RK4 steps.
    drift : BaumgarteDrift
        Bond drift and end error against the Baumgarte gains.
    knots : KnotsComparison
        IPOPT and Nelder-Mead against the number of knots.
    singular : tuple of SingularCase
        The Euler-angle singularity, one per sign.
    settings : StabilitySettings
        The sizes the study ran with.
    part_times : dict of str to float, s
        Wall time of each part, by name.
    wall_time : float, s
        Of the whole study.
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
        s, search = self.settings, self.settings.search
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
                "`cable_ocp.studies.stability.run_stability`.",
                "",
                "## Largest stable RK4 step",
                "",
                "end_force scene with its push (F_x ramp over 15 s, F_y sine) starting at t = 0. "
                f"A run lasts at least {search.duration:g} s (torsion: {s.torsion_duration:g} s, "
                f"for cost) and {search.min_steps} steps. Stable: it completes with the bond "
                f"residual below {search.tolerance:g} m, finite, and (torsion) every twist angle "
                f"within {TWIST_LIMIT:.4g} rad; torsion models start with a {TWIST_SEED:g} rad "
                f"random twist. Bisection in log h to a ratio of {search.resolution:g}. "
                "Cross-checks: the end trajectory at h_max/4, and the linearised limit: the "
                "largest step for which the eigenvalues of the Jacobian (forward differences) at "
                f"{search.linearised_samples} evenly spaced states of the stable run (first and "
                "last included) lie in RK4's stability region (the smallest over them).",
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
            settings.search,
            settings.torsion_duration,
            settings.compile_from,
            quiet=quiet,
        ),
    )
    drift = timed(
        "Baumgarte",
        lambda: baumgarte_drift(end_force, settings.gains, settings.drift, quiet),
    )
    singular = timed(
        "singularity",
        lambda: singular_states(load_scene(models_dir / settings.singular_scene)),
    )
    knots = timed(
        "knots",
        lambda: knots_comparison(flat, settings.knots, settings.optimisation, quiet),
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
