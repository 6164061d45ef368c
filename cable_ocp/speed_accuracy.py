"""Speed against accuracy: end-trajectory error versus CPU time, and OCP Omega versus wall time.

For each scene (``paper_flat`` with the winch locked, ``end_force``) a reference end trajectory
comes from the adaptive DOP853 integrator (:func:`cable_ocp.integrate.reference_solution`) on the
compiled right-hand side of a fine model; its own uncertainty is its difference from an RK4 run of
the same model at a small step. Every other setting (elements ``n``, RK4 step ``h``, torsion on or
off, interpreted or compiled) is scored by ``max_t |r_E - r_E,ref|`` against the CPU time of its
integration. For each ``n`` the step is doubled until a run fails (:class:`SimulationError`), which
brackets the RK4 stability limit; the failed run is recorded as unstable. The optimal-control part
solves ``paper_flat`` by IPOPT on reduced models and by Nelder-Mead, each verified on the scene's
own model (DESIGN.md §5, §8).

The entry point is :func:`run_speed_accuracy`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.transforms import blended_transform_factory

from cable_ocp import structured, winch
from cable_ocp.compile import compiled as compile_function
from cable_ocp.drive import Drive
from cable_ocp.integrate import SimulationError, integrate, reference_solution
from cable_ocp.model import CableModel
from cable_ocp.nelder_mead import NelderMeadSettings
from cable_ocp.ocp import IpoptSettings
from cable_ocp.optimization import optimize
from cable_ocp.output import atomic_directory
from cable_ocp.scene import load_scene
from cable_ocp.statics import equilibrium

TOLERANCES = (0.01, 0.1)  # m, the accuracy targets named in the report
# The scan for a stable RK4 step gives up below this step (s).
SMALLEST_STEP = 2.0**-16


@dataclass(frozen=True)
class OcpSetting:
    """One optimiser setting of the OCP part.

    Attributes
    ----------
    method : str
        ``"ipopt"`` or ``"nelder-mead"``.
    elements : int
        Elements of the optimisation model.
    step : float, s
        RK4 step of the optimisation model.
    limit : int
        IPOPT iterations per solve, or Nelder-Mead evaluations.
    refinements : int
        Model-correction solves after the first (IPOPT only).
    compiled : bool
        Optimisation model compiled to C.
    """

    method: str
    elements: int
    step: float
    limit: int
    refinements: int = 0
    compiled: bool = True

    @property
    def label(self) -> str:
        """Short name for tables and legends."""
        cap = "iterations" if self.method == "ipopt" else "evaluations"
        plural = "" if self.refinements == 1 else "s"
        more = f", {self.refinements} refinement{plural}" if self.method == "ipopt" else ""
        head = f"{self.method}, n = {self.elements}, h = {self.step:g} s"
        return f"{head}, <= {self.limit} {cap}{more}"

    def settings(self, intervals: int) -> IpoptSettings | NelderMeadSettings:
        """The optimiser's own settings (``intervals``: IPOPT's shooting intervals)."""
        if self.method == "ipopt":
            return IpoptSettings(
                elements=self.elements,
                step=self.step,
                intervals=intervals,
                max_iter=self.limit,
                compiled=self.compiled,
            )
        return NelderMeadSettings(
            elements=self.elements,
            step=self.step,
            max_evaluations=self.limit,
            compiled=self.compiled,
        )


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
    reference_tolerance : float
        ``rtol = atol`` of DOP853.
    reference_check_step : float, s
        Step of the RK4 run that checks the reference.
    output_interval : float, s
        Error sampling interval, also the largest step tried.
    stable_steps : int
        Stable steps per ``n`` without torsion: the largest stable one and its halvings.
    torsion_stable_steps : int
    compiled : bool
        Scan the steps with the model compiled to C (and integrate the reference on the compiled
        right-hand side); False: everything interpreted, so that a fresh cache compiles nothing.
    interpreted_work : float
        With ``compiled``, each stable step is also run interpreted up to this many element-steps
        (``(n + 1) x steps``): interpreted runs are about 20 times dearer.
    ocp : tuple of OcpSetting
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


def timed(call: Callable[[], object]) -> tuple[object, float, float]:
    """Call ``call()``; return its value, the CPU time of this process and the wall time (s)."""
    cpu, wall = time.process_time(), time.perf_counter()
    value = call()
    return value, time.process_time() - cpu, time.perf_counter() - wall


def pareto_front(costs: Sequence[float], errors: Sequence[float]) -> list[int]:
    """Indices of the non-dominated points, cheapest first.

    A point is dominated when another is no dearer and no less accurate, and better in one of the
    two.
    """
    order = sorted(range(len(costs)), key=lambda k: (costs[k], errors[k]))
    front, best = [], math.inf
    for k in order:
        if errors[k] < best:
            front.append(k)
            best = errors[k]
    return front


@dataclass(frozen=True)
class Reference:
    """The converged end trajectory of a scene.

    Attributes
    ----------
    elements : int
    time : array (k,), s
    end : array (k, 3), m
    tolerance : float
        DOP853 ``rtol = atol``.
    cpu_time, wall_time : float, s
        Of the DOP853 integration.
    check_step : float, s
    check_difference : float, m
        ``max_t |r_E,RK4 - r_E,ref|`` with RK4 at ``check_step`` on the same model: the
        reference's own uncertainty.
    """

    elements: int
    time: np.ndarray
    end: np.ndarray
    tolerance: float
    cpu_time: float
    wall_time: float
    check_step: float
    check_difference: float


@dataclass(frozen=True)
class RunPoint:
    """One measured RK4 setting.

    Attributes
    ----------
    elements : int
    step : float, s
    torsion : bool
    mode : str
        ``"interpreted"`` or ``"compiled"``.
    stable : bool
        False when the run raised :class:`SimulationError`.
    error : float, m
        ``max_t |r_E - r_E,ref|`` at the output times (NaN when unstable).
    cpu_time, wall_time : float, s
        Of the integration alone (NaN when unstable): model build, equilibrium, compiling and
        building the step Function are excluded.
    steps : int
        RK4 steps of a complete run.
    message : str
        The failure, when unstable.
    """

    elements: int
    step: float
    torsion: bool
    mode: str
    stable: bool
    error: float
    cpu_time: float
    wall_time: float
    steps: int
    message: str = ""

    @property
    def label(self) -> str:
        """``n = 15, h = 0.0625 s, no torsion, compiled``."""
        twist = "torsion" if self.torsion else "no torsion"
        return f"n = {self.elements}, h = {self.step:g} s, {twist}, {self.mode}"


@dataclass(frozen=True)
class SceneStudy:
    """Every measured setting of one scene against its reference.

    Attributes
    ----------
    scene_name : str
    duration : float, s
    constraint_tolerance : float, m
        Bond residual beyond which a run is stopped as failed.
    reference : Reference
    points : tuple of RunPoint
    """

    scene_name: str
    duration: float
    constraint_tolerance: float
    reference: Reference
    points: tuple[RunPoint, ...]

    @property
    def stable_points(self) -> list[RunPoint]:
        """The points of complete runs."""
        return [p for p in self.points if p.stable]

    def pareto(self) -> list[RunPoint]:
        """Stable points not beaten in both CPU time and error, cheapest first."""
        stable = self.stable_points
        front = pareto_front([p.cpu_time for p in stable], [p.error for p in stable])
        return [stable[k] for k in front]

    def cheapest(self, tolerance: float) -> RunPoint | None:
        """The cheapest stable point with error <= ``tolerance`` (m), or None."""
        meeting = [p for p in self.stable_points if p.error <= tolerance]
        return min(meeting, key=lambda p: p.cpu_time) if meeting else None

    def stability_limits(self) -> list[tuple[int, bool, float, float]]:
        """``(n, torsion, largest stable step, smallest unstable step)`` (s; NaN if none)."""
        keys = sorted({(p.elements, p.torsion) for p in self.points})
        limits = []
        for n, torsion in keys:
            runs = [p for p in self.points if (p.elements, p.torsion) == (n, torsion)]
            stable = [p.step for p in runs if p.stable]
            unstable = [p.step for p in runs if not p.stable]
            limits.append(
                (n, torsion, max(stable, default=math.nan), min(unstable, default=math.nan))
            )
        return limits


@dataclass(frozen=True)
class OcpPoint:
    """One optimiser run on the OCP scene, verified on the scene's own model.

    Attributes
    ----------
    setting : OcpSetting
    omega : float, m
        Verified Omega (NaN when the last iterate could not be simulated).
    omega_model : float, m
        Omega on the optimisation model.
    success : bool
    status : str
    iterations, evaluations : int
    wall_time, cpu_time : float, s
        The whole ``optimize`` call, verification included.
    """

    setting: OcpSetting
    omega: float
    omega_model: float
    success: bool
    status: str
    iterations: int
    evaluations: int
    wall_time: float
    cpu_time: float


@dataclass(frozen=True)
class SpeedAccuracy:
    """The whole study.

    Attributes
    ----------
    plan : StudyPlan
    scenes : tuple of SceneStudy
    ocp : tuple of OcpPoint
    ocp_scene : str
    ocp_duration : float, s
    cpu_time, wall_time : float, s
        Of the whole study, compiling included.
    """

    plan: StudyPlan
    scenes: tuple[SceneStudy, ...]
    ocp: tuple[OcpPoint, ...]
    ocp_scene: str
    ocp_duration: float
    cpu_time: float
    wall_time: float


def study_scene(scene, plan: StudyPlan, duration: float):
    """The scene over ``duration`` (s), its top-element bounds widened to admit every ``Delta/2``.

    The winch stays locked, so the bounds only have to admit the initial top element.
    """
    counts = (*plan.elements, *plan.torsion_elements, plan.reference_elements)
    half = scene.cable.length / 2
    return scene.updated(
        {
            "numerics.duration": duration,
            "winch.top_length_min": min(scene.winch.top_length_min, half / max(counts)),
            "winch.top_length_max": max(scene.winch.top_length_max, half / min(counts)),
        }
    )


@dataclass(frozen=True)
class Setup:
    """A model at rest, ready to integrate: scene, model, drive and initial state."""

    scene: object
    model: CableModel
    drive: Drive
    x0: np.ndarray

    @classmethod
    def build(cls, scene, elements: int, torsion: bool = False) -> Setup:
        """The locked-winch ``scene`` with ``elements`` and torsion, at its static equilibrium."""
        local = scene.updated({"model.elements": elements, "model.torsion": torsion})
        model = CableModel.from_scene(local)
        drive = Drive.from_scene(local, winch.locked, elements=elements)
        return cls(local, model, drive, equilibrium(model, drive))

    def run(
        self, step: float, output_interval: float, compiled: bool, duration: float | None = None
    ):
        """RK4 end trajectory sampled every ``output_interval`` (s); CPU and wall time (s).

        ``duration`` (s) defaults to the scene's.
        """
        numerics = self.scene.numerics
        raw, cpu, wall = timed(
            lambda: integrate(
                self.model,
                self.x0,
                self.drive,
                duration or numerics.duration,
                step,
                output_every=round(output_interval / step),
                tolerance=numerics.constraint_tolerance,
                compiled=compiled,
            )
        )
        return raw.time, raw.states[:, :3], cpu, wall


def reference_run(scene, plan: StudyPlan) -> Reference:
    """DOP853 on the (compiled) right-hand side of the reference model, checked by RK4."""
    setup = Setup.build(scene, plan.reference_elements)
    model = setup.model
    if plan.compiled:
        # The structured form (equal to model.rhs) compiles in seconds where the flat one takes
        # minutes; reference_solution reads only ``model.rhs``: hand it the compiled one.
        flat = not structured.supports(model)
        rhs = model.rhs if flat else structured.structured_rhs(model)
        model = SimpleNamespace(rhs=compile_function(rhs, repr(model.spec), derivatives=False)[0])
    duration = scene.numerics.duration
    times = np.linspace(0.0, duration, 1 + round(duration / plan.output_interval))
    states, cpu, wall = timed(
        lambda: reference_solution(
            model,
            setup.x0,
            setup.drive,
            times,
            rtol=plan.reference_tolerance,
            atol=plan.reference_tolerance,
        )
    )
    _, end, _, _ = setup.run(plan.reference_check_step, plan.output_interval, plan.compiled)
    return Reference(
        elements=plan.reference_elements,
        time=times,
        end=states[:, :3],
        tolerance=plan.reference_tolerance,
        cpu_time=cpu,
        wall_time=wall,
        check_step=plan.reference_check_step,
        check_difference=end_error(end, states[:, :3]),
    )


def end_error(end: np.ndarray, reference_end: np.ndarray) -> float:
    """``max_t |r_E - r_E,ref|`` over common output times (m)."""
    return float(np.max(np.linalg.norm(end - reference_end, axis=1)))


def measure(
    setup: Setup, step: float, mode: str, reference: Reference, plan: StudyPlan
) -> RunPoint:
    """Run one setting and score it against the reference; an unstable run is recorded as such."""
    compiled = mode == "compiled"
    steps = round(setup.scene.numerics.duration / step)
    point = dict(elements=setup.model.spec.elements, step=step, steps=steps, mode=mode)
    point["torsion"] = setup.scene.model.torsion
    try:
        # integrate keeps its Functions on the model: a run of one output interval first builds,
        # compiles or loads them all, so that only the integration is timed.
        setup.run(step, plan.output_interval, compiled, duration=plan.output_interval)
        _, end, cpu, wall = setup.run(step, plan.output_interval, compiled)
    except SimulationError as failure:
        return RunPoint(
            **point,
            stable=False,
            error=math.nan,
            cpu_time=math.nan,
            wall_time=math.nan,
            message=str(failure).split(". Remedy")[0],
        )
    return RunPoint(
        **point,
        stable=True,
        error=end_error(end, reference.end),
        cpu_time=cpu,
        wall_time=wall,
    )


def first_step_guess(scene, elements: int, torsion: bool, largest: float) -> float:
    """A power-of-two step (s) near the RK4 stability limit, where the scan starts.

    Without torsion: the power law through DESIGN.md §9's 0.4 s at n = 15 and 0.04 s at
    n = 100. With torsion: the time a torsional wave takes to cross an element,
    ``Delta / sqrt(G / rho)``.
    """
    if torsion:
        cable = scene.cable
        guess = cable.length / elements / math.sqrt(cable.shear_modulus / cable.density)
    else:
        guess = 0.4 * (15 / elements) ** (math.log(10) / math.log(100 / 15))
    return min(largest, 2.0 ** math.floor(math.log2(guess)))


def step_scan(
    run: Callable[[float], RunPoint], first: float, largest: float, stable_count: int
) -> list[RunPoint]:
    """Bracket the stability limit by doubling the step, then halve below it.

    From ``first`` the step is halved until a run is stable, then doubled until one is not (or
    ``largest`` is reached); below the largest stable step ``stable_count - 1`` halvings follow.
    """
    done: dict[float, RunPoint] = {}

    def at(step: float) -> RunPoint:
        if step not in done:
            done[step] = run(step)
        return done[step]

    step = first
    while not at(step).stable:
        step /= 2
        if step < SMALLEST_STEP:
            raise SimulationError(f"no stable RK4 step down to {SMALLEST_STEP:g} s")
    while 2 * step <= largest and at(2 * step).stable:
        step *= 2
    for k in range(1, stable_count):
        at(step / 2**k)
    return [done[h] for h in sorted(done)]


def scene_study(scene, plan: StudyPlan, quiet: bool = True) -> SceneStudy:
    """Reference and grid of one scene (already cut to the study's duration)."""
    reference = reference_run(scene, plan)
    points: list[RunPoint] = []
    grid = [(n, False, plan.stable_steps) for n in plan.elements]
    grid += [(n, True, plan.torsion_stable_steps) for n in plan.torsion_elements]
    mode = "compiled" if plan.compiled else "interpreted"
    for n, torsion, count in grid:
        setup = Setup.build(scene, n, torsion)
        first = first_step_guess(scene, n, torsion, plan.output_interval)
        scanned = step_scan(
            lambda h, s=setup: measure(s, h, mode, reference, plan),
            first,
            plan.output_interval,
            count,
        )
        points += scanned
        if plan.compiled:
            affordable = [
                p for p in scanned if p.stable and (n + 1) * p.steps <= plan.interpreted_work
            ]
            points += [measure(setup, p.step, "interpreted", reference, plan) for p in affordable]
        if not quiet:
            print(f"{scene.name}: n = {n}, torsion {torsion}: done", flush=True)
    numerics = scene.numerics
    return SceneStudy(
        scene.name, numerics.duration, numerics.constraint_tolerance, reference, tuple(points)
    )


def ocp_point(scene, setting: OcpSetting, intervals: int, quiet: bool = True) -> OcpPoint:
    """Solve the OCP with one setting; Omega is verified on the scene's own model."""
    kwargs = {"refinements": setting.refinements} if setting.method == "ipopt" else {}
    settings = setting.settings(intervals)
    result, cpu, _ = timed(lambda: optimize(scene, setting.method, settings, quiet=quiet, **kwargs))
    return OcpPoint(
        setting=setting,
        omega=result.omega,
        omega_model=result.omega_model,
        success=result.success,
        status=result.status,
        iterations=result.iterations,
        evaluations=result.evaluations,
        wall_time=result.wall_time,
        cpu_time=cpu,
    )


def ocp_study(scene, plan: StudyPlan, quiet: bool = True) -> tuple[OcpPoint, ...]:
    """Every OCP setting of the plan on ``scene``."""
    return tuple(ocp_point(scene, s, plan.ocp_intervals, quiet) for s in plan.ocp)


# ------------------------------------------------------------------------------------------------
# Charts and tables

MARKERS = "os^DvP*Xh<>"


def speed_chart(study: SceneStudy, path: Path) -> None:
    """Log-log error against CPU time: marker by n, filled compiled, open interpreted."""
    fig = Figure(figsize=(10, 5.5))
    ax = fig.subplots()
    counts = sorted({p.elements for p in study.points})
    for p in study.stable_points:
        marker = MARKERS[counts.index(p.elements) % len(MARKERS)]
        colour = "tab:red" if p.torsion else "tab:blue"
        face = colour if p.mode == "compiled" else "none"
        ax.loglog(p.cpu_time, p.error, marker, color=colour, mfc=face, ms=7, alpha=0.85)
    front = study.pareto()
    ax.loglog(
        [p.cpu_time for p in front], [p.error for p in front], "k-", lw=1, label="Pareto front"
    )
    for tolerance in TOLERANCES:
        ax.axhline(tolerance, color="gray", ls="--", lw=0.8)
        ax.annotate(
            f"{100 * tolerance:g} cm", (0.01, tolerance), xycoords=("axes fraction", "data"),
            ha="left", va="bottom", color="gray",
        )  # fmt: skip
    handles = [
        Line2D([], [], ls="", marker=MARKERS[k % len(MARKERS)], color="k", mfc="none")
        for k in range(len(counts))
    ]
    labels = [f"n = {n}" for n in counts]
    for colour, face, text in (
        ("tab:blue", "tab:blue", "no torsion, compiled"),
        ("tab:blue", "none", "no torsion, interpreted"),
        ("tab:red", "tab:red", "torsion, compiled"),
        ("tab:red", "none", "torsion, interpreted"),
    ):
        handles.append(Line2D([], [], ls="", marker="o", color=colour, mfc=face))
        labels.append(text)
    handles.append(Line2D([], [], color="k", lw=1))
    labels.append("Pareto front")
    ax.legend(handles, labels, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.set_xlabel("CPU time of the integration [s]")
    ax.set_ylabel(r"max$_t$ |r$_E$ - r$_{E,ref}$| [m]")
    ax.set_title(
        f"{study.scene_name}: {study.duration:g} s simulated, against n = "
        f"{study.reference.elements} DOP853 (rtol = atol = {study.reference.tolerance:g})"
    )
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def ocp_chart(points: Sequence[OcpPoint], scene_name: str, path: Path) -> None:
    """Verified Omega against wall time; a failed solve is drawn as a cross.

    A solve whose last iterate cannot be simulated on the scene's model (Omega NaN) is drawn at
    the top edge.
    """
    fig = Figure(figsize=(8, 5))
    ax = fig.subplots()
    ax.set_xscale("log")
    ax.set_yscale("log")
    top_edge = blended_transform_factory(ax.transData, ax.transAxes)
    for k, p in enumerate(points):
        state = "" if p.success else f" - FAILED: {p.status}"
        style = dict(color=f"C{k % 10}", marker="o" if p.success else "x", ms=9, mew=2, ls="")
        if np.isfinite(p.omega):
            ax.plot(p.wall_time, p.omega, label=f"{p.setting.label}{state}", **style)
        else:
            ax.plot(p.wall_time, 0.97, transform=top_edge, clip_on=False,
                    label=f"{p.setting.label}{state}", **style)  # fmt: skip
            ax.annotate("last iterate not simulable: no Omega", (p.wall_time, 0.97),
                        xycoords=top_edge, xytext=(-8, -4), textcoords="offset points",
                        ha="right", va="top", fontsize=7)  # fmt: skip
    ax.set_xlabel("wall time of the whole optimisation, verification included [s]")
    ax.set_ylabel(r"$\Omega$ verified on the scene's model [m]")
    ax.set_title(f"{scene_name}: optimal winch control, Omega (eq. 39) against wall time")
    ax.legend(fontsize=7, loc="best")
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def _number(value: float, spec: str = ".3g") -> str:
    return "-" if not np.isfinite(value) else format(value, spec)


def scene_report(study: SceneStudy) -> str:
    """Markdown: reference, cheapest settings, Pareto front, stability limits, every point."""
    ref = study.reference
    lines = [
        f"## {study.scene_name} ({study.duration:g} s simulated, winch locked)",
        "",
        f"Reference: n = {ref.elements}, DOP853 at rtol = atol = {ref.tolerance:g} on the compiled "
        f"right-hand side ({ref.cpu_time:.1f} s CPU, {ref.wall_time:.1f} s wall). Its own "
        f"uncertainty, max |r_E(RK4, h = {ref.check_step:g} s) - r_E(DOP853)| = "
        f"{ref.check_difference:.2e} m.",
        "",
    ]
    for tolerance in TOLERANCES:
        best = study.cheapest(tolerance)
        text = (
            "no setting"
            if best is None
            else f"{best.label}: error {best.error:.3g} m, {best.cpu_time:.3g} s CPU "
            f"({best.wall_time:.3g} s wall)"
        )
        lines.append(f"- Cheapest with error <= {100 * tolerance:g} cm: {text}")
    lines += ["", "Pareto front (cheapest first):", ""]
    lines += [f"- {p.label}: {p.error:.3g} m, {p.cpu_time:.3g} s CPU" for p in study.pareto()]
    lines += [
        "",
        "RK4 stability limit, bracketed by doubling the step until a run fails (its state "
        "becomes non-finite or a bond residual exceeds numerics.constraint_tolerance = "
        f"{study.constraint_tolerance:g} m):",
        "",
        "| n | torsion | largest stable h [s] | smallest unstable h [s] |",
        "|---:|---|---:|---:|",
    ]
    for n, torsion, stable, unstable in study.stability_limits():
        tried = "not reached" if not np.isfinite(unstable) else f"{unstable:g}"
        lines.append(f"| {n} | {'on' if torsion else 'off'} | {stable:g} | {tried} |")
    front = {id(p) for p in study.pareto()}
    lines += [
        "",
        "Every measured setting (CPU and wall time of the integration only; '-' for an unstable "
        "run, which stopped early):",
        "",
        "| n | h [s] | torsion | mode | steps | error [m] | CPU [s] | wall [s] | Pareto | note |",
        "|---:|---:|---|---|---:|---:|---:|---:|---|---|",
    ]
    for p in sorted(study.points, key=lambda p: (p.torsion, p.elements, p.step, p.mode)):
        note = "" if p.stable else f"unstable: {p.message}"
        lines.append(
            f"| {p.elements} | {p.step:g} | {'on' if p.torsion else 'off'} | {p.mode} | "
            f"{p.steps} | {_number(p.error)} | {_number(p.cpu_time)} | {_number(p.wall_time)} | "
            f"{'yes' if id(p) in front else ''} | {note} |"
        )
    return "\n".join(lines)


def ocp_report(points: Sequence[OcpPoint], scene_name: str, duration: float) -> str:
    """Markdown table of the OCP runs."""
    lines = [
        f"## Optimal winch control on {scene_name} ({duration:g} s horizon)",
        "",
        "Omega verified on the scene's own model; wall and CPU time of the whole `optimize` call "
        "(model build, compiling on a cache miss, solves, verification). A failed solve keeps its "
        "status and is drawn as a cross.",
        "",
        "| setting | Omega verified [m] | Omega on the optimisation model [m] | success | status "
        "| iterations | evaluations | wall [s] | CPU [s] |",
        "|---|---:|---:|---|---|---:|---:|---:|---:|",
    ]
    for p in points:
        lines.append(
            f"| {p.setting.label} | {_number(p.omega, '.3g')} | {_number(p.omega_model, '.3g')} | "
            f"{p.success} | {p.status} | {p.iterations} | {p.evaluations} | {p.wall_time:.1f} | "
            f"{p.cpu_time:.1f} |"
        )
    return "\n".join(lines)


def report(result: SpeedAccuracy) -> str:
    """The whole study as markdown."""
    plan = result.plan
    torsion = ", ".join(map(str, plan.torsion_elements)) or "none"
    head = [
        "# Speed against accuracy",
        "",
        "Written by `cable_ocp.speed_accuracy.run_speed_accuracy`; every number and figure comes "
        f"from this run ({result.cpu_time:.0f} s CPU, {result.wall_time:.0f} s wall in all, "
        "compiling included).",
        "",
        f"- Grid: n = {', '.join(map(str, plan.elements))} without torsion ({plan.stable_steps} "
        f"stable steps each), n = {torsion} with torsion ({plan.torsion_stable_steps} stable "
        "steps each; torsional modes need far smaller steps). Steps are powers of two: from a "
        "guess, doubled until a run fails, then halved below the largest stable one.",
        (
            f"- Compiled (C, cached on disk) for every point; interpreted (CasADi SX) only up to "
            f"{plan.interpreted_work:g} element-steps ((n + 1) x steps) per run."
            if plan.compiled
            else "- Interpreted (CasADi SX) only: nothing compiled."
        ),
        f"- Error: max over the output times (every {plan.output_interval:g} s) of "
        "|r_E - r_E,ref|. Torsion runs are compared with the same (torsion-free) reference; "
        "they start untwisted and nothing twists the cable, so their torsional modes grow only "
        "from what bending couples into them.",
        "- Cost: CPU time (`time.process_time`) of the `integrate` call, after a run of one output "
        "interval on the same model has built, compiled or loaded its Functions: model build, "
        "equilibrium and compiling are excluded.",
        f"- Scope: {plan.scope}",
    ]
    parts = ["\n".join(head)] + [scene_report(s) for s in result.scenes]
    if result.ocp:
        parts.append(ocp_report(result.ocp, result.ocp_scene, result.ocp_duration))
    return "\n\n".join(parts) + "\n"


def run_speed_accuracy(
    out: Path, models_dir: Path, quick: bool = False, quiet: bool = True
) -> SpeedAccuracy:
    """Measure speed against accuracy and write the report and charts into ``out`` atomically.

    Parameters
    ----------
    out : Path
        Folder of ``speed_accuracy.md``, ``speed_accuracy_<scene>.png`` and
        ``ocp_omega_vs_time.png`` (replaced as a whole).
    models_dir : Path
        Folder of the scene files.
    quick : bool
        A tiny version (n = 3, 5 against n = 5, seconds of simulated time, a one-iteration OCP).
    quiet : bool
        No progress messages.

    Returns
    -------
    SpeedAccuracy
    """
    plan = QUICK_PLAN if quick else FULL_PLAN
    cpu, wall = time.process_time(), time.perf_counter()
    scenes = []
    for name, duration in plan.scenes:
        scene = study_scene(load_scene(Path(models_dir) / f"{name}.toml"), plan, duration)
        scenes.append(scene_study(scene, plan, quiet))
    ocp_scene = load_scene(Path(models_dir) / "paper_flat.toml")
    if plan.ocp_duration is not None:
        ocp_scene = ocp_scene.updated({"numerics.duration": plan.ocp_duration})
    ocp = ocp_study(ocp_scene, plan, quiet)
    result = SpeedAccuracy(
        plan=plan,
        scenes=tuple(scenes),
        ocp=ocp,
        ocp_scene=ocp_scene.name,
        ocp_duration=ocp_scene.numerics.duration,
        cpu_time=time.process_time() - cpu,
        wall_time=time.perf_counter() - wall,
    )
    with atomic_directory(out) as folder:
        for study in result.scenes:
            speed_chart(study, folder / f"speed_accuracy_{study.scene_name}.png")
        if result.ocp:
            ocp_chart(result.ocp, result.ocp_scene, folder / "ocp_omega_vs_time.png")
        (folder / "speed_accuracy.md").write_text(report(result))
    return result
