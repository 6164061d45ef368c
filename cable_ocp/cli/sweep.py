"""``cable-ocp sweep SWEEP.toml --out DIR``: the subcommand and its summary table."""

from __future__ import annotations

import argparse
import logging
import math
import sys
from typing import TYPE_CHECKING

import numpy as np

from cable_ocp.cli.arguments import add_engine_command, add_quiet
from cable_ocp.cli.exits import INTERRUPTED, SUCCESS, failed

if TYPE_CHECKING:
    from cable_ocp.sweep.runner import SweepReport

MAX_ROWS = 50  # beyond this many cases the table lists the cases that are not ok only


def add_sweep_command(commands) -> argparse.ArgumentParser:
    """Add ``sweep`` to the subparsers of ``cable-ocp`` (its ``run`` is `run_sweep_command`)."""
    sweep = add_engine_command(
        commands,
        "sweep",
        "many simulations or OCPs of one scene on Dask, one xarray Dataset out",
        "Run the cases of SWEEP (a grid or sample of scene overrides, see models/sweeps/) on a "
        "Dask LocalCluster or an existing scheduler. Every finished case is saved in DIR/cases "
        "at once; a rerun skips them. All cases end up in DIR/sweep.nc.",
        ("sweep", "the sweep TOML file, or the name of a bundled example"),
        "sweep folder (resumed if present)",
    )
    sweep.add_argument(
        "--engine-timeout",
        type=float,
        metavar="SECONDS",
        help="stop (resumable) after this long without a Dask worker or scheduler "
        "(default: cable_ocp.sweep.runner.ENGINE_TIMEOUT)",
    )
    sweep.add_argument("--retry-failed", action="store_true", help="rerun cases saved as failed")
    add_quiet(sweep)
    sweep.set_defaults(run=run_sweep_command)
    return sweep


def summary(report: SweepReport) -> str:
    """A markdown table of the cases (only the ones not ok beyond :data:`MAX_ROWS`)."""
    ds = report.dataset
    swept = [n for n in ds.coords if n not in ("case", "time")]
    rows = list(range(ds.sizes["case"]))
    if len(rows) > MAX_ROWS:
        rows = [k for k in rows if ds["status"].values[k] != "ok"]
    lines = [
        "| case | " + " | ".join(swept) + (" | " if swept else "")
        + "status | Omega [m] | wall [s] | reason |",
        "|---:|" + "---:|" * len(swept) + "---|---:|---:|---|",
    ]  # fmt: skip
    for k in rows:
        values = "".join(f"{ds[n].values[k]:.4g} | " if np.issubdtype(ds[n].dtype, np.number)
                         else f"{ds[n].values[k]} | " for n in swept)  # fmt: skip
        lines.append(
            f"| {k} | {values}{ds['status'].values[k]} | {ds['omega'].values[k]:.4g} | "
            f"{ds['wall_time'].values[k]:.1f} | {ds['reason'].values[k]} |"
        )
    counts = {s: int((ds["status"] == s).sum()) for s in ("ok", "failed", "not run")}
    lines.append(
        f"\n{len(report.ran)} cases run, {len(report.skipped)} found finished; ok {counts['ok']}, "
        f"failed {counts['failed']}, not run {counts['not run']}; wall {report.wall_time:.1f} s"
        + (f" on {report.workers} workers" if report.workers else "")
    )
    return "\n".join(lines)


def _silence_dask() -> None:
    """Keep Dask's own log lines (and asyncio's about its tasks) off this process's stderr.

    What goes wrong reaches the user as a case's reason or the one line about a lost engine;
    Dask's warnings about a lost worker or scheduler, with their tracebacks, would bury it.
    """
    import distributed  # noqa: F401 - its logging is configured on import, then overridden

    names = [n for n in logging.root.manager.loggerDict if n.startswith("distributed")]
    for name in ("distributed", "tornado", "asyncio", *names):
        logging.getLogger(name).setLevel(logging.CRITICAL + 1)


def run_sweep_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp sweep``; 0 when every case is ok, 3 otherwise, 130 after Ctrl-C.

    3: a case failed or did not run, or the engine was lost (one line says how to resume).
    """
    # Dask and xarray load only for a sweep.
    from cable_ocp.sweep.runner import check_engine, run_sweep
    from cable_ocp.sweep.spec import load_sweep

    check_engine(args.scheduler, args.workers)
    _silence_dask()
    timeout = args.engine_timeout
    if timeout is not None and not (math.isfinite(timeout) and timeout > 0):
        raise ValueError(f"--engine-timeout {timeout}: must be finite and > 0 s")
    spec = load_sweep(args.sweep)
    report = run_sweep(
        spec,
        args.out,
        scheduler=args.scheduler,
        workers=args.workers,
        quiet=args.quiet,
        retry_failed=args.retry_failed,
        **({} if timeout is None else {"engine_timeout": timeout}),
    )
    print(summary(report))
    print(f"results written to {report.path}")
    if report.engine_lost:
        saved = int((report.dataset["status"] != "not run").sum())
        return failed(
            "sweep",
            f"the Dask engine was lost ({report.engine_lost}); {saved} of "
            f"{report.dataset.sizes['case']} cases are saved: start the engine again and rerun "
            "the same command to resume",
        )
    if report.interrupted:
        print("cable-ocp sweep: interrupted; rerun the same command to resume", file=sys.stderr)
        return INTERRUPTED
    if not report.all_ok:
        return failed("sweep", "some cases failed or did not run (see reason)")
    return SUCCESS
