"""Run a sweep on Dask: one task per case, each case saved the moment it finishes.

Cases already in the folder are skipped (resume); a failed case (an exception, a solver that did
not converge, a worker that died) is saved with its reason and the others go on. Ctrl-C cancels
what is left and still assembles the Dataset from the finished cases. So does a lost engine: a
scheduler that went away, or no worker left for :data:`ENGINE_TIMEOUT` seconds; the report says
so in ``engine_lost`` and a rerun resumes.
"""

from __future__ import annotations

import asyncio
import logging
import os
import signal
import threading
import time
from collections.abc import Callable
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import xarray as xr

from cable_ocp.simulation.progress import Progress
from cable_ocp.sweep import execute
from cable_ocp.sweep.spec import SweepSpec
from cable_ocp.sweep.store import (
    assemble,
    case_path,
    case_statuses,
    check_folder,
    claim_folder,
    folder_lock,
    read_case,
    remove_scratch,
    save_dataset,
    write_case,
)

ENGINE_TIMEOUT = 60.0  # s without a worker (or a scheduler) before the engine counts as lost
POLL = 0.2  # s between looks at the engine while cases run
RESULT_WAIT = 10.0  # s at most to fetch a finished case's result before looking at the engine
WORKER_MEMORY = "about 100 MB"  # of one worker process, said when --workers is refused


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
    engine_lost : str
        Why the Dask engine was lost (empty if it was not); unfinished cases have status
        ``"not run"``.
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
    engine_lost: str = ""
    wall_time: float = 0.0
    workers: int = 0

    @property
    def all_ok(self) -> bool:
        """Whether every case finished with status ``"ok"``."""
        return bool((self.dataset["status"] == "ok").all())


