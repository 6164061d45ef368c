"""``cable-ocp mpc SCENE --out DIR``: a closed-loop run with its figures and figures of merit."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from cable_ocp.control.closed_loop.settings import SOLVERS, MpcSettings


def _weight(text: str) -> float:
    """An argparse type: a finite number >= 0 (a weight of the objective)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r:.40}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"{text!r:.40} is out of range: must be finite and >= 0")
    return value


def add_mpc_command(subparsers) -> None:
    """Add the ``mpc`` command to the ``cable-ocp`` sub-command parsers."""
    parser = subparsers.add_parser(
        "mpc",
        help="closed-loop winch control: receding-horizon IPOPT driving the scene's model",
        description="Closed-loop winch control of SCENE: every --sample seconds a receding-"
        "horizon OCP on a reduced model is solved from the measured state; the scene's own model "
        "(with its heave, e.g. --set top.heave.amplitude=1 --set top.heave.period=8) is the "
        "plant. Writes mpc.nc (the run, netCDF), summary.json and figures to --out.",
    )
    parser.add_argument("scene", type=Path)
    parser.add_argument("--out", type=Path, required=True, help="results folder (atomic)")
    defaults = MpcSettings()
    parser.add_argument(
        "--horizon", type=float, default=defaults.horizon, help="prediction horizon [s]"
    )
    parser.add_argument(
        "--sample", type=float, default=defaults.sample, help="time between solves [s]"
    )
    parser.add_argument(
        "--interval", type=float, default=defaults.interval, help="interval of the plan [s]"
    )
    parser.add_argument(
        "--elements", type=int, default=defaults.elements, help="elements of the reduced model"
    )
    parser.add_argument(
        "--step", type=float, default=defaults.step, help="RK4 step of the reduced model [s]"
    )
    parser.add_argument(
        "--solver",
        choices=SOLVERS,
        default=defaults.solver,
        help="gauss-newton: one Gauss-Newton step per sample (real-time iteration); ipopt: IPOPT",
    )
    parser.add_argument(
        "--no-heave-feedback",
        action="store_true",
        help="apply the plan only (no pay-out of the measured heave)",
    )
    parser.add_argument(
        "--heave-filter",
        type=float,
        default=defaults.heave_filter,
        help="time constant of the heave low-pass [s]",
    )
    parser.add_argument(
        "--heave-margin",
        type=float,
        default=defaults.heave_margin,
        help="room kept for the heave feedback, 0..1",
    )
    parser.add_argument(
        "--limiter-band",
        type=float,
        default=defaults.limiter_band,
        help="width of the plant's soft limiter at each end of the winch range [rad]",
    )
    parser.add_argument(
        "--rate-weight",
        type=_weight,
        default=defaults.rate_weight,
        help="pay-out speed weight [s^2]",
    )
    parser.add_argument(
        "--max-iter", type=int, default=defaults.max_iter, help="iterations per solve"
    )
    parser.add_argument(
        "--open-loop",
        action="store_true",
        help="also optimise open loop (without the heave) and simulate that profile as a reference",
    )
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene field, e.g. --set top.heave.amplitude=1",
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(run=run_mpc_command)


def run_mpc_command(args) -> int:
    """Run ``cable-ocp mpc``; returns the exit code (3 if a solve failed)."""
    from cable_ocp.cli import parse_overrides
    from cable_ocp.control.closed_loop.loop import mpc
    from cable_ocp.plots import closed_loop as plots
    from cable_ocp.scene.output import atomic_directory
    from cable_ocp.scene.schema import load_scene

    scene = load_scene(args.scene, parse_overrides(args.set))
    settings = MpcSettings(
        horizon=args.horizon,
        sample=args.sample,
        interval=args.interval,
        elements=args.elements,
        step=args.step,
        solver=args.solver,
        heave_feedback=not args.no_heave_feedback,
        heave_filter=args.heave_filter,
        heave_margin=args.heave_margin,
        limiter_band=args.limiter_band,
        rate_weight=args.rate_weight,
        max_iter=args.max_iter,
        references=("locked", "open-loop") if args.open_loop else ("locked",),
    )
    result = mpc(scene, settings, quiet=args.quiet)
    with atomic_directory(args.out) as folder:
        result.save(folder)
        plots.clearance(result, path=folder / "clearance.png")
        plots.solve_times(result, path=folder / "solve_times.png")
        plots.winch_angle(result, path=folder / "winch_angle.png")
        (folder / "summary.json").write_text(json.dumps(result.summary(), indent=1))
    summary = {k: v for k, v in result.summary().items() if k != "failures"}
    print(json.dumps(summary, indent=1))
    print(f"results and figures written to {Path(args.out).resolve()}")
    if not result.success:
        print(
            f"cable-ocp mpc: {len(result.failures)} solve(s) failed (the previous plan was kept): "
            + "; ".join(result.failures),
            file=sys.stderr,
        )
        return 3
    return 0
