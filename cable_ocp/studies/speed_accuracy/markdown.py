"""The study's markdown report."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from cable_ocp.studies.speed_accuracy.ocp_points import OcpPoint
from cable_ocp.studies.speed_accuracy.plan import TOLERANCES
from cable_ocp.studies.speed_accuracy.result import SpeedAccuracy
from cable_ocp.studies.speed_accuracy.scenes import SceneStudy


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
        r = p.result
        lines.append(
            f"| {p.setting.label} | {_number(r.omega, '.3g')} | {_number(r.omega_model, '.3g')} | "
            f"{r.success} | {r.status} | {r.iterations} | {r.evaluations} | {r.wall_time:.1f} | "
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
        "Written by `cable_ocp.studies.speed_accuracy.run_speed_accuracy`; every number and figure "
        "comes "
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
