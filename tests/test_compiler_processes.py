"""The C compiler's processes end with the run (cable_ocp.model.compile, issue 45 D1).

A stand-in compiler (a shell script whose own child plays cc1) is run by a child Python process;
the test checks that every process of the compiler ends when the run is interrupted or simply
exits, that the exit does not wait for the compile, and that no scratch folder or library is left.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.skipif(
    not sys.platform.startswith("linux"), reason="process groups and /proc"
)

# Records its pid and its child's (the "cc1"), then waits for the child, which never ends alone.
COMPILER = '#!/bin/sh\nsleep 600 &\necho "$$ $!" > "{record}"\nwait\n'
BOUND = 10.0  # s from the signal (or the end of the script) to the process's exit
# The child: compiles a tiny Function with the stand-in compiler, in the foreground or the
# background, and exits (or is interrupted) once the compiler runs.
CHILD = textwrap.dedent(
    """
    import os, signal, sys, threading, time
    from pathlib import Path
    import casadi as ca
    from cable_ocp.model import compile as compile_module

    record, how = Path(sys.argv[1]), sys.argv[2]
    x = ca.SX.sym("x", 2)
    tiny = ca.Function("tiny_process", [x], [ca.sin(x)])
    library = compile_module.Library(lambda: [tiny], ["tiny_process"], "process test " + how, True)

    def wait_until_running():
        while not record.is_file() or not record.read_text().strip():
            time.sleep(0.01)
        print("running", flush=True)

    def interrupt_once_running():
        wait_until_running()
        os.kill(os.getpid(), signal.SIGINT)  # to the process: its main thread takes it

    if how == "exit":  # exits while the compiler runs, without waiting for it
        compile_module.compile_in_background(library)
        wait_until_running()
    else:  # interrupted while compiling, or while waiting for the background compile
        threading.Thread(target=interrupt_once_running, daemon=True).start()
        if how == "background":
            compile_module.compile_in_background(library)
        try:
            compile_module.compiled_from(library)
        except KeyboardInterrupt:
            print("interrupted", flush=True)
    print("exiting", flush=True)
    """
)


def _running(pid: int) -> bool:
    """Whether the process ``pid`` exists and is not a zombie."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (FileNotFoundError, ProcessLookupError):
        return False
    return state not in ("Z", "X")


@pytest.mark.parametrize("how", ["foreground", "background", "exit"])
def test_a_run_that_ends_kills_the_whole_compiler_and_leaves_no_scratch(tmp_path, how):
    cache, record = tmp_path / "cache", tmp_path / "compiler.pids"
    compiler = tmp_path / "slow-cc"
    compiler.write_text(COMPILER.format(record=record))
    compiler.chmod(0o755)
    env = {**os.environ, "CC": str(compiler), "CABLE_OCP_CACHE": str(cache)}
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(record), how], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    assert child.stdout.readline() == "running\n", child.communicate(timeout=60)
    started = time.monotonic()
    child.wait(timeout=60)
    out, err = child.stdout.read(), child.stderr.read()  # small: no pipe fills up
    assert time.monotonic() - started < BOUND, err  # waited for no compiler
    assert child.returncode == 0, err
    assert "Traceback" not in err and "exiting" in out
    assert ("interrupted" in out) == (how != "exit")
    pids = [int(pid) for pid in record.read_text().split()]
    deadline = time.monotonic() + 5
    while any(map(_running, pids)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(map(_running, pids)), "the compiler or its child outlived the run"
    assert sorted(p.name for p in cache.iterdir()) == []  # no scratch folder, no library


def test_background_compiles_still_finish_and_load(tmp_path, monkeypatch):
    """Several libraries compiled side by side by the daemon workers, each then loaded."""
    import casadi as ca

    from cable_ocp.model import compile as compile_module

    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    x = ca.SX.sym("x", 2)
    arguments = [
        compile_module.Library(
            lambda k=k: [ca.Function(f"tiny_many_{k}", [x], [x * k])], [f"tiny_many_{k}"],
            "many background compiles", True,
        )
        for k in range(1, 5)
    ]  # fmt: skip
    for each in arguments:
        compile_module.compile_in_background(each)
    for k, each in enumerate(arguments, start=1):
        functions, report = compile_module.compiled_from(each)
        assert report.library is not None and not report.cache_hit
        assert float(functions[0]([1.0, 2.0])[1]) == 2.0 * k
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_a_ctrl_c_while_the_compiler_starts_still_kills_it(tmp_path, monkeypatch):
    """SIGINT delivered inside ``Popen`` (after the fork) is held back, then kills the group.

    On a loaded machine the stand-in compiler above was left running when the Ctrl-C arrived
    before ``Popen`` had returned its handle: nothing knew its process to kill.
    """
    import signal

    from cable_ocp.model import compile as compile_module

    record = tmp_path / "compiler.pids"
    real_popen = subprocess.Popen

    def interrupted_popen(*args, **kwargs):
        process = real_popen(*args, **kwargs)
        while not record.is_file() or not record.read_text().strip():
            time.sleep(0.01)
        signal.raise_signal(signal.SIGINT)  # the compiler runs; its handle is not yet returned
        return process

    monkeypatch.setattr(compile_module.subprocess, "Popen", interrupted_popen)
    script = f'sleep 600 & echo "$$ $!" > "{record}"; wait'
    with pytest.raises(KeyboardInterrupt):
        compile_module._run_compiler(["sh", "-c", script])
    pids = [int(pid) for pid in record.read_text().split()]
    deadline = time.monotonic() + 5
    while any(map(_running, pids)) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(map(_running, pids)), "the compiler outlived the Ctrl-C"
    assert not compile_module._RUNNING
