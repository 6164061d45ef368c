"""Run a sweep on Dask: one task per case, each case saved the moment it finishes.

Cases already in the folder are skipped (resume); a failed case (an exception, a solver that did
not converge, a worker that died) is saved with its reason and the others go on. Ctrl-C cancels
what is left and still assembles the Dataset from the finished cases.
"""

from __future__ import annotations

import logging
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import xarray as xr

from cable_ocp.simulation.progress import Progress
from cable_ocp.sweep import execute
from cable_ocp.sweep.spec import SweepSpec
from cable_ocp.sweep.store import (
    assemble,
    case_path,
    claim_folder,
    finished_cases,
    read_case,
    save_dataset,
    write_case,
)


@dataclass
class SweepReport:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    dataset : xarray.Dataset
        All cases (also the ones skipped or not run).
    path : Path
        ``DIR/sweep.nc``.
    ran : list of int
        Cases computed in this run.
    skipped : list of int
        Cases found finished in the folder.
    interrupted : bool
        Ctrl-C stopped the run; unfinished cases have status ``"not run"``.
    wall_time : float, s
        Of this run, cluster start included.
    workers : int
        Workers of the cluster used.
    """

    dataset: xr.Dataset
    path: Path
    ran: list[int] = field(default_factory=list)
    skipped: list[int] = field(default_factory=list)
    interrupted: bool = False
    wall_time: float = 0.0
    workers: int = 0

    @property
    def all_ok(self) -> bool:
        """Whether every case finished with status ``"ok"``."""
        return bool((self.dataset["status"] == "ok").all())


def _client(scheduler: str | None, workers: int | None, processes: bool):
    """A Dask client of an existing scheduler, or of a new LocalCluster (one thread per worker)."""
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        return Client(scheduler, timeout="30s"), None
    cluster = LocalCluster(
        n_workers=workers or os.cpu_count() or 1,
        threads_per_worker=1,
        processes=processes,
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )
    return Client(cluster), cluster


def _lost(error: BaseException) -> dict:
    """The record of a case whose task itself failed (e.g. its worker died)."""
    return {
        "success": False,
        "status": "failed",
        "reason": f"task lost: {type(error).__name__}: {error}",
        "omega": float("nan"),
        "wall_time": float("nan"),
    }


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    quiet: bool = False,
    retry_failed: bool = False,
    processes: bool = True,
) -> SweepReport:
    """Run the cases of a sweep that are not finished yet, and assemble all of them.

    Parameters
    ----------
    spec : SweepSpec
        From :func:`~cable_ocp.sweep.spec.load_sweep` (every case already validated).
    out : path-like
        The sweep folder (see :mod:`cable_ocp.sweep.store`); created, or resumed when it holds
        this sweep, refused when it holds anything else.
    scheduler : str, optional
        Address of a running Dask scheduler; default: a LocalCluster started here.
    workers : int, optional
        Workers of the LocalCluster (default: one per core).
    quiet : bool
        No progress bar.
    retry_failed : bool
        Run the cases saved as failed again.
    processes : bool
        LocalCluster workers as processes (true) or threads of this process (tests).

    Returns
    -------
    SweepReport
    """
    started = time.perf_counter()
    folder = Path(out).resolve()
    claim_folder(folder, spec)
    done = finished_cases(folder, spec)
    if retry_failed:
        done = {i for i in done if str(read_case(case_path(folder, i))["status"].values) == "ok"}
    todo = [case for case in spec.cases if case.index not in done]
    report = SweepReport(dataset=xr.Dataset(), path=folder / "sweep.nc")
    report.skipped = sorted(done)
    if todo:
        _run(spec, folder, todo, report, scheduler, workers, quiet, processes)
    report.dataset = assemble(folder, spec)
    save_dataset(folder, report.dataset)
    report.wall_time = time.perf_counter() - started
    return report


def _run(spec, folder, todo, report, scheduler, workers, quiet, processes) -> None:
    """Submit ``todo`` and save each case as it arrives (Ctrl-C: cancel the rest)."""
    from dask.distributed import as_completed

    client, cluster = _client(scheduler, workers, processes)
    progress = Progress(f"sweep ({len(todo)} cases)", len(todo), quiet)
    failed = 0
    try:
        report.workers = len(client.scheduler_info().get("workers", {}))
        futures = {
            client.submit(
                execute.run_case,
                case.scene,
                spec.task,
                spec.method,
                spec.settings,
                key=f"cable-ocp-case-{case.index}-{case.fingerprint}",
                pure=False,
            ): case
            for case in todo
        }
        progress.update(0, f"0/{len(todo)} on {report.workers} workers")
        try:
            for future in as_completed(futures):
                case = futures[future]
                try:
                    record = future.result()
                except Exception as error:  # the task died with its worker
                    record = _lost(error)
                write_case(folder, case, record)
                report.ran.append(case.index)
                failed += record["status"] != "ok"
                progress.update(len(report.ran), f"{len(report.ran)}/{len(todo)}, {failed} failed")
        except KeyboardInterrupt:
            report.interrupted = True
            client.cancel(list(futures))
    finally:
        progress.close()
        client.close()
        if cluster is not None:
            cluster.close()
