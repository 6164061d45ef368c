"""The command line: ``cable-ocp simulate|optimize|compare|validate|study|bench``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from cable_ocp.scene import load_scene

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

MODELS_DIR = Path(__file__).resolve().parent.parent / "models"


def parse_overrides(pairs: list[str]) -> dict:
    """``["model.elements=30", "top.motion='tow'"]`` -> ``{"model.elements": 30, ...}``.

    Values are read as TOML, so numbers, booleans, strings and arrays keep their types; a bare
    word is taken as a string.
    """
    overrides = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        if not sep:
            raise ValueError(f"--set {pair!r}: expected KEY=VALUE, e.g. model.elements=30")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except tomllib.TOMLDecodeError:
            value = text
        overrides[key.strip()] = value
    return overrides


def _simulate(args) -> int:
    from cable_ocp import plots
    from cable_ocp.output import atomic_directory
    from cable_ocp.simulation import simulate

    scene = load_scene(args.scene, parse_overrides(args.set))
    knots = [float(v) for v in args.knots.split(",")] if args.knots else None
    trajectory = simulate(scene, winch=knots, quiet=args.quiet)
    hills = scene.seabed.hills
    with atomic_directory(args.out) as folder:
        trajectory.save(folder / "trajectory")
        plots.end_trajectory(trajectory, path=folder / "end_trajectory.png")
        plots.clearance(trajectory, scene.seabed.clearance, path=folder / "clearance.png")
        plots.cable_shapes(trajectory, hills=hills, clearance_depth=scene.seabed.clearance,
                           path=folder / "cable_shapes.png")  # fmt: skip
        plots.winch_angle(trajectory, bounds=(scene.winch.angle_min, scene.winch.angle_max),
                          path=folder / "winch_angle.png")  # fmt: skip
        summary = {
            "scene": scene.name,
            "omega_m": trajectory.omega,
            "end_rise_m": float(trajectory.end[:, 2].max() - trajectory.end[0, 2]),
            "final_end_position_m": trajectory.end[-1].tolist(),
            "max_top_tension_N": float(trajectory.top_tension.max()),
        }
        (folder / "summary.json").write_text(json.dumps(summary, indent=1))
    print(json.dumps(summary, indent=1))
    print(f"results and figures written to {Path(args.out).resolve()}")
    return 0


def _ipopt_settings(args):
    from cable_ocp.ocp import IpoptSettings

    return IpoptSettings(
        elements=args.elements,
        step=args.step,
        intervals=args.intervals,
        control=args.control,
        hessian=args.hessian,
        max_iter=args.max_iter,
    )


def _nelder_mead_settings(args):
    from cable_ocp.nelder_mead import NelderMeadSettings

    return NelderMeadSettings(
        elements=args.elements, step=args.step, max_evaluations=args.max_evaluations
    )


def _optimize(args) -> int:
    from cable_ocp import plots
    from cable_ocp.optimization import optimize
    from cable_ocp.output import atomic_directory
    from cable_ocp.simulation import simulate

    scene = load_scene(args.scene, parse_overrides(args.set))
    if args.method == "ipopt":
        result = optimize(scene, "ipopt", _ipopt_settings(args), quiet=args.quiet,
                          refinements=args.refinements)  # fmt: skip
    else:
        result = optimize(scene, "nelder-mead", _nelder_mead_settings(args), quiet=args.quiet)
    locked = simulate(scene, quiet=True)
    hills, bounds = scene.seabed.hills, (scene.winch.angle_min, scene.winch.angle_max)
    labels = ["locked winch", f"optimised ({result.method})"]
    with atomic_directory(args.out) as folder:
        result.save(folder)
        pair = [locked, result.trajectory] if result.trajectory is not None else [locked]
        labels = labels[: len(pair)]
        plots.end_trajectory(pair, labels, path=folder / "end_trajectory.png")
        plots.clearance(pair, scene.seabed.clearance, labels, path=folder / "clearance.png")
        plots.winch_angle(pair, labels, bounds, path=folder / "winch_angle.png")
        plots.cable_shapes(pair[-1], hills=hills, clearance_depth=scene.seabed.clearance,
                           path=folder / "cable_shapes.png")  # fmt: skip
    print(
        f"{result.method}: success = {result.success} ({result.status}); Omega = "
        f"{result.omega:.3g} m verified on n = {scene.model.elements} (locked: {locked.omega:.3f}"
        f" m); iterations {result.iterations}, evaluations {result.evaluations}, wall "
        f"{result.wall_time:.1f} s (build {result.build_time:.1f} s, solver {result.solve_time:.1f}"
        f" s of which functions {result.function_time:.1f} s)"
    )
    print(f"results and figures written to {Path(args.out).resolve()}")
    if not result.success:
        print(f"cable-ocp optimize: the optimiser failed: {result.status}", file=sys.stderr)
        return 3
    return 0


def _compare(args) -> int:
    from dataclasses import replace

    from cable_ocp.optimization import optimize
    from cable_ocp.output import atomic_directory

    rows = []
    for path in args.scenes:
        scene = load_scene(path, parse_overrides(args.set))
        base = _ipopt_settings(args)
        runs = [
            ("ipopt, hermite", optimize(scene, "ipopt", base, quiet=True)),
            ("ipopt, spline",
             optimize(scene, "ipopt", replace(base, control="spline"), quiet=True)),
            ("nelder-mead, spline",
             optimize(scene, "nelder-mead", _nelder_mead_settings(args), quiet=args.quiet)),
        ]  # fmt: skip
        rows += [(scene.name, label, r) for label, r in runs]
    lines = [
        "| scene | method | control | Omega verified [m] | success | iterations | evaluations "
        "| wall [s] | build [s] |",
        "|---|---|---|---:|---|---:|---:|---:|---:|",
    ]
    for name, label, r in rows:
        lines.append(
            f"| {name} | {label} | {r.control} | {r.omega:.2e} | {r.success} | {r.iterations} "
            f"| {r.evaluations} | {r.wall_time:.1f} | {r.build_time:.1f} |"
        )
    table = "\n".join(lines)
    with atomic_directory(args.out) as folder:
        (folder / "comparison.md").write_text(table + "\n")
    print(table)
    return 0


def _add_optimiser_options(parser) -> None:
    parser.add_argument(
        "--elements",
        type=int,
        default=3,
        help="elements of the optimisation model (verification uses the scene's)",
    )
    parser.add_argument("--step", type=float, default=0.5, help="RK4 step of the optimisation [s]")
    parser.add_argument("--intervals", type=int, default=42, help="shooting intervals (IPOPT)")
    parser.add_argument("--control", choices=["hermite", "spline"], default="hermite")
    parser.add_argument("--hessian", choices=["limited-memory", "exact"], default="limited-memory")
    parser.add_argument("--max-iter", type=int, default=300, help="IPOPT iterations")
    parser.add_argument("--max-evaluations", type=int, default=3000, help="Nelder-Mead runs")
    parser.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    parser.add_argument("--quiet", action="store_true")  # fmt: skip


def _validate(args) -> int:
    import numpy as np

    from cable_ocp import plots
    from cable_ocp.catenary import catenary_shape
    from cable_ocp.validation import catenary_check

    scene = load_scene(args.scene)
    print("catenary (paper 4.1): max relative errors eq. 35-36, in %")
    print(f"{'n':>5}{'eps_x':>10}{'eps_z':>10}{'inextensible':>14}{'top tension':>13}")
    checks = [catenary_check(scene, n) for n in args.elements]
    for c in checks:
        print(
            f"{c.elements:>5}{100 * c.max_error_x:>10.4f}{100 * c.max_error_z:>10.4f}"
            f"{100 * c.max_error_inextensible:>14.5f}{100 * c.top_tension_error:>13.2e}"
        )
    if args.out:
        from cable_ocp.output import atomic_directory

        check = checks[0]
        s = np.linspace(0, scene.cable.length, 300)
        c, e = scene.cable, scene.end
        x, z, _ = catenary_shape(s, c.length, c.mass_per_length * scene.environment.gravity,
                                 float(np.hypot(*e.force[:2])), e.force[2],
                                 c.youngs_modulus * c.cross_section_area)  # fmt: skip
        with atomic_directory(args.out) as folder:
            plots.catenary_comparison(check.joints, np.vstack([x, z]), folder / "catenary.png")
        print(f"figure written to {Path(args.out).resolve() / 'catenary.png'}")
    return 0


def _bench(args) -> int:
    from cable_ocp import bench
    from cable_ocp.moordyn_compare import moordyn_report

    if args.hessian:
        bench.hessian_report(MODELS_DIR)
        return 0
    parts = {
        "rk4": bench.rk4_report,
        "moordyn": moordyn_report,
        "ocp": bench.ocp_report,
    }
    for name in args.only or list(parts):
        parts[name](MODELS_DIR, quick=args.quick)
        print()
    return 0


def _study(args) -> int:
    from cable_ocp import studies
    from cable_ocp.output import atomic_directory

    if args.name in ("speed-accuracy", "stability"):
        if args.scene is not None:
            raise ValueError(f"study {args.name} takes no scene: it runs its own (see --help)")
        if args.name == "speed-accuracy":
            from cable_ocp.speed_accuracy import run_speed_accuracy as run
        else:
            from cable_ocp.stability import run_stability as run
        run(args.out, MODELS_DIR, quick=args.quick, quiet=args.quiet)
        print(f"written to {Path(args.out).resolve()}")
        return 0
    if args.scene is None:
        raise ValueError(f"study {args.name} needs a scene file, e.g. models/paper_flat.toml")
    scene = load_scene(args.scene, parse_overrides(args.set))
    with atomic_directory(args.out) as folder:
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
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``cable-ocp``."""
    parser = argparse.ArgumentParser(prog="cable-ocp", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)

    sim = commands.add_parser("simulate", help="simulate a scene and write results and figures")
    sim.add_argument("scene", type=Path)
    sim.add_argument("--out", type=Path, required=True, help="results folder (written atomically)")
    sim.add_argument("--knots", help="winch knot angles phi_1..phi_p in rad, comma-separated")
    sim.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene field, e.g. --set model.elements=30")  # fmt: skip
    sim.add_argument("--quiet", action="store_true", help="no progress bar")
    sim.set_defaults(run=_simulate)

    val = commands.add_parser("validate", help="statics check against the analytic catenary")
    val.add_argument("scene", type=Path, nargs="?", default=MODELS_DIR / "catenary.toml")
    val.add_argument("--elements", type=int, nargs="+", default=[15, 5, 30, 60])
    val.add_argument("--out", type=Path, help="folder for the comparison figure")
    val.set_defaults(run=_validate)

    opt = commands.add_parser("optimize", help="optimise the winch angle of a scene")
    opt.add_argument("scene", type=Path)
    opt.add_argument("--method", choices=["ipopt", "nelder-mead"], default="ipopt")
    opt.add_argument("--out", type=Path, required=True)
    opt.add_argument("--refinements", type=int, default=3, help="model-correction solves")
    _add_optimiser_options(opt)
    opt.set_defaults(run=_optimize)

    cmp = commands.add_parser("compare", help="IPOPT against Nelder-Mead in one table")
    cmp.add_argument("scenes", type=Path, nargs="+")
    cmp.add_argument("--out", type=Path, required=True)
    _add_optimiser_options(cmp)
    cmp.set_defaults(run=_compare)

    study = commands.add_parser(
        "study",
        help="convergence, validation, speed-accuracy and stability studies",
        description="step, elements, end-force: studies of SCENE. speed-accuracy: error vs CPU "
        "time on paper_flat and end_force, and the OCP's Omega vs wall time. stability: largest "
        "stable step vs n, Baumgarte gains, Nelder-Mead vs IPOPT as the knots grow.",
    )
    study.add_argument(
        "name", choices=["step", "elements", "end-force", "speed-accuracy", "stability"]
    )
    study.add_argument("scene", type=Path, nargs="?")
    study.add_argument("--out", type=Path, required=True)
    study.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    study.add_argument("--quiet", action="store_true")
    study.add_argument("--compiled", action="store_true", help="end-force: model compiled to C")
    study.add_argument(
        "--quick", action="store_true", help="speed-accuracy, stability: a small version"
    )
    study.set_defaults(run=_study)

    bench = commands.add_parser("bench", help="speed benchmarks against baselines")
    bench.add_argument(
        "--quick", action="store_true", help="scene steps only, short MoorDyn runs, small OCP"
    )
    bench.add_argument(
        "--only", nargs="+", choices=["rk4", "moordyn", "ocp"], help="run only these parts"
    )
    bench.add_argument(
        "--hessian", action="store_true", help="IPOPT exact vs limited-memory Hessian instead"
    )
    bench.set_defaults(run=_bench)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``cable-ocp``; returns the exit code."""
    args = build_parser().parse_args(argv)
    try:
        return args.run(args)
    except (ValueError, RuntimeError) as error:
        print(f"cable-ocp {args.command}: error: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
