"""``cable-ocp bench --only grid``: the adaptive control grid against the uniform one (issue 43).

One run solves every scene twice with the default ``optimize`` (Gauss-Newton, model correction,
verified on the scene's model): on the uniform default grid (about 5 s intervals) and with
``GridSettings(adaptive=True)`` (:mod:`cable_ocp.control.adaptive_grid`), after an untimed solve
on each grid that compiles the scene's models and makes each grid's arrays once, in alternating
order. The scenes are the robustness bench's whole-space scenes of two seeds
(:mod:`cable_ocp.studies.scene_space`) and ``paper_hill``. The acceptance of issue 43, printed
per seed:

- Omega: the adaptive grid's within :data:`OMEGA_SHARE` of the uniform one's (or better), as a
  median and as the share of the cases;
- parameters: the adaptive median at most :data:`PARAMETER_SHARE` of the uniform median;
- wall time: the medians side by side (the adaptive one not higher), with the totals and the
  median of the per-scene ratio.

:func:`chart_points` adds the speed-accuracy points of the control grid: uniform grids of several
sizes, the adaptive grid and the paper's knots (a spline, by Gauss-Newton), Omega against the
number of parameters, which :func:`cable_ocp.plots.grid.omega_against_parameters` draws
(``cable-ocp bench --only grid --out FOLDER``).
"""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from cable_ocp.control.optimization import optimize
from cable_ocp.control.settings import GridSettings
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import load_scene
from cable_ocp.studies.scene_space import space_cases, space_scene

OMEGA_SHARE = 1.05  # the adaptive Omega at most this times the uniform one
PARAMETER_SHARE = 0.5  # the adaptive median of parameters at most this times the uniform one
GRIDS = ("uniform", "adaptive")
# Uniform grids of the chart: every k-th node of the default grid (and one twice as fine).
CHART_SPACINGS = (8, 4, 2, 1)
LONG_CASE = (0, 0)  # seed and case of the chart's long whole-space scene (508 s)


def solve(scene, grid: str) -> dict:
    """The default ``optimize`` of ``scene`` on the uniform or the adaptive grid: its figures."""
    settings = GridSettings(adaptive=grid == "adaptive")
    started = time.perf_counter()
    result = optimize(scene, grid=settings, quiet=True)
    notes = [part for part in result.notes.split("; ") if part.startswith("adaptive grid")]
    return {
        "success": bool(result.success),
        "omega": float(result.omega),
        "parameters": int(result.parameters.size),
        "wall": time.perf_counter() - started,
        "refinement": notes[0] if notes else "",
    }


def compare(scene, order: int = 0) -> dict:
    """Both grids on ``scene``: ``{"uniform": figures, "adaptive": figures}`` (:func:`solve`).

    An untimed solve on each grid first (without model correction) compiles the scene's models
    (cached on disk), which the first timed solve would pay alone (10-20 s against 1-5 s on
    whole-space seed 1, measured 2026-12-05), and makes each grid's arrays once (the adaptive
    grid's candidates, their bound rows and sweep: whole-space seed 0 case 8's coarsening took
    1.04 s in the first adaptive solve of its process, 0.68 s in the next, measured 2026-12-06,
    where only the uniform grid had been solved before); ``order`` odd then runs the adaptive
    grid first.
    """
    for grid in GRIDS:
        optimize(scene, grid=GridSettings(adaptive=grid == "adaptive"), quiet=True, refinements=0)
    grids = GRIDS if order % 2 == 0 else GRIDS[::-1]
    return {grid: solve(scene, grid) for grid in grids}


def space_rows(cases: int, seed: int, first: int = 0, quiet: bool = False) -> list[dict]:
    """The whole-space cases ``first .. cases - 1`` of ``seed``, compared (each printed)."""
    rows = []
    for k, overrides in enumerate(space_cases(cases, seed)):
        if k < first:
            continue
        with tempfile.TemporaryDirectory(prefix="cable_ocp-grid-") as folder:
            scene = space_scene(overrides, Path(folder))
            row = {"seed": seed, "case": k, "duration": scene.numerics.duration}
            row.update(compare(scene, k))
        rows.append(row)
        if not quiet:
            print(row_text(row), flush=True)
    return rows


