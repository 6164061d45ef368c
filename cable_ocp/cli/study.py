"""``cable-ocp study NAME [SCENE] --out DIR``: the convergence, validation and speed studies."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import OUT_HELP, add_command, add_quiet, add_set, scene_from
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.cli.files import results_folder
from cable_ocp.scene.bundled import models_dir, scene_argument

SCENE_STUDIES = ("step", "elements", "end-force")  # each of a scene given
# The others, each with what it runs instead.
OWN_SCENES = {"speed-accuracy": "its own", "stability": "its own", "payout": "paper_flat's rope"}


def add_study_command(commands) -> None:
    """Add ``study`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands,
        "study",
        "convergence, validation, speed-accuracy and stability studies",
        scene=False,
        description="step, elements, end-force: studies of SCENE. speed-accuracy: error vs CPU "
        "time on paper_flat and end_force, and the OCP's Omega vs wall time. stability: largest "
        "stable step vs n, Baumgarte gains, Nelder-Mead vs IPOPT as the knots grow. payout: the "
        "top tension where a line paid out by elements splits one off, against element length.",
    )
    parser.add_argument("name", choices=[*SCENE_STUDIES, *OWN_SCENES], help="the study (see above)")
    parser.add_argument("scene", type=scene_argument, nargs="?",
                        help="the scene of step, elements and end-force: a TOML file or a "
                        "bundled scene's name")  # fmt: skip
    parser.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    add_set(parser, "numerics.step=0.02", "a field of SCENE")
    add_quiet(parser)
    parser.add_argument("--compiled", action="store_true", help="end-force: model compiled to C")
    parser.add_argument(
        "--quick", action="store_true", help="speed-accuracy, stability, payout: a small version"
    )
    parser.set_defaults(run=run_study_command)


def run_study_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp study``: its table printed and written (with its figure) to ``--out``."""
    if args.name in SCENE_STUDIES:
        return _scene_study(args)
    if args.scene is not None:
        raise ValueError(
            f"study {args.name} takes no scene: it runs {OWN_SCENES[args.name]} (see --help)"
        )
    if args.name == "payout":
        return _payout_study(args)
    if args.name == "speed-accuracy":
        from cable_ocp.studies.speed_accuracy import run_speed_accuracy as run
    else:
        from cable_ocp.studies.stability import run_stability as run
    run(args.out, models_dir(), quick=args.quick, quiet=args.quiet)
    print(f"written to {Path(args.out).resolve()}")
    return SUCCESS


def _scene_study(args: argparse.Namespace) -> int:
    """step, elements or end-force of the scene given: a table, and elements' figure."""
    from cable_ocp.studies import convergence as studies

    if args.scene is None:
        raise ValueError(f"study {args.name} needs a scene file, e.g. models/paper_flat.toml")
    scene = scene_from(args)
    with results_folder(args.out) as folder:
        if args.name == "step":
            result = studies.step_halving(scene, quiet=args.quiet)
        elif args.name == "elements":
            result = studies.element_convergence(scene, quiet=args.quiet)
            result.chart(folder / "element_convergence.png")
        else:
            result = studies.end_positions(
                scene, studies.END_FORCE_SETTINGS, quiet=args.quiet, compiled=args.compiled
            )
        text = result.table()
        (folder / f"{args.name}.md").write_text(f"# {args.name} study of {scene.name}\n\n{text}\n")
    print(text)
    print(f"written to {Path(args.out).resolve()}")
    return SUCCESS


def _payout_study(args: argparse.Namespace) -> int:
    """Acceptance 4 of the line on the drum: the top tension at the splits, figure and table."""
    from cable_ocp.studies import payout_validation as pv

    runs, finest = pv.insertion_runs(
        pv.TRANSIENT_LENGTHS[:1] if args.quick else pv.TRANSIENT_LENGTHS
    )
    rows = ["| Delta [m] | new top [m] | splits | largest jump | against the finest |",
            "|---:|---:|---:|---:|---:|"]  # fmt: skip
    for delta, run in runs.items():
        t = pv.transient(run, finest)
        rows.append(
            f"| {delta:g} | {t.new_top_length:.3g} | {t.changes} | {100 * t.jump:.3f} % "
            f"| {100 * t.against_finest:.3f} % |"
        )
    text = "\n".join(rows)
    with results_folder(args.out) as folder:
        pv.transient_chart(runs, finest, folder / "payout_transients.png")
        (folder / "payout.md").write_text(
            "# Top tension at the splits: pay-out 100 -> 200 m at 0.5 m/s under the tow\n\n"
            f"Jumps relative to the static top tension; reference Delta = "
            f"{pv.FINEST_TRANSIENT} m.\n\n{text}\n"
        )
    print(text)
    print(f"written to {Path(args.out).resolve()}")
    return SUCCESS
