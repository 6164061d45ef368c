"""Ctrl-C during a solve (issue 17 item 8): exit 130, the previous results untouched, never a
solver failure; and messages that show by how much a tolerance was broken (item 9).

Where the process can interrupt itself at a known point (``CABLE_OCP_INTERRUPT_AT``,
:mod:`cable_ocp.control.interrupts`), the test does so, so that no solve can finish before the
signal lands (issue 24 class 7); IPOPT's C code is interrupted from outside, on its first
iteration line.
"""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cable_ocp.control.interrupts import INTERRUPT_AT, keeping_interrupts
from cable_ocp.simulation.figures import apart

MODELS = Path(__file__).resolve().parents[1] / "models"
TIMEOUT = 300  # s, for a whole command
SMALL = ["--intervals", "8"]  # small_tow's 80 RK4 steps of the default optimisation model


def _interrupted_at(command: list[str], point: str) -> tuple[int, str]:
    """Run ``command``, which interrupts itself at ``point``; returns (exit code, stderr)."""
    run = subprocess.run(
        [sys.executable, "-m", "cable_ocp.cli", *command],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        timeout=TIMEOUT,
        env={**os.environ, INTERRUPT_AT: point},
    )
    return run.returncode, run.stderr


def _interrupt_when(command: list[str], marker: str, delay: float = 0.0) -> tuple[int, str]:
    """Run ``command``, send SIGINT ``delay`` s after ``marker`` appears on its stderr.

    Returns (exit code, stderr).
    """
    process = subprocess.Popen(
        [sys.executable, "-m", "cable_ocp.cli", *command],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    seen, started = [], time.monotonic()
    for line in process.stderr:
        seen.append(line)
        if marker in line:
            time.sleep(delay)
            process.send_signal(signal.SIGINT)
            break
        if time.monotonic() - started > TIMEOUT:
            process.kill()
            pytest.fail(f"{marker!r} never appeared: {''.join(seen)[-2000:]}")
    rest = process.stderr.read()
    return process.wait(timeout=TIMEOUT), "".join(seen) + rest


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@pytest.mark.skipif(os.name != "posix", reason="SIGINT to a child process")
@pytest.mark.parametrize(
    ("solver", "delay"),
    # IPOPT: in its callback, in its C code; Gauss-Newton: at its first iteration, from inside.
    [("ipopt", 0.0), ("ipopt", 0.05), ("gauss-newton", None)],
)  # fmt: skip
def test_ctrl_c_during_a_solve_keeps_the_previous_results(tmp_path, solver, delay):
    out = tmp_path / "results"
    scene = str(MODELS / "small_tow.toml")
    first = subprocess.run(
        [
            sys.executable,
            "-m",
            "cable_ocp.cli",
            "optimize",
            scene,
            *SMALL,
            "--out",
            str(out),
            "--quiet",
        ],
        capture_output=True,
        text=True,
        timeout=TIMEOUT,
    )
    assert first.returncode == 0, first.stderr
    before = _snapshot(out)
    command = ["optimize", scene, *SMALL, "--solver", solver, "--out", str(out)]
    if delay is None:
        code, stderr = _interrupted_at([*command, "--quiet"], "check")
    else:
        code, stderr = _interrupt_when(command, f"{solver} iter", delay)
    assert code == 130, stderr
    assert "interrupted" in stderr and "failed" not in stderr
    assert _snapshot(out) == before


@pytest.mark.skipif(os.name != "posix", reason="SIGINT to a child process")
@pytest.mark.parametrize("point", ["check", "reference run"])  # a solve; the locked run after
def test_ctrl_c_during_the_closed_loop_is_an_interrupt(tmp_path, point):
    out = tmp_path / "loop"
    command = ["mpc", str(MODELS / "small_tow.toml"), "--out", str(out), "--horizon", "10"]
    code, stderr = _interrupted_at(command, point)
    assert code == 130, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr
    assert not out.exists() or not any(out.iterdir())


def test_an_error_left_by_an_interrupt_inside_casadi_is_the_interrupt():
    """CasADi can return with the interrupt still set; numpy then raises SystemError."""
    with pytest.raises(KeyboardInterrupt), keeping_interrupts():
        try:
            signal.raise_signal(signal.SIGINT)
        except KeyboardInterrupt as error:
            raise SystemError(
                "<function DM.__array__> returned a result with an exception set"
            ) from error


def test_a_broken_tolerance_shows_its_excess():
    assert apart(0.000100049, 1e-4) == ("0.00010005", "0.0001")
    assert apart(0.00104, 1e-4) == ("0.00104", "0.0001")
    assert apart(1e-4, 1e-4) == ("0.0001", "0.0001")


# --- Ctrl-C while a result is written (issue 45 item 1) -------------------------------------------

# Run as a child: a real SIGINT, sent by the process to itself in the middle of netCDF4's
# combined lock (the first lock taken, the second not yet) the AT-th time it is taken, where an
# interrupt that is let through leaves a process-wide lock held: the 1st (opening the file) and
# the 8th (inside the write, whose close then waited on it for ever: 0 % CPU, the folder's lock
# and scratch folder kept).
SIGINT_IN_THE_WRITE = """
import signal, sys
from xarray.backends import locks

taken = locks.acquire

def acquire(lock, blocking=True):
    got = taken(lock, blocking)
    acquire.calls = getattr(acquire, "calls", 0) + 1
    if acquire.calls == AT:
        signal.raise_signal(signal.SIGINT)
    return got

locks.acquire = acquire
"""
WRITE_TIMEOUT = 60  # s: a write that an interrupt hangs never ends


@pytest.mark.skipif(os.name != "posix", reason="SIGINT")
@pytest.mark.parametrize("at", [1, 8])
def test_ctrl_c_while_a_run_is_written_exits_130_leaving_nothing(tmp_path, at):
    out = tmp_path / "run"
    command = ["simulate", str(MODELS / "hanging.toml"), "--set", "numerics.duration=2.0",
               "--quiet", "--out", str(out)]  # fmt: skip
    child = SIGINT_IN_THE_WRITE.replace("AT", str(at))
    child += f"from cable_ocp.cli import main\nsys.exit(main({command!r}))"
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                         timeout=WRITE_TIMEOUT)  # fmt: skip
    assert run.returncode == 130, run.stderr
    assert "interrupted" in run.stderr and "Traceback" not in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no folder, scratch or lock left


@pytest.mark.skipif(os.name != "posix", reason="SIGINT")
def test_ctrl_c_in_a_save_is_raised_after_it_and_the_next_save_works(tmp_path):
    child = (
        SIGINT_IN_THE_WRITE.replace("AT", "8")
        + f"""
import cable_ocp as co
from pathlib import Path
folder = Path({str(tmp_path)!r})
scene = co.load_scene({str(MODELS / "small_tow.toml")!r}, {{"numerics.duration": 2.0}})
trajectory = co.simulate(scene, quiet=True)
try:
    trajectory.save(folder / "first")
except KeyboardInterrupt:
    print("interrupted:", sorted(p.name for p in folder.iterdir()))
trajectory.save(folder / "second")
print("saved:", co.Trajectory.load(folder / "second").time.size)
"""
    )
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                         timeout=WRITE_TIMEOUT)  # fmt: skip
    assert run.returncode == 0, run.stderr
    lines = run.stdout.splitlines()
    assert lines[0] == "interrupted: []", run.stdout  # neither first.nc nor its scratch file
    assert lines[1].startswith("saved: ") and int(lines[1].split()[1]) > 1