def paper_hill_row(quiet: bool = False) -> dict:
    """``paper_hill`` compared."""
    row = {"seed": None, "case": "paper_hill", "duration": 210.0}
    row.update(compare(load_scene(scene_path("paper_hill"))))
    if not quiet:
        print(row_text(row), flush=True)
    return row


def row_text(row: dict) -> str:
    """One case: both grids' Omega, parameters and wall time, and the adaptive rounds."""
    u, a = row["uniform"], row["adaptive"]
    ratio = a["omega"] / u["omega"] if u["omega"] > 0 else float("nan")
    name = row["case"] if row["seed"] is None else f"seed {row['seed']} case {row['case']:2d}"
    return (
        f"  {name} (T = {row['duration']:g} s): Omega {u['omega']:.4g} m uniform, "
        f"{a['omega']:.4g} m adaptive (x{ratio:.3f}); parameters {u['parameters']} / "
        f"{a['parameters']}; wall {u['wall']:.2f} / {a['wall']:.2f} s"
        f"{'' if u['success'] and a['success'] else ' (a solve failed)'}; {a['refinement']}"
    )


def summary(rows: list[dict]) -> dict:
    """The acceptance figures over the cases where both grids succeeded (module docstring)."""
    both = [r for r in rows if r["uniform"]["success"] and r["adaptive"]["success"]]
    ratios = np.array([r["adaptive"]["omega"] / r["uniform"]["omega"] for r in both])

    def median(grid: str, figure: str) -> float:
        return float(np.median([r[grid][figure] for r in both])) if both else float("nan")

    figures = {
        "cases": len(rows),
        "both": len(both),
        "adaptive_only": sum(
            r["adaptive"]["success"] and not r["uniform"]["success"] for r in rows
        ),
        "uniform_only": sum(r["uniform"]["success"] and not r["adaptive"]["success"] for r in rows),
        "ratio_median": float(np.median(ratios)) if both else float("nan"),
        "ratio_worst": float(np.max(ratios)) if both else float("nan"),
        "within": int(np.sum(ratios <= OMEGA_SHARE)),
    }
    for grid in GRIDS:
        figures[f"{grid}_parameters"] = median(grid, "parameters")
        figures[f"{grid}_wall"] = median(grid, "wall")
        figures[f"{grid}_wall_total"] = float(sum(r[grid]["wall"] for r in both))
    per_scene = [r["adaptive"]["wall"] / r["uniform"]["wall"] for r in both]
    figures["wall_ratio_median"] = float(np.median(per_scene)) if both else float("nan")
    figures["faster"] = int(sum(ratio < 1.0 for ratio in per_scene))
    figures["accepted"] = bool(
        both
        and figures["ratio_median"] <= OMEGA_SHARE
        and figures["adaptive_parameters"] <= PARAMETER_SHARE * figures["uniform_parameters"]
        and figures["adaptive_wall"] <= figures["uniform_wall"]
    )
    return figures


def summary_text(figures: dict, what: str) -> str:
    """The acceptance figures of :func:`summary` as lines."""
    f = figures
    return "\n".join(
        [
            f"{what}: {f['both']} of {f['cases']} solved on both grids (adaptive only "
            f"{f['adaptive_only']}, uniform only {f['uniform_only']})",
            f"  Omega adaptive / uniform: median {f['ratio_median']:.4f}, worst "
            f"{f['ratio_worst']:.4f}; within {OMEGA_SHARE - 1:.0%} on {f['within']} of {f['both']}",
            f"  parameters, median: uniform {f['uniform_parameters']:g}, adaptive "
            f"{f['adaptive_parameters']:g} (goal: at most {PARAMETER_SHARE:g} of it)",
            f"  optimize wall time, median: uniform {f['uniform_wall']:.2f} s, adaptive "
            f"{f['adaptive_wall']:.2f} s",
            f"    in all: uniform {f['uniform_wall_total']:.1f} s, adaptive "
            f"{f['adaptive_wall_total']:.1f} s; per scene adaptive / uniform: median "
            f"{f['wall_ratio_median']:.3f}, faster on {f['faster']} of {f['both']}",
            f"  issue 43's acceptance: {'met' if f['accepted'] else 'not met'}",
        ]
    )


