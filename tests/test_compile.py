"""Compiled mode: the C step equals the interpreted one, and a second build hits the cache."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from cable_ocp.model import compile as compile_module
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.integrate import rk4_step


@pytest.fixture(scope="module")
def tiny_step(models_dir):
    scene = load_scene(models_dir / "small_tow.toml", {"model.elements": 2})
    model = CableModel.from_scene(scene)
    return model, rk4_step(model, 0.05)


def test_compiled_step_matches_and_is_cached(tiny_step, tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    model, step = tiny_step
    description = f"{model.spec!r}|step=0.05"
    fast, first = compile_module.compiled(step, description, derivatives=True)
    assert not first.cache_hit and first.compile_time > 0
    again, second = compile_module.compiled(step, description, derivatives=True)
    assert second.cache_hit and second.compile_time == 0.0
    assert second.library == first.library
    rng = np.random.default_rng(0)
    x = rng.normal(size=model.state_size) * 0.1
    u = rng.normal(size=(15, 3))
    u[INPUTS.top_length] = 25.0
    reference = np.array(step(x, u))
    for f in (fast, again):
        assert np.allclose(np.array(f(x, u)), reference, rtol=1e-12, atol=1e-12)
    # The compiled first derivatives agree with the interpreted ones.
    import casadi as ca

    xs = ca.MX.sym("x", model.state_size)
    jac = [ca.Function("j", [xs], [ca.jacobian(f(xs, u), xs)]) for f in (step, fast)]
    assert np.allclose(np.array(jac[0](x)), np.array(jac[1](x)), rtol=1e-10, atol=1e-10)
    # Another description is another library.
    _, other = compile_module.compiled(step, description + "|other", derivatives=False)
    assert not other.cache_hit and other.library != first.library


def test_without_a_compiler_falls_back_to_interpreted(tiny_step, monkeypatch):
    monkeypatch.setattr(compile_module, "find_compiler", lambda: None)
    _, step = tiny_step
    with pytest.warns(RuntimeWarning, match="no C compiler"):
        function, report = compile_module.compiled(step, "x")
    assert function is step and not report.cache_hit


SECOND_PROCESS = """
from cable_ocp.model.compile import compiled
from cable_ocp.simulation.integrate import rk4_step
from cable_ocp.model.cable import CableModel
from cable_ocp.scene.schema import load_scene
scene = load_scene({scene!r}, {{"model.elements": 2, "hydrodynamics.drag_normal": {drag}}})
model = CableModel.from_scene(scene)
print(compiled(rk4_step(model, 0.05), "step", derivatives=False)[1].cache_hit)
"""


def test_a_second_process_loads_from_the_cache_and_a_changed_model_compiles(models_dir, tmp_path):
    """The key hashes the expression graph: the same model rebuilt elsewhere hits the cache."""
    import os
    import subprocess
    import sys

    def hit(drag: float) -> bool:
        code = SECOND_PROCESS.format(scene=str(models_dir / "small_tow.toml"), drag=drag)
        env = {**os.environ, "CABLE_OCP_CACHE": str(tmp_path)}
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        return out.stdout.strip() == "True"

    assert not hit(1.0)  # first build compiles
    assert hit(1.0)  # a new process, the same model: loaded from the cache
    assert not hit(1.2)  # other physics, other code: compiled anew


# --- A damaged cache, a failing compiler, an unwritable cache (a tiny Function: ~1 s compiles) ---

TINY_POINT = [0.3, -1.2, 2.0]
TINY_VALUE = np.sin(TINY_POINT) * np.square(TINY_POINT)

TINY_PROCESS = """
import json, warnings
import casadi as ca
from cable_ocp.model.compile import compiled
x = ca.SX.sym("x", 3)
tiny = ca.Function("tiny", [x], [ca.sin(x) * x**2])
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    function, report = compiled(tiny, "tiny")
print(json.dumps({
    "warnings": [str(w.message) for w in caught],
    "hit": report.cache_hit,
    "library": str(report.library),
    "value": [float(v) for v in ca.DM(function([0.3, -1.2, 2.0])).full().ravel()],
}))
"""


def tiny_function():
    import casadi as ca

    x = ca.SX.sym("x", 3)
    return ca.Function("tiny", [x], [ca.sin(x) * x**2])


def run_tiny(cache):
    """Compile or load the tiny Function in a new process: a loader crash fails the test only."""
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, "CABLE_OCP_CACHE": str(cache)}
    out = subprocess.run(
        [sys.executable, "-c", TINY_PROCESS], env=env, capture_output=True, text=True
    )
    assert out.returncode == 0, (
        f"exit status {out.returncode} (-7 is SIGBUS):\n{out.stderr[-2000:]}"
    )
    return json.loads(out.stdout)


def truncate(library):
    data = library.read_bytes()
    library.write_bytes(data[: len(data) // 2])


def garbage(library):
    library.write_bytes(np.random.default_rng(1).bytes(len(library.read_bytes())))


def garbage_with_its_record(library):
    """Bytes that pass the hash but do not load (as a library built by another CasADi would)."""
    import json

    garbage(library)
    record = compile_module.fingerprint_path(library)
    record.write_text(json.dumps(compile_module.fingerprint(library)))


def record_missing(library):
    compile_module.fingerprint_path(library).unlink()


@pytest.mark.parametrize(
    ("damage", "reason"),
    [
        (truncate, "size/hash mismatch"),
        (garbage, "size/hash mismatch"),
        (garbage_with_its_record, "CasADi cannot load it"),
        (record_missing, "record missing"),
    ],
)
def test_a_damaged_cached_library_is_rebuilt_not_loaded(tmp_path, damage, reason):
    first = run_tiny(tmp_path)
    assert not first["hit"] and first["warnings"] == []
    library = Path(first["library"])
    intact = library.read_bytes()
    damage(library)
    second = run_tiny(tmp_path)
    assert len(second["warnings"]) == 1
    message = second["warnings"][0]
    assert f"cached library {library} is damaged" in message and reason in message
    assert "rebuilding" in message
    assert not second["hit"] and second["library"] == str(library)
    assert np.allclose(second["value"], TINY_VALUE, rtol=1e-14, atol=0)
    # The rebuilt library has its record again, so the next process loads it quietly.
    assert library.read_bytes() == intact
    assert compile_module.damage(library) is None
    third = run_tiny(tmp_path)
    assert third["hit"] and third["warnings"] == []


def test_a_second_call_hits_the_cache_after_a_cheap_hash_check(tmp_path, monkeypatch):
    import time
    import warnings

    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    tiny = tiny_function()
    _, first = compile_module.compiled(tiny, "tiny")
    record = compile_module.fingerprint_path(first.library)
    assert record.is_file() and compile_module.damage(first.library) is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        function, second = compile_module.compiled(tiny, "tiny")
    assert second.cache_hit and second.library == first.library
    assert np.allclose(np.array(function(TINY_POINT)).ravel(), TINY_VALUE, rtol=1e-14, atol=0)
    started = time.perf_counter()
    compile_module.damage(first.library)
    elapsed = time.perf_counter() - started
    size = first.library.stat().st_size
    print(f"hash check of a {size} byte library: {elapsed * 1e3:.3f} ms")


def test_a_failing_compiler_warns_with_its_stderr_and_falls_back(tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path / "cache"))
    compiler = tmp_path / "broken-cc"
    compiler.write_text("#!/bin/sh\necho 'broken-cc: licence expired' >&2\nexit 3\n")
    compiler.chmod(0o755)
    monkeypatch.setenv("CC", str(compiler))
    tiny = tiny_function()
    with pytest.warns(RuntimeWarning, match="exited with status 3") as caught:
        function, report = compile_module.compiled(tiny, "tiny")
    assert "broken-cc: licence expired" in str(caught[0].message)
    assert "using the interpreted model" in str(caught[0].message)
    assert function is tiny and report.library is None and not report.cache_hit
    assert list((tmp_path / "cache").glob("*.so*")) == []  # nothing half-built is left behind


def test_cc_bin_false_is_honoured_and_falls_back(tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", "/bin/false")
    assert compile_module.find_compiler() == "/bin/false"
    tiny = tiny_function()
    with pytest.warns(RuntimeWarning, match=r"/bin/false exited with status 1:\nno output"):
        function, report = compile_module.compiled(tiny, "tiny")
    assert function is tiny and report.library is None
    assert np.allclose(np.array(function(TINY_POINT)).ravel(), TINY_VALUE, rtol=1e-14, atol=0)


def test_a_cc_that_does_not_exist_warns_and_uses_cc(monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler-xyz")
    with pytest.warns(RuntimeWarning, match="no-such-compiler-xyz.*not an executable"):
        found = compile_module.find_compiler()
    assert found is not None and Path(found).name in ("cc", "gcc")


def test_an_unwritable_cache_warns_and_falls_back(tmp_path, monkeypatch):
    # A folder below a regular file cannot be created, not even by root (chmod would not stop root).
    blocker = tmp_path / "file.txt"
    blocker.write_text("not a folder")
    monkeypatch.setenv("CABLE_OCP_CACHE", str(blocker / "cache"))
    tiny = tiny_function()
    with pytest.warns(RuntimeWarning, match="cannot write the compiled-model cache") as caught:
        function, report = compile_module.compiled(tiny, "tiny")
    assert "CABLE_OCP_CACHE" in str(caught[0].message)
    assert function is tiny and report.library is None and not report.cache_hit
    assert np.allclose(np.array(function(TINY_POINT)).ravel(), TINY_VALUE, rtol=1e-14, atol=0)


def test_two_processes_compiling_the_same_library_at_once_both_succeed(tmp_path):
    import json
    import os
    import subprocess
    import sys

    env = {**os.environ, "CABLE_OCP_CACHE": str(tmp_path)}
    runs = [
        subprocess.Popen([sys.executable, "-c", TINY_PROCESS], env=env, stdout=subprocess.PIPE)
        for _ in range(2)
    ]
    results = [json.loads(run.communicate()[0]) for run in runs]
    assert [run.returncode for run in runs] == [0, 0]
    for result in results:
        assert np.allclose(result["value"], TINY_VALUE, rtol=1e-14, atol=0)
    (library,) = tmp_path.glob("tiny_*.so")
    assert compile_module.damage(library) is None
    assert run_tiny(tmp_path)["hit"]


def test_a_library_that_never_loads_is_rebuilt_once_then_interpreted(tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    tiny = tiny_function()
    _, first = compile_module.compiled(tiny, "tiny")  # intact library and record

    def refuse(name, path):
        raise RuntimeError(".../casadi_os.cpp:335: Assertion failed:\nCannot load shared library")

    monkeypatch.setattr(compile_module.ca, "external", refuse)
    with pytest.warns(RuntimeWarning) as caught:
        function, report = compile_module.compiled(tiny, "tiny")
    messages = [str(w.message) for w in caught]
    assert len(messages) == 2
    assert "is damaged (CasADi cannot load it" in messages[0] and "rebuilding" in messages[0]
    assert "freshly compiled library" in messages[1] and "Cannot load shared library" in messages[1]
    assert function is tiny and report.library is None
    assert not first.library.exists()  # the unloadable rebuild is not left to fail again


# --- Libraries keyed by the code that builds them, compiled in the background ---


def test_the_source_digest_follows_the_code(tmp_path):
    """The key of a code-keyed library changes with the code it is built from, not otherwise."""
    module = tmp_path / "derive.py"
    module.write_text("A = 1\n")
    first = compile_module.source_digest((str(module),))
    assert compile_module.source_digest((str(module),)) == first
    other = tmp_path / "other.py"
    other.write_text("A = 2\n")
    assert compile_module.source_digest((str(other),)) != first
    assert compile_module.source_digest() != first  # the model package alone


def test_a_background_compile_is_waited_for_and_then_loaded(tmp_path, monkeypatch):
    """compile_in_background writes the C and runs the compiler in a worker; compiled_from then
    waits for it (not a cache hit, the wait as its compile time), a second call hits the cache,
    and the compiled Functions equal the interpreted ones."""
    import casadi as ca

    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    x = ca.SX.sym("x", 3)
    functions = [
        ca.Function("tiny_sine", [x], [ca.sin(x) * x**2]),
        ca.Function("tiny_square", [x], [x**2 + 1]),
    ]
    built = []

    def build():
        built.append(True)
        return functions

    names = ["tiny_sine", "tiny_square"]
    arguments = compile_module.Library(build, names, "background test", True)
    compile_module.compile_in_background(arguments)
    assert len(built) == 1
    compile_module.compile_in_background(arguments)  # already under way: nothing new
    assert len(built) == 1
    loaded, report = compile_module.compiled_from(arguments)
    assert not report.cache_hit and report.library.is_file()
    assert len(built) == 1  # built once, for the background compile
    assert np.allclose(np.array(loaded[0](TINY_POINT)).ravel(), TINY_VALUE, rtol=1e-14, atol=0)
    assert np.allclose(np.array(loaded[1](TINY_POINT)).ravel(), np.square(TINY_POINT) + 1)
    again, second = compile_module.compiled_from(arguments)
    assert second.cache_hit and second.library == report.library and len(built) == 1
    assert not list(tmp_path.glob("tmp*"))  # no scratch folder left behind


def test_a_failed_background_compile_is_reported_by_the_foreground(tmp_path, monkeypatch):
    """A compiler that fails in the background leaves compiled_from to try again, warn with its
    reason and return the interpreted Functions."""
    import casadi as ca

    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path / "cache"))
    compiler = tmp_path / "broken-cc"
    compiler.write_text("#!/bin/sh\necho 'broken: no code today' >&2\nexit 3\n")
    compiler.chmod(0o755)
    monkeypatch.setenv("CC", str(compiler))
    x = ca.SX.sym("x", 3)
    tiny = ca.Function("tiny_failing", [x], [ca.sin(x) * x**2])
    arguments = compile_module.Library(
        lambda: [tiny], ["tiny_failing"], "failing background test", True
    )
    compile_module.compile_in_background(arguments)
    with pytest.warns(RuntimeWarning, match="broken: no code today"):
        functions, report = compile_module.compiled_from(arguments)
    assert functions[0] is tiny and report.library is None


def test_an_empty_cache_variable_is_the_default_cache_not_the_working_folder(monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", "")
    assert compile_module.cache_dir() == Path.home() / ".cache" / "cable_ocp"


def test_the_scratch_of_a_killed_compile_is_removed_by_the_next(tmp_path, monkeypatch):
    import socket
    import subprocess
    import sys

    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    host = socket.gethostname().replace("-", "_")
    killed = tmp_path / f"{compile_module.SCRATCH_PREFIX}{host}-{dead}-abcd1234"
    live = tmp_path / f"{compile_module.SCRATCH_PREFIX}{host}-{os.getpid()}-live0000"
    for folder in (killed, live):
        folder.mkdir()
        (folder / "tiny.c").write_text("half")
    _, report = compile_module.compiled(tiny_function(), "tiny scratch")
    assert report.library is not None and not killed.exists() and live.is_dir()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".build-") and p != live]