def usable_cores() -> int:
    """Cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_engine(scheduler: str | None, workers: int | None) -> None:
    """Refuse ``workers`` with a scheduler, or more workers than cores.

    Raises
    ------
    ValueError
        Naming the option.
    """
    if workers is None:
        return
    if scheduler is not None:
        raise ValueError(
            f"--workers {workers} with --scheduler {scheduler}: the scheduler has its own "
            "workers; give one of the two"
        )
    cores = usable_cores()
    if not 1 <= workers <= cores:
        raise ValueError(
            f"--workers {workers}: must be 1 to {cores}, the cores of this machine (each worker "
            f"is a process of {WORKER_MEMORY} that runs one case at a time)"
        )


def engine(scheduler: str | None, workers: int | None, processes: bool = True):
    """A Dask client of an existing scheduler, or of a new LocalCluster (one thread per worker).

    Returns ``(client, cluster)``, the cluster None for a scheduler's address; close both when
    done. The sweep's engine, and a policy's data generation's (:mod:`cable_ocp.policy.data`).
    The client is not made Dask's default, so that nothing else (xarray's write lock) goes
    through the scheduler.
    """
    from dask.distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            return Client(scheduler, timeout="30s", set_as_default=False), None
        except (OSError, TypeError, ValueError) as error:
            raise ValueError(
                f"--scheduler {scheduler}: cannot reach a Dask scheduler there "
                f"({type(error).__name__}: {' '.join(str(error).split())[:200]}); nothing ran"
            ) from None
    with _interrupt_ignored():
        cluster = LocalCluster(
            n_workers=workers or usable_cores(),
            threads_per_worker=1,
            processes=processes,
            # Any free port: None meant Dask's 8787, and a second engine on this machine (two
            # sweeps, a sweep beside a learning) printed Dask's "Port 8787 is already in use".
            dashboard_address=":0",
            silence_logs=logging.ERROR,
        )
    return Client(cluster, set_as_default=False), cluster


def mapped(
    function: Callable,
    tasks: list[tuple],
    scheduler: str | None = None,
    workers: int | None = None,
    progress: Callable[[int], None] | None = None,
) -> list:
    """``[function(*task) for task in tasks]`` on the Dask engine, in the tasks' order.

    The engine of :func:`engine` (a LocalCluster of ``workers``, or the ``scheduler``'s),
    closed when done; ``progress`` is called with the count of tasks done as each finishes.
    An exception of a task is raised here. Used by a policy's data and validation
    (:mod:`cable_ocp.policy`).
    """
    from dask.distributed import as_completed

    check_engine(scheduler, workers)
    client, cluster = engine(scheduler, workers)
    try:
        futures = [client.submit(function, *task, pure=False) for task in tasks]
        order = {future.key: k for k, future in enumerate(futures)}
        results: list = [None] * len(tasks)
        for done, future in enumerate(as_completed(futures, loop=client.loop), start=1):
            results[order[future.key]] = future.result()
            if progress is not None:
                progress(done)
    finally:
        client.close(timeout=5)
        if cluster is not None:
            cluster.close()
    return results


@contextmanager
def _interrupt_ignored():
    """Ignore SIGINT while a LocalCluster starts its worker processes.

    A worker process inherits the ignored SIGINT (Python keeps an ignored SIGINT at start), so the
    terminal's Ctrl-C reaches only this process, which cancels the cases and closes the cluster,
    instead of also interrupting each worker mid-task (a traceback per worker). A Ctrl-C in the
    few seconds the cluster takes to start is ignored. Only the main thread can set a handler:
    elsewhere (a sweep run from a thread) nothing changes.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


def _lost(error: BaseException) -> dict:
    """The record of a case whose task itself failed (e.g. its worker died)."""
    return {
        "success": False,
        "status": "failed",
        "reason": f"task lost: {type(error).__name__}: {error}",
        "omega": float("nan"),
        "wall_time": float("nan"),
    }


class EngineLost(Exception):
    """The Dask scheduler went away, or no worker was left for too long."""


def run_sweep(
    spec: SweepSpec,
    out: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    quiet: bool = False,
    retry_failed: bool = False,
    processes: bool = True,
    engine_timeout: float = ENGINE_TIMEOUT,
) -> SweepReport:
    """Run the cases of a sweep that are not finished yet, and assemble all of them.

    Parameters
    ----------
    spec : SweepSpec
        From :func:`~cable_ocp.sweep.spec.load_sweep` (every case already validated).
    out : path-like
        The sweep folder (see :mod:`cable_ocp.sweep.store`); created, or resumed when it holds
        this sweep, refused when it holds anything else or another sweep is running in it.
    scheduler : str, optional
        Address of a running Dask scheduler; default: a LocalCluster started here.
    workers : int, optional
        Workers of the LocalCluster (default: one per core; at most one per core with
        ``processes``; not with ``scheduler``).
    quiet : bool
        No progress bar.
    retry_failed : bool
        Run the cases saved as failed, or whose file is damaged, again.
    processes : bool
        LocalCluster workers as processes (true) or threads of this process (tests).
    engine_timeout : float, s
        How long the sweep waits without any worker (or for a lost scheduler) before it stops
        with ``engine_lost`` set.

    Returns
    -------
    SweepReport

    Raises
    ------
    ValueError
        A folder that is not this sweep's, in use, or with damaged files (naming the file and
        how to recover); bad ``workers``; an unreachable scheduler. Nothing runs then.
    """
    started = time.perf_counter()
    check_engine(scheduler, workers if processes else None)
    folder = Path(out).expanduser().resolve()
    report = SweepReport(dataset=xr.Dataset(), path=folder / "sweep.nc")
    check_folder(folder, spec)  # before the lock's file is written beside it
    with folder_lock(folder, f"cable-ocp sweep {spec.path}"):
        check_folder(folder, spec)  # again: another run may have written it meanwhile
        claim_folder(folder, spec)
        remove_scratch(folder)
        statuses = case_statuses(folder, spec)
        damaged = sorted(i for i, s in statuses.items() if s == "damaged")
        if damaged and not retry_failed:
            others = f" (and {len(damaged) - 1} more case files)" if len(damaged) > 1 else ""
            try:
                read_case(case_path(folder, damaged[0]))
            except ValueError as error:
                raise ValueError(f"{error}{others}") from None
        keep = ("ok",) if retry_failed else ("ok", "failed")
        done = {i for i, s in statuses.items() if s in keep}
        todo = [case for case in spec.cases if case.index not in done]
        report.skipped = sorted(done)
        if todo:
            _run(spec, folder, todo, report, scheduler, workers, quiet, processes, engine_timeout)
        report.dataset = assemble(folder, spec)
        save_dataset(folder, report.dataset)
    report.wall_time = time.perf_counter() - started
    return report


@contextmanager
def _dask_quiet(active: bool):
    """Silence Dask's own logging (a lost scheduler's reconnect tracebacks) while closing."""
    names = [n for n in logging.root.manager.loggerDict if n.startswith("distributed")]
    loggers = [logging.getLogger(n) for n in ("distributed", "tornado", "asyncio", *names)]
    levels = [logger.level for logger in loggers]
    if active:
        for logger in loggers:
            logger.setLevel(logging.CRITICAL + 1)
    try:
        yield
    finally:
        for logger, level in zip(loggers, levels, strict=True):
            logger.setLevel(level)


def _engine_state(client) -> str:
    """Why the engine is unusable now (empty if the client is connected)."""
    if client.status not in ("running", "newly-created"):
        return f"the Dask scheduler is gone (client {client.status})"
    return ""


def _workers(client) -> int | None:
    """Workers the scheduler has now (None if it cannot be asked)."""
    try:
        return len(client.scheduler_info().get("workers", {}))
    except Exception:  # noqa: BLE001 - any failure to ask is a scheduler we cannot use
        return None


def _run(spec, folder, todo, report, scheduler, workers, quiet, processes, engine_timeout) -> None:
    """Submit ``todo`` and save each case as it arrives (Ctrl-C, a lost engine: stop)."""
    from dask.distributed import as_completed

    client, cluster = engine(scheduler, workers, processes)
    progress = Progress(f"sweep ({len(todo)} cases)", len(todo), quiet)
    failed, lost = 0, False
    try:
        report.workers = _workers(client) or 0
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
        arrivals = as_completed(futures, loop=client.loop)
        last_seen = time.monotonic()  # last time the engine had a worker
        wait = min(engine_timeout, RESULT_WAIT)
        try:
            while not arrivals.is_empty():
                batch = arrivals.next_batch(block=False)
                for future in batch:
                    if future.status == "cancelled":  # not by us: the scheduler went away
                        continue
                    try:
                        record = future.result(timeout=wait)
                    except TimeoutError:  # its result died with its worker: computed again
                        arrivals.add(future)
                        continue
                    except (Exception, asyncio.CancelledError) as error:
                        if _engine_state(client):
                            continue  # not a result of the case: it did not run to the end
                        record = _lost(error)  # the task died with its worker
                    case = futures[future]
                    write_case(folder, case, record)
                    report.ran.append(case.index)
                    failed += record["status"] != "ok"
                    done = len(report.ran)
                    progress.update(done, f"{done}/{len(todo)}, {failed} failed")
                why = _engine_state(client) or (
                    "the Dask scheduler is gone (it cancelled the cases)"
                    if any(f.status == "cancelled" for f in batch)
                    else ""
                )
                if why:
                    raise EngineLost(why)
                count = _workers(client)
                if count:
                    last_seen = time.monotonic()
                elif time.monotonic() - last_seen > engine_timeout:
                    raise EngineLost(
                        "the Dask scheduler cannot be reached"
                        if count is None
                        else f"the Dask scheduler has had no worker for {engine_timeout:g} s"
                    )
                if not batch:
                    time.sleep(POLL)
        except KeyboardInterrupt:
            report.interrupted = True
            client.cancel(list(futures))
        except EngineLost as error:
            lost = True
            report.engine_lost = str(error)
    finally:
        progress.close()
        with _dask_quiet(lost):
            if lost:
                try:
                    client.cancel(list(futures))
                except Exception:  # noqa: BLE001, S110 - the scheduler is gone already
                    pass
            client.close(timeout=5)
            if cluster is not None:
                cluster.close()
