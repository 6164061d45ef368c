"""``cable-ocp learn FAMILY --out DIR``: learn a winch policy for a scene family, on Dask."""

from __future__ import annotations

import argparse
from pathlib import Path

from cable_ocp.cli.arguments import OUT_HELP, add_engine_command, add_quiet, integer
from cable_ocp.cli.exits import SUCCESS
from cable_ocp.policy.defaults import C_NAME, HIDDEN, POLICY_FILE, ROUNDS, SCENES


def hidden_layers(text: str) -> tuple[int, ...]:
    """An argparse type: hidden layer widths as ``16,16`` (1 to 4 layers of 1 to 256)."""
    try:
        widths = tuple(int(part) for part in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected widths such as 16,16; got {text!r:.40}"
        ) from None
    if not 1 <= len(widths) <= 4 or not all(1 <= w <= 256 for w in widths):
        raise argparse.ArgumentTypeError(
            f"{text!r:.40} is out of range: 1 to 4 layers, each 1 to 256 wide"
        )
    return widths


def add_learn_command(commands) -> argparse.ArgumentParser:
    """Add ``learn`` to the subparsers of ``cable-ocp``."""
    learn = add_engine_command(
        commands,
        "learn",
        "learn a winch policy for a scene family from the MPC's runs (DAgger, on Dask)",
        "Draw scenes of FAMILY (a base scene and ranges of its fields, see models/families/), run "
        "the closed loop on each on a Dask LocalCluster or an existing scheduler, record "
        "(observation, action) pairs, train a small network, and repeat on the states the "
        "network visits (DAgger). DIR gets policy.nc (co.load_policy), policy.c/policy.h (the "
        "network as dependency-free C) and summary.json.",
        ("family", "the family TOML file, or a bundled family's name"),
        OUT_HELP,
    )
    learn.add_argument("--scenes", type=integer(2, 100_000), default=SCENES,
                       help="training scenes drawn from the family")  # fmt: skip
    learn.add_argument("--rounds", type=integer(0, 100), default=ROUNDS,
                       help="DAgger rounds after the MPC's own runs")  # fmt: skip
    learn.add_argument("--seed", type=integer(0, 2**32 - 1), default=0,
                       help="seeds the scenes drawn and the network's initial weights")  # fmt: skip
    learn.add_argument("--hidden", type=hidden_layers, default=",".join(map(str, HIDDEN)),
                       help="hidden layer widths, comma-separated")  # fmt: skip
    add_quiet(learn)
    learn.set_defaults(run=run_learn_command)
    return learn


def run_learn_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp learn``; 0 when the policy is written (2: bad input, refused first)."""
    from cable_ocp.cli.files import results_folder
    from cable_ocp.policy.family import load_family
    from cable_ocp.policy.learn import learn_policy
    from cable_ocp.scene.output import json_text
    from cable_ocp.sweep.runner import check_engine

    check_engine(args.scheduler, args.workers)
    family = load_family(args.family)
    policy = learn_policy(
        family, scenes=args.scenes, rounds=args.rounds, hidden=args.hidden, seed=args.seed,
        scheduler=args.scheduler, workers=args.workers, quiet=args.quiet,
    )  # fmt: skip
    figures = {
        "policy": policy.name,
        "family": family.name,
        "fingerprint": family.fingerprint,
        "pairs": int(policy.actions.size),
        **policy.validation["training"],
    }
    with results_folder(args.out) as folder:
        policy.save(folder / POLICY_FILE)
        policy.to_c(folder / C_NAME)
        (folder / "summary.json").write_text(json_text(figures))
    print(json_text(figures))
    print(f"policy written to {Path(args.out).resolve() / POLICY_FILE}")
    return SUCCESS
