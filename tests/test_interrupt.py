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


def _interrupt_when(
    command: list[str], marker: str, delay: float = 0.0, number: int = signal.SIGINT
) -> tuple[int, str]:
    """Run ``command``, send the signal ``number`` ``delay`` s after ``marker`` is on its stderr.

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
            process.send_signal(number)
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


# --- Ctrl-C while the model compiles, during the imports, and SIGTERM (issue 45 D1, D7) ----------

EXIT_BOUND = 10.0  # s from the signal to the exit (it waited for every compile: 14 s and more)


def _processes_naming(text: str) -> list[str]:
    """Command lines of the running processes that contain ``text`` (zombies have none)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            line = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        if text in line:
            found.append(line)
    return found


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="SIGINT, /proc")
def test_ctrl_c_while_the_model_compiles_exits_at_once_leaving_no_compiler(tmp_path):
    from cable_ocp.model.compile import damage, find_compiler

    if find_compiler() is None:
        pytest.skip("no C compiler")
    cache, out = tmp_path / "cache", tmp_path / "run"
    command = ["optimize", str(MODELS / "small_tow.toml"), *SMALL, "--quiet", "--out", str(out)]
    process = subprocess.Popen(
        [sys.executable, "-m", "cable_ocp.cli", *command],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
        env={**os.environ, "CABLE_OCP_CACHE": str(cache)},  # empty: everything compiles
    )
    started = time.monotonic()
    while not any("cc1" in line for line in _processes_naming(str(cache))):
        assert process.poll() is None and time.monotonic() - started < TIMEOUT, "no compiler"
        time.sleep(0.02)
    process.send_signal(signal.SIGINT)
    sent = time.monotonic()
    stderr = process.communicate(timeout=TIMEOUT)[1]
    assert process.returncode == 130 and time.monotonic() - sent < EXIT_BOUND, stderr
    assert stderr.strip().splitlines() == ["cable-ocp optimize: interrupted"]
    assert _processes_naming(str(cache)) == []  # no cc, cc1, as or ld left of any run
    files = sorted(p.name for p in cache.iterdir())
    libraries = [name for name in files if name.endswith(".so")]
    assert files == sorted([*libraries, *(f"{name}.json" for name in libraries)])  # no scratch
    assert all(damage(cache / name) is None for name in libraries)  # the next run loads them
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cache"]  # no results, lock, scratch


# A child that interrupts itself the first time a given module is imported (a deterministic
# Ctrl-C during the imports), then runs the script's entry point with the given arguments.
SIGINT_IN_THE_IMPORTS = """
import os, signal, sys

class Interrupt:
    def find_spec(self, name, path=None, target=None):
        if name == sys.argv[1]:
            sys.meta_path.remove(self)
            os.kill(os.getpid(), signal.SIGINT)
        return None

sys.meta_path.insert(0, Interrupt())
from cable_ocp.entry import main
sys.exit(main(sys.argv[2:]))
"""


def test_the_script_is_the_light_entry_point():
    from importlib.metadata import entry_points

    (script,) = entry_points(group="console_scripts", name="cable-ocp")
    assert script.value == "cable_ocp.entry:main"
    heavy = ["casadi", "numpy", "xarray", "cable_ocp.cli"]  # imported when main runs
    light = subprocess.run([sys.executable, "-c", "import sys, cable_ocp.entry; "
                            f"print([m for m in {heavy!r} if m in sys.modules])"],
                           capture_output=True, text=True, timeout=TIMEOUT, check=True)  # fmt: skip
    assert light.stdout.strip() == "[]"


@pytest.mark.skipif(os.name != "posix", reason="SIGINT")
@pytest.mark.parametrize("module", ["numpy", "casadi", "cable_ocp.cli.arguments"])
def test_ctrl_c_during_the_imports_exits_130_in_one_line(module):
    run = subprocess.run([sys.executable, "-c", SIGINT_IN_THE_IMPORTS, module, "scenes"],
                         capture_output=True, text=True, timeout=TIMEOUT)  # fmt: skip
    assert run.returncode == 130, run.stderr
    assert run.stderr == "cable-ocp: interrupted\n" and run.stdout == ""


def _importing_numpy(pid: int, wait: float = 30.0) -> None:
    """Return once process ``pid`` has mapped numpy (its script's imports are under way).

    A signal before Python has run the script (its own start, slow on a loaded machine) is the
    interpreter's to report, not the script's; without ``/proc``, 0.2 s.
    """
    maps = Path(f"/proc/{pid}/maps")
    if not maps.parent.is_dir():
        time.sleep(0.2)
        return
    started = time.monotonic()
    while time.monotonic() - started < wait:
        try:
            if "numpy" in maps.read_text():
                return
        except OSError:  # the process ended
            return
        time.sleep(0.01)


@pytest.mark.skipif(os.name != "posix", reason="SIGINT")
def test_ctrl_c_right_after_the_script_starts_is_no_traceback(tmp_path):
    """The installed script, interrupted in its imports (as soon as numpy is loading)."""
    script = Path(sys.executable).with_name("cable-ocp")
    if not script.is_file():
        pytest.skip("the cable-ocp script is not installed beside this Python")
    out = tmp_path / "run"
    process = subprocess.Popen([str(script), "simulate", str(MODELS / "hanging.toml"), "--quiet",
                                "--out", str(out)], stderr=subprocess.PIPE, text=True)  # fmt: skip
    _importing_numpy(process.pid)
    process.send_signal(signal.SIGINT)
    stderr = process.communicate(timeout=TIMEOUT)[1]
    assert process.returncode == 130, stderr
    assert "Traceback" not in stderr and stderr.strip().endswith("interrupted")
    assert sorted(p.name for p in tmp_path.iterdir()) == []


@pytest.mark.skipif(os.name != "posix", reason="SIGTERM")
def test_sigterm_during_a_solve_is_an_interrupt_leaving_nothing(tmp_path):
    out = tmp_path / "run"
    command = ["optimize", str(MODELS / "small_tow.toml"), *SMALL, "--solver", "ipopt", "--out",
               str(out)]  # fmt: skip
    code, stderr = _interrupt_when(command, "ipopt iter", number=signal.SIGTERM)
    assert code == 143, stderr
    assert "Traceback" not in stderr and "interrupted" in stderr and "failed" not in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []  # no folder, lock or scratch


@pytest.mark.skipif(os.name != "posix", reason="SIGTERM")
@pytest.mark.parametrize("at", [1, 8])
def test_sigterm_while_a_run_is_written_is_held_to_its_end(tmp_path, at):
    """SIGTERM goes where SIGINT goes: held by the write (which it hung), then an interrupt."""
    out = tmp_path / "run"
    command = ["simulate", str(MODELS / "hanging.toml"), "--set", "numerics.duration=2.0",
               "--quiet", "--out", str(out)]  # fmt: skip
    child = SIGINT_IN_THE_WRITE.replace("AT", str(at)).replace("SIGINT", "SIGTERM")
    child += f"from cable_ocp.entry import main\nsys.exit(main({command!r}))"
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True,
                         timeout=WRITE_TIMEOUT)  # fmt: skip
    assert run.returncode == 143, run.stderr
    assert "interrupted" in run.stderr and "Traceback" not in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []
