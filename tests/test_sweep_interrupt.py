"""Ctrl-C in a terminal during a sweep on a LocalCluster: one line, exit 130, no worker traceback.

The terminal sends SIGINT to the whole process group, so the sweep's worker processes get it
too; they ignore it (the sweep cancels the cases and closes the cluster), and none prints a
traceback. ``cable-ocp sweep`` runs as a process in a session of its own, signalled as a terminal
would once a case is saved (the workers are up and busy). About 15 s.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from cable_ocp.sweep.runner import usable_cores
from cable_ocp.sweep.store import case_path

ROOT = Path(__file__).resolve().parent.parent
CASES = 8
SWEEP = f"""
scene = "small_tow"
[set]
"numerics.duration" = 40.0
"numerics.step" = 0.01
[grid]
"top.tow.surge_speed" = {[round(0.6 + 0.1 * k, 1) for k in range(CASES)]}
"""
LIMIT = 120  # s: no step of the test waits longer


def test_ctrl_c_reaches_the_sweep_and_not_its_workers(tmp_path):
    (tmp_path / "sweep.toml").write_text(SWEEP)
    workers = min(2, usable_cores())
    command = [sys.executable, "-m", "cable_ocp.cli", "sweep", "sweep.toml", "--out", "out",
               "--workers", str(workers), "--quiet"]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.Popen(command, cwd=tmp_path, env=env, text=True, start_new_session=True,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE)  # fmt: skip
    try:
        deadline = time.monotonic() + LIMIT
        while not any(case_path(tmp_path / "out", k).exists() for k in range(CASES)):
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
    done = [k for k in range(CASES) if case_path(tmp_path / "out", k).exists()]
    assert 1 <= len(done) < CASES