def chart_points(scene, quiet: bool = False) -> list[dict]:
    """Omega against parameters on ``scene``: uniform grids, the adaptive grid, the knots' spline.

    Each point: ``{"label", "kind", "parameters", "omega", "wall"}``; a grid whose solve fails
    is left out (printed).
    """
    duration = scene.numerics.duration
    uniform = optimize(scene, quiet=True)
    count = uniform.parameters.size // 2
    default = np.linspace(0.0, duration, count + 1)
    grids = []
    for spacing in CHART_SPACINGS:
        nodes = np.unique(np.r_[default[::spacing], duration])
        grids.append(("uniform", f"every {spacing}", GridSettings(nodes=tuple(nodes))))
    grids.append(("uniform", "twice as fine", GridSettings(intervals=2 * count)))
    grids.append(("adaptive", "adaptive (among a grid twice as fine)", GridSettings(adaptive=True)))
    among_default = GridSettings(adaptive=True, adaptive_finest=1)
    grids.append(("adaptive", "adaptive, among the default grid's nodes", among_default))
    grids.append(("spline", f"{scene.winch.knots} knots", GridSettings(control="spline")))
    points = []
    for kind, label, grid in grids:
        started = time.perf_counter()
        try:
            result = optimize(scene, grid=grid, quiet=True)
        except ValueError as error:  # a grid that does not fit the scene's steps
            print(f"    {kind} {label}: not run ({error})", flush=True)
            continue
        point = {
            "label": label,
            "kind": kind,
            "parameters": int(result.parameters.size),
            "omega": float(result.omega),
            "wall": time.perf_counter() - started,
        }
        if not quiet:
            state = "" if result.success else f" (failed: {result.status[:60]})"
            print(
                f"    {kind} {label}: {point['parameters']} parameters, Omega "
                f"{point['omega']:.4g} m, {point['wall']:.1f} s{state}",
                flush=True,
            )
        if result.success:
            points.append(point)
    return points


def chart_scenes(folder: Path) -> dict:
    """The chart's scenes by name: paper_hill, survey and a long whole-space scene."""
    seed, case = LONG_CASE
    long = space_scene(space_cases(case + 1, seed)[case], folder)
    return {
        "paper_hill": load_scene(scene_path("paper_hill")),
        "survey": load_scene(scene_path("survey")),
        f"whole-space seed {seed} case {case} (T = {long.numerics.duration:g} s)": long,
    }


def report(cases: int, seed: int, chart: bool = False) -> dict:
    """The grid bench: seeds ``seed`` and ``seed + 1`` and paper_hill (and the chart's points).

    Returns ``{"rows": {seed: rows}, "summaries": {seed: summary}, "paper_hill": row}``, with
    ``"chart": {scene name: points}`` (:func:`chart_points`) when ``chart``.
    """
    print(f"adaptive control grid against the uniform default, {cases} cases a seed", flush=True)
    figures: dict = {"rows": {}, "summaries": {}}
    for s in (seed, seed + 1):
        rows = space_rows(cases, s)
        figures["rows"][s] = rows
        figures["summaries"][s] = summary(rows)
        print(summary_text(figures["summaries"][s], f"whole-space scenes, seed {s}"), flush=True)
    hill = paper_hill_row()
    figures["paper_hill"] = hill
    fewer = hill["adaptive"]["parameters"] < hill["uniform"]["parameters"]
    better = hill["adaptive"]["omega"] <= hill["uniform"]["omega"]
    print(
        f"paper_hill: Omega at least today's: {'yes' if better else 'no'}; fewer parameters: "
        f"{'yes' if fewer else 'no'}",
        flush=True,
    )
    if chart:
        with tempfile.TemporaryDirectory(prefix="cable_ocp-grid-") as folder:
            figures["chart"] = {}
            for name, scene in chart_scenes(Path(folder)).items():
                print(f"  chart: {name}", flush=True)
                figures["chart"][name] = chart_points(scene)
    return figures
