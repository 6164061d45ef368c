"""``cable-ocp bench``: the speed benchmarks, each part against its baseline in the same run."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import add_command, integer
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.cli.files import results_folder
from cable_ocp.scene.bundled import models_dir

PARTS = ("rk4", "simulate", "moordyn", "payout", "elastic", "ocp", "ocp-speed", "qp", "mpc")
NAMED_ONLY = ("robustness", "lowering", "grid", "policy")  # run only when --only names them


def add_bench_command(commands) -> None:
    """Add ``bench`` to the subparsers of ``cable-ocp``."""
    parser = add_command(
        commands,
        "bench",
        "speed benchmarks against baselines (long: see bench --help)",
        scene=False,
        description="Speed of the toolkit against its baselines, each part comparing within "
        "one run: rk4 (the simulation loop, interpreted against compiled), simulate (the "
        "command end to end), moordyn (MoorDyn at the same accuracy), payout (a line paid out "
        "by elements against fixed n), elastic (the elastic rope beside the rigid one and "
        "MoorDyn on a 2000 m deep lift, about a minute), ocp (IPOPT against Nelder-Mead), ocp-"
        "speed (the default optimize, cold and warm), qp (the Gauss-Newton QP screened against "
        "whole), mpc (the closed loop's solve times). The "
        "default parts run for tens of minutes on 2 cores (MoorDyn and the optimisers "
        "dominate); --quick runs short versions; --only picks parts. robustness (random scenes)"
        " and lowering (random landings: 10 cases took 5 min on 2 cores) run only when named, and "
        "grid (the adaptive control grid against the uniform one on the whole-space scenes of "
        "seeds S and S + 1 and on paper_hill; with --out, its chart of Omega against the "
        "parameters), and policy (a learned policy's C function per sample beside the MPC's "
        "median solve on its family's base scene; give --policy). "
        "Nothing is written without --out.",
    )
    parser.add_argument(
        "--quick", action="store_true", help="scene steps only, short MoorDyn runs, small OCP"
    )
    parser.add_argument(
        "--only", nargs="+", choices=[*PARTS, *NAMED_ONLY],
        help="run only these parts (robustness, lowering, grid and policy run only when named)",
    )  # fmt: skip
    parser.add_argument(
        "--cases", type=integer(1, 10_000), default=None,
        help="robustness, lowering, grid: random scenes to draw (default 50, 10 and 50 a seed; "
        "6, 3 and 4 with --quick)",
    )  # fmt: skip
    parser.add_argument(
        "--seed", type=int, default=0,
        help="robustness, lowering, grid: seed of the random scenes (default 0; grid takes it "
        "and the next)",
    )  # fmt: skip
    parser.add_argument(
        "--policy", type=Path, metavar="POLICY.nc",
        help="policy: the learned policy to time (cable-ocp learn's policy.nc)",
    )  # fmt: skip
    parser.add_argument(
        "--hessian", action="store_true", help="IPOPT exact vs limited-memory Hessian instead"
    )
    parser.add_argument(
        "--out", type=Path, default=None,
        help="folder for the benchmarks' figures (none are written without it)",
    )  # fmt: skip
    parser.set_defaults(run=run_bench_command)


def run_bench_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp bench``: the parts asked for (the default ones without ``--only``)."""
    from cable_ocp.studies import (
        bench,
        bench_elastic,
        bench_lowering,
        bench_payout,
        bench_qp,
        bench_simulate,
        robustness,
    )
    from cable_ocp.studies.moordyn_compare import moordyn_report

    if args.hessian:
        bench.hessian_report(models_dir())
        return SUCCESS
    if "policy" in (args.only or ()) and args.policy is None:
        raise ValueError("--only policy times a learned policy: give --policy POLICY.nc")
    parts = {
        "rk4": bench.rk4_report,
        "simulate": bench_simulate.report,
        "moordyn": moordyn_report,
        "payout": bench_payout.report,
        "elastic": bench_elastic.report,
        "ocp": bench.ocp_report,
        "ocp-speed": bench.ocp_speed_report,
        "qp": bench_qp.report,
        "mpc": lambda models, quick: _bench_mpc(models, quick, args.out),
        "robustness": lambda _, quick: robustness.report(
            args.cases or (6 if quick else 50), args.seed
        ),
        "lowering": lambda _, quick: bench_lowering.report(
            args.cases or (3 if quick else 10), args.seed
        ),
        "grid": lambda _, quick: _bench_grid(
            args.cases or (4 if quick else 50), args.seed, args.out
        ),
        "policy": lambda _, quick: _bench_policy(args.policy),
    }
    for name in args.only or PARTS:
        parts[name](models_dir(), quick=args.quick)
        print()
    return SUCCESS


def _bench_policy(path: Path) -> None:
    """The learned policy's benchmark: its C function beside the MPC on its family's base.

    The family is found by the name the policy keeps (a bundled family's, or a file's there).
    """
    from cable_ocp.policy.bench import bench_policy
    from cable_ocp.policy.policy import load_policy

    policy = load_policy(path)
    bench_policy(policy, policy.family["name"])


def _bench_grid(cases: int, seed: int, out: Path | None = None) -> None:
    """The control grid's benchmark; with ``out``, its chart saved there."""
    from cable_ocp.studies import bench_grid

    figures = bench_grid.report(cases, seed, chart=out is not None)
    if out is None:
        print("chart of Omega against the parameters not written (give --out DIR)")
        return
    from cable_ocp.plots.grid import omega_against_parameters

    with results_folder(out) as folder:
        path = folder / "grid_omega_parameters.png"
        omega_against_parameters(figures["chart"], path)
    print(f"chart written to {(Path(out) / path.name).resolve()}")


def _bench_mpc(models: Path, quick: bool = False, out: Path | None = None) -> None:
    """The closed loop's benchmark; its figure of solve times saved in ``out`` when given."""
    from cable_ocp.plots.closed_loop import solve_time_comparison
    from cable_ocp.studies import bench_mpc

    results = bench_mpc.report(models, quick=quick)
    if out is None:
        print("figure of the solve times not written (give --out DIR)")
        return
    with results_folder(out) as folder:
        path = folder / "mpc_solve_times.png"
        solve_time_comparison(results, path=path, scene_name="paper_hill")  # bench_mpc's scene
    print(f"figure written to {(Path(out) / path.name).resolve()}")
