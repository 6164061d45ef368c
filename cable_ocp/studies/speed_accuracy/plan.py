"""What the speed-accuracy study measures: the plan, its OCP settings, full and quick."""

from __future__ import annotations

from dataclasses import dataclass

from cable_ocp.control.settings import (
    GridSettings,
    ModelSettings,
    OcpSettings,
    TranscriptionSettings,
)
from cable_ocp.control.solvers import Solver, ocp_settings, solver_named

TOLERANCES = (0.01, 0.1)  # m, the accuracy targets named in the report


@dataclass(frozen=True)
class OcpSetting:
    """One optimiser setting of the OCP part.

    Attributes
    ----------
    solver : str
        A solver of the registry (:data:`cable_ocp.control.solvers.SOLVERS`): ``"ipopt"`` or
        ``"nelder-mead"`` here.
    elements : int
        Elements of the optimisation model.
    step : float, s
        RK4 step of the optimisation model.
    limit : int
        Iterations per solve of a shooting solver, or evaluations of the knots' search.
    refinements : int
        Model-correction solves after the first (a transcription that corrects its model only).
    compiled : bool
        Optimisation model compiled to C.
    """

    solver: str
    elements: int
    step: float
    limit: int
    refinements: int = 0
    compiled: bool = True

    @property
    def label(self) -> str:
        """Short name for tables and legends."""
        entry = solver_named(self.solver)
        plural = "" if self.refinements == 1 else "s"
        more = f", {self.refinements} refinement{plural}" if _corrects(entry) else ""
        head = f"{self.solver}, n = {self.elements}, h = {self.step:g} s"
        return f"{head}, <= {self.limit} {_budget(entry)[1]}{more}"

    @property
    def options(self) -> dict:
        """What ``optimize`` takes beside the settings: the refinements, where they apply."""
        return {"refinements": self.refinements} if _corrects(solver_named(self.solver)) else {}

    def settings(self, intervals: int) -> OcpSettings:
        """The optimiser's settings (``intervals``: a shooting solver's shooting intervals)."""
        entry = solver_named(self.solver)
        model = ModelSettings(self.elements, self.step)
        transcription = TranscriptionSettings(compiled=self.compiled)
        grid = GridSettings(intervals=intervals) if entry.shootings else None
        own = entry.settings(**{_budget(entry)[0]: self.limit})
        return ocp_settings(entry.name, own, model, grid, transcription)


def _corrects(entry: Solver) -> bool:
    """Whether ``optimize`` refines the solver's answer by model correction (``refinements``)."""
    return entry.transcription.model_correction


def _budget(entry: Solver) -> tuple[str, str]:
    """The field of a solver's settings that caps a solve, and what it counts.

    A shooting solver counts iterations; the knots' search (no shooting) counts evaluations,
    one simulation each (the registry's ``shootings``).
    """
    return ("max_iter", "iterations") if entry.shootings else ("max_evaluations", "evaluations")


@dataclass(frozen=True)
class StudyPlan:
    """What the study measures.

    Attributes
    ----------
    scenes : tuple of (str, float)
        Scene names (files in ``models_dir``) with the simulated duration of each, s.
    elements : tuple of int
        ``n`` of the grid, torsion off.
    torsion_elements : tuple of int
        ``n`` of the grid with torsion on.
    reference_elements : int
        ``n`` of the reference run (DOP853), the same for every scene.
    reference_tolerance : float
        ``rtol = atol`` of DOP853.
    reference_check_step : float, s
        Step of the RK4 run that checks the reference.
    output_interval : float, s
        Error sampling interval, also the largest step tried.
    stable_steps : int
        Stable steps per ``n`` without torsion: the largest stable one and its halvings.
    torsion_stable_steps : int
        The same with torsion on.
    compiled : bool
        Scan the steps with the model compiled to C (and integrate the reference on the compiled
        right-hand side); False: everything interpreted, so that a fresh cache compiles nothing.
    interpreted_work : float
        With ``compiled``, each stable step is also run interpreted up to this many element-steps
        (``(n + 1) x steps``): interpreted runs are about 20 times dearer.
    ocp : tuple of OcpSetting
        The optimiser settings of the OCP part, each solved once.
    ocp_duration : float or None, s
        Horizon of the OCP scene (None: the scene's).
    ocp_intervals : int
        Shooting intervals of IPOPT.
    scope : str
        Why the plan is cut where it is (printed in the report).
    """

    scenes: tuple[tuple[str, float], ...]
    elements: tuple[int, ...]
    torsion_elements: tuple[int, ...]
    reference_elements: int
    reference_tolerance: float
    reference_check_step: float
    output_interval: float
    stable_steps: int
    torsion_stable_steps: int
    compiled: bool
    interpreted_work: float
    ocp: tuple[OcpSetting, ...]
    ocp_duration: float | None
    ocp_intervals: int
    scope: str


FULL_PLAN = StudyPlan(
    scenes=(("paper_flat", 210.0), ("end_force", 100.0)),
    elements=(5, 10, 15, 30, 60, 100),
    torsion_elements=(5, 15),
    reference_elements=100,
    reference_tolerance=1e-10,
    reference_check_step=2.0**-7,
    output_interval=1.0,
    stable_steps=5,
    torsion_stable_steps=3,
    compiled=True,
    interpreted_work=1.5e5,
    ocp=(
        OcpSetting("ipopt", 3, 0.5, 300, refinements=1),
        OcpSetting("ipopt", 5, 0.5, 100, refinements=1),
        OcpSetting("ipopt", 8, 0.5, 30, refinements=1),
        OcpSetting("ipopt", 15, 0.25, 3),
        OcpSetting("nelder-mead", 3, 0.5, 3000),
    ),
    ocp_duration=None,
    ocp_intervals=42,
    scope=(
        "Sized to about 35 minutes on a shared 2-core machine: torsion only at n = 5 and 15; "
        "IPOPT's iterations per solve capped at 100 (n_ocp = 5), 30 (n_ocp = 8) and 3 "
        "(n_ocp = 15, the dearest by far), with one model-correction solve after a converged "
        "first solve (none for n_ocp = 15); Nelder-Mead with its default budget of 3000 "
        "evaluations. A capped solve that stops early is reported as failed, with its status."
    ),
)

QUICK_PLAN = StudyPlan(
    scenes=(("paper_flat", 10.0), ("end_force", 20.0)),
    elements=(3, 5),
    torsion_elements=(),
    reference_elements=5,
    reference_tolerance=1e-10,
    reference_check_step=2.0**-6,
    output_interval=0.5,
    stable_steps=2,
    torsion_stable_steps=0,
    compiled=False,
    interpreted_work=0.0,
    ocp=(OcpSetting("ipopt", 3, 0.5, 1, compiled=False),),
    ocp_duration=20.0,
    ocp_intervals=4,
    scope="Quick check of the machinery: tiny settings, nothing compiled; not a measurement.",
)
