"""A sweep on a real Dask engine that dies under it: ``dask scheduler`` and ``dask worker``.

Both run as separate processes on 127.0.0.1, and so does ``cable-ocp sweep --scheduler`` (no
Dask thread in the test process). The worker is killed (``kill -9``, no nanny) once a case is
saved, then the scheduler: each time the sweep stops with exit 3 and one line that says the
engine was lost and how to resume, keeps every finished case as it was, and assembles
``sweep.nc``; a rerun on a new engine completes, computing only the cases that are missing.
About 40 s.

A terminal's Ctrl-C goes to the whole process group, the workers of the sweep's own
LocalCluster included: ``cable-ocp sweep --workers`` runs in a session of its own and the group
is signalled once a case is saved; the sweep stops with exit 130 and one line, and no worker
prints a traceback (they ignore SIGINT). About 15 s.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cable_ocp.sweep import open_sweep
from cable_ocp.sweep.runner import usable_cores
from cable_ocp.sweep.store import case_path

ROOT = Path(__file__).resolve().parent.parent
CASES = 8
# small_tow at a fine step: about a second per case (a fifth of it with a warm compile cache), and
# cases enough that the engine dies with some left to run: with 5 cases of 0.2 s the last result
# could arrive before the sweep saw its scheduler die, and it ended with exit 0.
SWEEP = f"""
scene = "small_tow"
[set]
"numerics.duration" = 40.0
"numerics.step" = 0.01
[grid]
"top.tow.surge_speed" = {[round(0.6 + 0.1 * k, 1) for k in range(CASES)]}
"""
LIMIT = 120  # s: no step of the test waits longer


class Engine:
    """The processes this test starts, each ended by its own pid at teardown."""

    def __init__(self, folder: Path):
        self.folder, self.processes = folder, []

    def start(self, *args: str) -> subprocess.Popen:
        log = open(self.folder / f"{len(self.processes)}.log", "w")  # noqa: SIM115
        process = subprocess.Popen([sys.executable, "-m", *args], cwd=self.folder,
                                   stdout=log, stderr=subprocess.STDOUT)  # fmt: skip
        self.processes.append(process)
        return process

    def scheduler(self) -> tuple[subprocess.Popen, str]:
        info = self.folder / f"scheduler_{len(self.processes)}.json"
        process = self.start("distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
                             "0", "--no-dashboard", "--scheduler-file", str(info))  # fmt: skip
        deadline = time.monotonic() + LIMIT
        while time.monotonic() < deadline:
            if info.exists() and info.stat().st_size:
                return process, json.loads(info.read_text())["address"]
            assert process.poll() is None, "the scheduler did not start"
            time.sleep(0.1)
        pytest.fail("the scheduler did not start in time")

    def worker(self, address: str) -> subprocess.Popen:
        """A worker without a nanny, returned once it has registered with the scheduler."""
        log = self.folder / f"{len(self.processes)}.log"
        process = self.start("distributed.cli.dask_worker", address, "--nthreads", "1",
                             "--no-nanny", "--no-dashboard")  # fmt: skip
        deadline = time.monotonic() + LIMIT
        while "Registered to:" not in log.read_text():
            assert process.poll() is None and time.monotonic() < deadline, log.read_text()
            time.sleep(0.1)
        return process

    def close(self):
        for process in self.processes:
            if process.poll() is None:
                process.kill()
                process.wait(timeout=LIMIT)


@pytest.fixture
def engine(tmp_path):
    started = Engine(tmp_path)
    yield started
    started.close()


def kill_after(process: subprocess.Popen, folder: Path, count: int, running) -> None:
    """Kill ``process`` once ``count`` case files exist (or the sweep ended)."""
    deadline = time.monotonic() + LIMIT
    while len(saved(folder)) < count and time.monotonic() < deadline and running():
        time.sleep(0.02)
    process.send_signal(signal.SIGKILL)
    process.wait(timeout=LIMIT)


def sweep_command(folder: Path, address: str, kill=None, after: int = 0):
    """``cable-ocp sweep`` on ``address``, a process; kill ``kill`` after ``after`` cases."""
    command = [sys.executable, "-m", "cable_ocp.cli", "sweep", "sweep.toml", "--out", "out",
               "--scheduler", address, "--engine-timeout", "3", "--quiet"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.Popen(command, cwd=folder, env=env, text=True,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    if kill is not None:
        kill_after(kill, folder, after, lambda: run.poll() is None)
    out, err = run.communicate(timeout=LIMIT)
    return run.returncode, out, err


def saved(folder: Path) -> dict[int, int]:
    """The case files there are, with their modification times (ns)."""
    return {k: os.stat(case_path(folder / "out", k)).st_mtime_ns for k in range(CASES)
            if case_path(folder / "out", k).exists()}  # fmt: skip


def statuses_match_the_files(folder: Path) -> int:
    """``sweep.nc`` holds what finished: ok where a case file is, not run elsewhere."""
    statuses = list(open_sweep(folder / "out")["status"].values)
    assert set(statuses) <= {"ok", "not run"}, statuses
    assert [k for k, s in enumerate(statuses) if s == "ok"] == sorted(saved(folder))
    return statuses.count("ok")


def assert_lost(code: int, out: str, err: str, why: str) -> None:
    """Exit 3 and one line: the engine was lost, why, and how to resume."""
    assert code == 3, err
    assert "Traceback" not in out + err and err.count("\n") == 1, err
    assert err.startswith(f"cable-ocp sweep: the Dask engine was lost ({why}"), err
    assert "rerun the same command to resume" in err


def test_a_killed_worker_then_a_killed_scheduler_lose_nothing(engine, tmp_path):
    (tmp_path / "sweep.toml").write_text(SWEEP)
    scheduler, address = engine.scheduler()

    # The only worker dies (no nanny to restart it): the sweep gives up after --engine-timeout.
    code, out, err = sweep_command(tmp_path, address, kill=engine.worker(address), after=1)
    assert_lost(code, out, err, "the Dask scheduler has had no worker for 3 s")
    first = saved(tmp_path)
    done = statuses_match_the_files(tmp_path)
    assert 1 <= done < CASES and f"{done} cases run, 0 found finished" in out

    # A new worker on the same scheduler; then the scheduler dies under the sweep.
    engine.worker(address)
    code, out, err = sweep_command(tmp_path, address, kill=scheduler, after=done + 1)
    assert_lost(code, out, err, "the Dask scheduler is gone")
    second = saved(tmp_path)
    more = statuses_match_the_files(tmp_path)
    assert done < more < CASES
    assert {k: second[k] for k in first} == first  # finished cases untouched

    # A new engine: the rerun computes only what is missing.
    _, address = engine.scheduler()
    engine.worker(address)
    code, out, err = sweep_command(tmp_path, address)
    assert code == 0, err
    assert f"{CASES - more} cases run, {more} found finished; ok {CASES}," in out
    final = saved(tmp_path)
    assert {k: final[k] for k in second} == second and len(final) == CASES
    assert statuses_match_the_files(tmp_path) == CASES
    assert sorted(p.name for p in (tmp_path / "out" / "cases").iterdir()) == [
        case_path(tmp_path, k).name for k in range(CASES)
    ]  # no scratch file, no duplicate


def test_ctrl_c_reaches_the_sweep_and_not_its_workers(tmp_path):
    (tmp_path / "sweep.toml").write_text(SWEEP)
    command = [sys.executable, "-m", "cable_ocp.cli", "sweep", "sweep.toml", "--out", "out",
               "--workers", str(min(2, usable_cores())), "--quiet"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.Popen(command, cwd=tmp_path, env=env, text=True, start_new_session=True,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    try:
        deadline = time.monotonic() + LIMIT
        while not saved(tmp_path):  # the workers are up and busy
            assert run.poll() is None and time.monotonic() < deadline, run.communicate()
            time.sleep(0.02)
        os.killpg(run.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole group
        out, err = run.communicate(timeout=LIMIT)
    finally:
        if run.poll() is None:
            os.killpg(run.pid, signal.SIGKILL)
            run.wait(timeout=LIMIT)
    assert run.returncode == 130, err
    assert "Traceback" not in out + err, err
    assert err == "cable-ocp sweep: interrupted; rerun the same command to resume\n", err
    assert 1 <= len(saved(tmp_path)) < CASES
