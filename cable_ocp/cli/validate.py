"""``cable-ocp validate [SCENE] [--out DIR]``: the statics against the analytic catenary."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import OUT_HELP, SCENE_HELP, add_command, integer
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.cli.files import results_folder
from cable_ocp.scene.bundled import models_dir, scene_argument


def add_validate_command(commands) -> None:
    """Add ``validate`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands, "validate", "statics check against the analytic catenary", scene=False
    )
    parser.add_argument("scene", type=scene_argument, nargs="?",
                        help=SCENE_HELP + "; default: catenary")  # fmt: skip
    parser.add_argument("--elements", type=integer(1, 1000), nargs="+", default=[15, 5, 30, 60],
                        help="element counts n to check, listed in ascending order; the figure "
                        "shows the first given")  # fmt: skip
    parser.add_argument("--out", type=Path, help="folder for the comparison figure; " + OUT_HELP)
    parser.set_defaults(run=run_validate_command)


def run_validate_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp validate``: the errors per n printed, the first n's figure in ``--out``."""
    import numpy as np

    from cable_ocp import plots
    from cable_ocp.scene.schema import load_scene
    from cable_ocp.studies.catenary import catenary_shape
    from cable_ocp.studies.validation import catenary_check

    scene = load_scene(args.scene or models_dir() / "catenary.toml")
    print("catenary (paper 4.1): largest relative errors against the analytic catenary, in %")
    print(f"{'n':>5}{'eps_x [%]':>12}{'eps_z [%]':>12}{'inextensible [%]':>18}"
          f"{'top tension [%]':>17}")  # fmt: skip
    checks = [catenary_check(scene, n) for n in args.elements]
    for c in sorted(checks, key=lambda check: check.elements):
        print(
            f"{c.elements:>5}{100 * c.max_error_x:>12.4f}{100 * c.max_error_z:>12.4f}"
            f"{100 * c.max_error_inextensible:>18.5f}{100 * c.top_tension_error:>17.2e}"
        )
    if args.out:
        check = checks[0]
        s = np.linspace(0, scene.cable.length, 300)
        c, e = scene.cable, scene.end
        x, z, _ = catenary_shape(s, c.length, c.mass_per_length * scene.environment.gravity,
                                 float(np.hypot(*e.force[:2])), e.force[2],
                                 c.youngs_modulus * c.cross_section_area)  # fmt: skip
        with results_folder(args.out) as folder:
            plots.catenary_comparison(check.joints, np.vstack([x, z]), folder / "catenary.png",
                                      scene.name, check.elements)  # fmt: skip
        print(f"figure written to {Path(args.out).resolve() / 'catenary.png'}")
    return SUCCESS
