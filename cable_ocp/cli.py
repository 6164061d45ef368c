"""The command line: ``cable-ocp simulate|validate|study|bench``."""

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
    from cable_ocp.bench import rk4_report

    rk4_report(MODELS_DIR, quick=args.quick)
    return 0


def _study(args) -> int:
    from cable_ocp import studies
    from cable_ocp.output import atomic_directory

    scene = load_scene(args.scene, parse_overrides(args.set))
    with atomic_directory(args.out) as folder:
        if args.name == "step":
            result = studies.step_halving(scene, quiet=args.quiet)
        elif args.name == "elements":
            result = studies.element_convergence(scene, quiet=args.quiet)
            result.chart(folder / "element_convergence.png")
        else:
            result = studies.end_positions(scene, studies.END_FORCE_SETTINGS, quiet=args.quiet)
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

    study = commands.add_parser("study", help="convergence and validation studies of a scene")
    study.add_argument("name", choices=["step", "elements", "end-force"])
    study.add_argument("scene", type=Path)
    study.add_argument("--out", type=Path, required=True)
    study.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    study.add_argument("--quiet", action="store_true")
    study.set_defaults(run=_study)

    bench = commands.add_parser("bench", help="speed benchmarks against baselines")
    bench.add_argument("--quick", action="store_true", help="fewer steps at n = 100")
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
