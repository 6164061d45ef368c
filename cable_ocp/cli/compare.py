"""``cable-ocp compare SCENES --out DIR``: a shooting solver against Nelder-Mead in one table."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import OUT_HELP, add_command, scene_from
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.cli.files import results_folder
from cable_ocp.cli.optimiser_options import (
    add_optimiser_options,
    check_step,
    elapsed,
    optimize_settings,
)
from cable_ocp.control.solvers import KNOTS, SHOOTING, SOLVERS, solver_for
from cable_ocp.scene.bundled import scene_argument


def add_compare_command(commands) -> None:
    """Add ``compare`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands, "compare", "a shooting solver against Nelder-Mead in one table", scene=False
    )
    parser.add_argument("scenes", type=scene_argument, nargs="+",
                        help="scene files (TOML) or bundled scenes' names")  # fmt: skip
    parser.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    add_optimiser_options(parser)
    parser.set_defaults(run=run_compare_command)


def run_compare_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp compare``: every scene by three solvers, one table in comparison.md."""
    from dataclasses import replace

    from cable_ocp.control.optimization import optimize
    from cable_ocp.simulation.statics import check_scene_start

    scenes = [scene_from(args, path) for path in args.scenes]  # all checked before solving
    for scene in scenes:
        check_step(scene, args.step)
        check_scene_start(scene)
    simplex_solver = solver_for(KNOTS.name, None)
    if args.solver is not None and SOLVERS[args.solver].transcription is not SHOOTING:
        shooting_solvers = [n for n, e in SOLVERS.items() if e.transcription is SHOOTING]
        raise ValueError(
            f"--solver {args.solver}: compare runs {SOLVERS[simplex_solver].label} anyway, beside "
            f"a shooting solver; give --solver {' or '.join(shooting_solvers)}"
        )
    shooting = optimize_settings(args, beside=simplex_solver)
    simplex = optimize_settings(args, simplex_solver, beside=shooting.solver)
    spline = replace(shooting, grid=replace(shooting.grid, control="spline"))
    name = shooting.solver
    output = {"quiet": args.quiet, "verbose": args.verbose}
    rows = []
    for scene in scenes:
        runs = [
            (f"{name}, hermite", optimize(scene, settings=shooting, **output)),
            (f"{name}, spline", optimize(scene, settings=spline, **output)),
            (f"{simplex_solver}, spline", optimize(scene, settings=simplex, **output)),
        ]
        rows += [(scene.name, label, r) for label, r in runs]
    lines = [
        "| scene | solver | control | Omega verified [m] | success | iterations | evaluations "
        "| wall [s] | build [s] |",
        "|---|---|---|---:|---|---:|---:|---:|---:|",
    ]
    for name, label, r in rows:
        lines.append(
            f"| {name} | {label} | {r.control} | {r.omega:.2e} | {r.success} | {r.iterations} "
            f"| {r.evaluations} | {r.wall_time:.1f} | {r.build_time:.1f} |"
        )
    lines.append(
        f"\nwall: optimize()'s own time (build included); the whole command took "
        f"{elapsed(args):.1f} s"
    )
    table = "\n".join(lines)
    with results_folder(args.out) as folder:
        (folder / "comparison.md").write_text(table + "\n")
    print(table)
    return SUCCESS
