"""C code generation of CasADi Functions, compiled once and cached on disk (CONVENTIONS.md §2, §9).

A Function is written as C, optionally with its first forward and reverse derivatives (one
direction each, so the code stays small; CasADi calls them once per direction), compiled with
the system C compiler into a shared library and loaded back as an external Function. The library
is cached under a key that hashes the Function itself (its serialised expression graph), the
caller's description, the CasADi version and the compiler flags, so a second run loads it without
compiling, and a change to the model (and nothing else) compiles anew. Libraries that the model's
code builds deterministically from a structure (:func:`compiled_from`) are keyed by that code
instead, so that a cache hit builds no expression graph at all; several Functions may share one
library, and :func:`compile_in_background` runs their compilers while the caller goes on.

A compiler runs in a process group of its own, killed whole (cc1, as, ld) when its caller is
interrupted or the process exits: a run that ends, by Ctrl-C or otherwise, waits for no compiler
and leaves none running, and its scratch folders are removed (a library is installed only by a
compile that finished).

A library is loaded only if its size and SHA-256 match the record written beside it (a truncated
library makes the loader crash the process with SIGBUS; hashing a 2 MB library takes 1.3 ms,
against 7 ms to load it); a damaged or unloadable one is rebuilt. A compiler that fails, or a
cache that cannot be written, leaves the interpreted Function with a warning, not an exception.
"""

from __future__ import annotations

import atexit
import hashlib
import json
import os
import platform
import queue
import shutil
import signal
import socket
import subprocess
import tempfile
import threading
import time
import warnings
from collections.abc import Callable
from concurrent.futures import Future
from functools import cache
from pathlib import Path
from typing import NamedTuple

import casadi as ca

COMPILER_FLAGS = ("-fPIC", "-shared")


def optimisation_flags(function: ca.Function) -> tuple[str, ...]:
    """The C compiler's optimisation flags for a Function's code.

    A flat SX Function is one long straight-line C function, on which gcc spends most of its
    time allocating registers: -Og compiles it several times faster than -O1 for a tenth more per
    call (gcc 12; the right-hand side's Jacobian at n = 3, 4.4e4 instructions: 4.6 s and 40 us
    against 22.9 s and 36 us; the flat RK4 step at n = 15: 9.4 s and 67 us against 15.1 s and
    61 us; -O0 runs twice as slow again). An MX Function (loops over small Functions,
    :mod:`cable_ocp.model.structured`) compiles in seconds, so it gets -O3 for this processor:
    at n = 100, 56 us against 63 us at -O2 (-ffast-math would gain 10 % more, but lets the
    compiler assume that no NaN occurs, which blow-up detection relies on).
    """
    return _flags(function.is_a("SXFunction"))


def _flags(flat: bool) -> tuple[str, ...]:
    return ("-Og",) if flat else ("-O3", "-march=native")


def _processor() -> str:
    """The processor's model name: code built for one processor may not run on another."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def cache_dir() -> Path:
    """Folder of compiled libraries: ``$CABLE_OCP_CACHE`` or ``~/.cache/cable_ocp``.

    An empty ``$CABLE_OCP_CACHE`` counts as unset (not as the working directory).
    """
    given = os.environ.get("CABLE_OCP_CACHE", "").strip()
    return Path(given).expanduser() if given else Path.home() / ".cache" / "cable_ocp"


# Scratch folders of compiles: ".build-HOST-PID-XXXXXXXX" in the cache, so that the next compile
# can remove those whose process is dead (a compile that was killed).
SCRATCH_PREFIX = ".build-"


def _scratch_folder(cache: Path) -> Path:
    """A new scratch folder in ``cache``, named by this process; dead compiles' are removed."""
    host = socket.gethostname().replace("-", "_")
    for stale in cache.glob(f"{SCRATCH_PREFIX}{host}-*"):
        pid = stale.name.split("-")[2]
        if pid.isdigit() and not _alive(int(pid)) and stale.is_dir() and not stale.is_symlink():
            shutil.rmtree(stale, ignore_errors=True)
    return Path(tempfile.mkdtemp(dir=cache, prefix=f"{SCRATCH_PREFIX}{host}-{os.getpid()}-"))


def _alive(pid: int) -> bool:
    """Whether the process ``pid`` of this host runs (another user's counts as running)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:
        return True
    return True


def find_compiler() -> str | None:
    """Path of the C compiler (``$CC``, a name or a full path; else ``cc`` or ``gcc``), or None.

    A ``$CC`` that is not an executable is reported by a warning and ``cc``/``gcc`` are tried.
    """
    wanted = os.environ.get("CC")
    if wanted:
        found = shutil.which(wanted)
        if found:
            return found
        warnings.warn(
            f"$CC={wanted!r} is not an executable: trying cc and gcc", RuntimeWarning, stacklevel=3
        )
    for name in ("cc", "gcc"):
        found = shutil.which(name)
        if found:
            return found
    return None


def cache_key(function: ca.Function, description: str) -> str:
    """Key of a compiled Function: its expression graph, what built it, CasADi and the flags.

    Serialising the graph takes about 0.7 s at n = 100, against minutes of compiling.
    """
    digest = hashlib.sha256(function.serialize().encode())
    flags = [*optimisation_flags(function), *COMPILER_FLAGS]
    digest.update("|".join([description, ca.__version__, _processor(), *flags]).encode())
    return digest.hexdigest()[:20]


def fingerprint_path(library: Path) -> Path:
    """The record of a library's size and SHA-256 (``NAME.so.json``), written after the library."""
    return library.with_name(library.name + ".json")


def fingerprint(path: Path) -> dict[str, int | str]:
    """Size (bytes) and SHA-256 (hex) of a file."""
    digest, size = hashlib.sha256(), 0
    with path.open("rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
            size += len(block)
    return {"size": size, "sha256": digest.hexdigest()}


def damage(library: Path) -> str | None:
    """Why a cached library must not be loaded, or None when it matches its recorded fingerprint.

    A library without a record is damaged too: the record is written last, so it is either a
    write that was cut short or one that another process is finishing (rebuilding is safe then).
    """
    try:
        recorded = json.loads(fingerprint_path(library).read_text())
    except FileNotFoundError:
        return "size/hash record missing: an interrupted write or an older cable_ocp"
    except (OSError, ValueError):
        return "size/hash record unreadable"
    try:
        actual = fingerprint(library)
    except OSError as error:
        return f"unreadable: {error}"
    if recorded != actual:
        return f"size/hash mismatch: {actual['size']} bytes on disk"
    return None


class CompileReport:
    """What :func:`compiled` did: ``cache_hit`` (bool) and ``compile_time`` (s).

    For a library compiled in the background (:func:`compile_in_background`), ``compile_time``
    is how long its caller waited for it.

    ``library`` is the shared library loaded, or None when the interpreted Function is returned.
    """

    def __init__(self, cache_hit: bool, compile_time: float, library: Path | None):
        self.cache_hit, self.compile_time, self.library = cache_hit, compile_time, library

    def __repr__(self) -> str:
        return (
            f"CompileReport(cache_hit={self.cache_hit}, compile_time={self.compile_time:.2f} s, "
            f"library={self.library})"
        )


class _CompilerFailed(Exception):
    """The C compiler could not be run or exited with an error (the message has its stderr)."""


def _remove(library: Path) -> None:
    """Delete a library and its record if present.

    A read-only cache keeps them: the rebuild then fails to write and falls back to the
    interpreted Function.
    """
    for path in (library, fingerprint_path(library)):
        try:
            path.unlink(missing_ok=True)
        except OSError:
            pass


def _build(
    functions: list[ca.Function], compiler: str, library: Path, derivatives: bool, quiet: bool
) -> None:
    """Generate C for the Functions, compile it, and install the library and its record atomically.

    The Functions share one C file, so the Functions they call are compiled once. Raises
    _CompilerFailed when the compiler fails, OSError when the cache cannot be written.
    """
    if not quiet:
        names = ", ".join(f.name() for f in functions)
        print(f"compiling {names} to C (cached in {library.parent}) ...", flush=True)
    scratch, command = _generate(functions, compiler, library, derivatives)
    try:
        _compile_and_install(command, library, scratch)
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def _generate(
    functions: list[ca.Function], compiler: str, library: Path, derivatives: bool
) -> tuple[Path, list[str]]:
    """Write the Functions' C into a scratch folder of the cache; returns it and the command.

    Raises OSError when the cache cannot be written.
    """
    library.parent.mkdir(parents=True, exist_ok=True)
    scratch = _scratch_folder(library.parent)
    try:
        source = scratch / f"{functions[0].name()}.c"
        generator = ca.CodeGenerator(source.name, {"with_header": False})
        for function in functions:
            generator.add(function)
            if derivatives:
                generator.add(function.forward(1))
                generator.add(function.reverse(1))
        generator.generate(str(scratch) + os.sep)
    except BaseException:
        shutil.rmtree(scratch, ignore_errors=True)
        raise
    flags = [*optimisation_flags(functions[0]), *COMPILER_FLAGS]
    return scratch, [compiler, *flags, str(source), "-o", str(scratch / library.name), "-lm"]


def _compile_and_install(command: list[str], library: Path, scratch: Path) -> None:
    """Run the compiler, then move the library and its record into place (the record last).

    Raises _CompilerFailed when the compiler fails, OSError when the cache cannot be written.
    """
    target = scratch / library.name
    returncode, output = _run_compiler(command)
    if returncode != 0 or not target.is_file():
        output = output.strip()[-2000:] or "no output"
        raise _CompilerFailed(f"{command[0]} exited with status {returncode}:\n{output}")
    record = scratch / "fingerprint.json"
    record.write_text(json.dumps(fingerprint(target)))
    # Atomic renames, the record last: a reader never sees a half-written file, and a library
    # whose record is not there yet counts as damaged (rebuilt, never loaded).
    os.replace(target, library)
    os.replace(record, fingerprint_path(library))


# Compilers running, each the leader of a process group of its own (_run_compiler); once the
# process exits (_stop_compilers), no new one starts. Both guarded by _RUNNING_LOCK.
_RUNNING: set[subprocess.Popen] = set()
_RUNNING_LOCK = threading.Lock()
_exiting = False


def _run_compiler(command: list[str]) -> tuple[int, str]:
    """Run a compiler command in a process group of its own; its exit status and output.

    The whole group (the driver with its cc1, as and ld) is killed when the caller is interrupted
    (KeyboardInterrupt, which is raised again) or the process exits (:func:`_stop_compilers`),
    so that no compiler outlives its run. SIGINT is held back while the compiler starts: a
    Ctrl-C between the fork and the handle's return would otherwise leave it running with no
    one to kill it (seen on a loaded machine). Raises _CompilerFailed when the compiler cannot
    be started or the process is exiting.
    """
    process = None
    held = _hold_interrupts()
    try:
        with _RUNNING_LOCK:
            if _exiting:
                raise _CompilerFailed("not started: the process is exiting")
            try:
                process = subprocess.Popen(
                    command,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.PIPE,
                    text=True,
                    start_new_session=True,
                )
            except OSError as error:
                raise _CompilerFailed(f"cannot run {command[0]}: {error}") from error
            _RUNNING.add(process)
        _release_interrupts(held)  # a Ctrl-C held back is raised from here on, and kills it
        stdout, stderr = process.communicate()
    except BaseException:
        if process is not None:
            _kill_group(process)
        raise
    finally:
        _release_interrupts(held)
        if process is not None:
            _reap(process)
    return process.returncode, stderr or stdout


def _reap(process: subprocess.Popen) -> None:
    """Forget a compiler that ended (or was killed): close its pipes and wait for its exit."""
    with _RUNNING_LOCK:
        _RUNNING.discard(process)
    for pipe in (process.stdout, process.stderr):
        pipe.close()
    process.wait()


def _hold_interrupts() -> set | None:
    """Block SIGINT in this thread (POSIX); the mask to restore, None where nothing was blocked."""
    if not hasattr(signal, "pthread_sigmask"):
        return None
    return signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})


def _release_interrupts(held: set | None) -> None:
    """Restore the signal mask :func:`_hold_interrupts` returned (a held SIGINT then arrives)."""
    if held is not None:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _kill_group(process: subprocess.Popen) -> None:
    """SIGKILL a compiler's process group (the compiler alone where there are none)."""
    try:
        if hasattr(os, "killpg"):
            os.killpg(process.pid, signal.SIGKILL)
        else:
            process.kill()
    except ProcessLookupError:
        pass  # already ended


def compiled(
    function: ca.Function,
    description: str,
    derivatives: bool = True,
    quiet: bool = True,
) -> tuple[ca.Function, CompileReport]:
    """The Function compiled to C (with first derivatives), from the cache when possible.

    A cached library is loaded only if its size and SHA-256 match its record; a damaged one, or
    one CasADi cannot load, is deleted and rebuilt once (with a warning). When no compiler is
    found, the compiler fails, the cache cannot be written or the rebuilt library does not load,
    a RuntimeWarning says why and ``function`` itself (interpreted) is returned.

    Parameters
    ----------
    function : casadi.Function
        An SX Function.
    description : str
        Everything that built the Function (e.g. the model spec and the step), hashed into the
        cache key together with the Function's expression graph.
    derivatives : bool
        Also generate the first forward and reverse derivatives (needed by optimisation, not by
        simulation; they roughly triple the code).
    quiet : bool
        No message about compiling.

    Returns
    -------
    function : casadi.Function
        The external (compiled) Function, or ``function`` itself (interpreted) after a warning.
    report : CompileReport
    """
    key = cache_key(function, f"{description}|derivatives={derivatives}")
    functions, report = _compiled_together([function], key, derivatives, quiet)
    return functions[0], report


def _compiled_together(
    functions: list[ca.Function], key: str, derivatives: bool, quiet: bool
) -> tuple[list[ca.Function], CompileReport]:
    """:func:`compiled` of Functions that share one library (named after the first) and key."""
    interpreted = functions, CompileReport(False, 0.0, None)
    compiler = find_compiler()
    if compiler is None:
        warnings.warn(
            "no C compiler found (set $CC or install gcc): using the interpreted model",
            RuntimeWarning,
            stacklevel=3,
        )
        return interpreted
    names = [f.name() for f in functions]
    library = cache_dir() / f"{names[0]}_{key}.so"
    if library.is_file():
        problem = damage(library)
        if problem is None:
            try:
                return _loaded(names, library), CompileReport(True, 0.0, library)
            except RuntimeError as error:
                problem = f"CasADi cannot load it: {_first_line(error)}"
        warnings.warn(
            f"cached library {library} is damaged ({problem}): rebuilding",
            RuntimeWarning,
            stacklevel=3,
        )
        _remove(library)
    started = time.perf_counter()
    try:
        _build(functions, compiler, library, derivatives, quiet)
    except _CompilerFailed as error:
        warnings.warn(
            f"compiling {', '.join(names)} into {library} failed: {error}\nusing the interpreted "
            "model (fix the compiler or point $CC at a working one)",
            RuntimeWarning,
            stacklevel=3,
        )
        return interpreted
    except OSError as error:
        warnings.warn(
            f"cannot write the compiled-model cache {library.parent} ({error}): using the "
            "interpreted model (point $CABLE_OCP_CACHE at a writable folder)",
            RuntimeWarning,
            stacklevel=3,
        )
        return interpreted
    elapsed = time.perf_counter() - started
    try:
        return _loaded(names, library), CompileReport(False, elapsed, library)
    except RuntimeError as error:
        _remove(library)
        warnings.warn(
            f"the freshly compiled library {library} cannot be loaded ({_first_line(error)}): "
            "using the interpreted model (check the compiler and the CasADi installation)",
            RuntimeWarning,
            stacklevel=3,
        )
        return interpreted


def _loaded(names: list[str], library: Path) -> list[ca.Function]:
    """The Functions ``names`` of a library (RuntimeError when CasADi cannot load one)."""
    return [ca.external(name, str(library)) for name in names]


def source_digest(sources: tuple[str, ...] = ()) -> str:
    """SHA-256 (hex) of the model package's code and of ``sources`` (paths of further modules).

    What the symbolic graphs are built from: with the model's structure it determines them, so a
    library keyed by it needs no graph built to be found (:func:`compiled_from`).
    """
    return _source_digest(tuple(sorted(sources)))


@cache
def _source_digest(sources: tuple[str, ...]) -> str:
    digest = hashlib.sha256()
    for path in [*sorted(Path(__file__).parent.glob("*.py")), *map(Path, sources)]:
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


class Library(NamedTuple):
    """What builds the Functions of one library and keys it in the cache (:func:`compiled_from`).

    Attributes
    ----------
    build : callable
        Builds the Functions ``names``, in that order; called only on a cache miss.
    names : list of str
        The Functions' names, as the library exports them.
    description : str
        Everything else that built them: the model's structure, the derivation.
    flat : bool
        Whether ``build`` gives SX Functions (it sets the flags, :func:`optimisation_flags`).
    sources : tuple of str
        Paths of the modules outside the model package whose code builds them.
    """

    build: Callable[[], list[ca.Function]]
    names: list[str]
    description: str
    flat: bool
    sources: tuple[str, ...] = ()


def compiled_from(library: Library, quiet: bool = True) -> tuple[list[ca.Function], CompileReport]:
    """Functions compiled into one library (no derivatives), keyed by the code that builds them.

    For Functions that the model package's code (and the modules ``sources``) build
    deterministically from a structure: the key hashes that code (:func:`source_digest`), the
    description (the structure and the derivation), the names, CasADi's version, the processor
    and the flags, so that a cache hit loads the library without building the expression graphs
    (0.1 s for the structured right-hand side at n = 15, 1-2 s for the right-hand side's Jacobian
    at n = 3). Any change to that code compiles anew. Functions built from one graph (the
    structured right-hand side, outputs and bond check) compile together in about the time of
    the largest alone: the Functions they call are compiled once.

    Parameters
    ----------
    library : Library
        What builds the Functions and keys them.
    quiet : bool
        No compiler messages.

    Returns
    -------
    functions : list of casadi.Function
        The external (compiled) Functions, or the interpreted ones after a warning.
    report : CompileReport
    """
    key, path = _source_key(library)
    pending = _BACKGROUND.pop(path, None)
    waited = 0.0
    if pending is not None:  # compiling in the background (compile_in_background): wait for it
        begun = time.perf_counter()
        pending.result()
        waited = time.perf_counter() - begun
    if path.is_file() and damage(path) is None:
        try:
            # A background compile counts for the time the caller waited for it.
            report = CompileReport(pending is None, waited, path)
            return _loaded(library.names, path), report
        except RuntimeError:
            pass  # _compiled_together reports and rebuilds it
    return _compiled_together(library.build(), key, derivatives=False, quiet=quiet)


# Libraries being compiled in the background, by path (compile_in_background).
_BACKGROUND: dict[Path, Future] = {}
# Their compiles (future, command, library, scratch), served in the order asked (the library
# needed first, first) by daemon threads, one per processor: the process's exit waits for none
# of them (_stop_compilers). A None stops a thread.
_QUEUE: queue.SimpleQueue = queue.SimpleQueue()
_WORKERS: list[threading.Thread] = []
STOP_TIMEOUT = 10.0  # s that the exit waits for a killed compile to remove its scratch folder


def compile_in_background(library: Library) -> None:
    """Start compiling a library of :func:`compiled_from` while the caller goes on.

    Nothing happens when the library is in the cache, is being compiled already or there is no
    compiler. Otherwise its C is generated here and the compiler runs in a worker thread, one
    per processor, in the order the libraries were asked for (the compiler is a process of its
    own, so the cores work at once); the next :func:`compiled_from` of the library waits for it,
    and reports and retries a failure. A process that exits kills the compilers still running
    and drops those not started (:func:`_stop_compilers`): it waits for none, and leaves no
    half-written library.
    """
    _, path = _source_key(library)
    compiler = find_compiler()
    if path in _BACKGROUND or compiler is None or path.is_file():
        return
    try:
        scratch, command = _generate(library.build(), compiler, path, derivatives=False)
    except OSError:
        return  # compiled_from reports the unwritable cache
    future: Future = Future()
    _BACKGROUND[path] = future
    _QUEUE.put((future, command, path, scratch))
    _WORKERS[:] = [worker for worker in _WORKERS if worker.is_alive()]  # none survives a fork
    if len(_WORKERS) < (os.cpu_count() or 1):
        worker = threading.Thread(target=_serve, name="compile", daemon=True)
        _WORKERS.append(worker)
        worker.start()


def _serve() -> None:
    """A background compiler's thread: the queue's compiles, one at a time, until a None."""
    while (job := _QUEUE.get()) is not None:
        future, command, library, scratch = job
        try:
            _compile_and_install(command, library, scratch)
        except (_CompilerFailed, OSError):
            pass  # compiled_from compiles again and reports why it fails
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
            future.set_result(None)


@atexit.register
def _stop_compilers() -> None:
    """At exit: kill the compilers running, start no other, and remove their scratch folders.

    Runs before the interpreter stops the daemon threads of :func:`compile_in_background`, which
    then empty the queue without compiling; waits up to :data:`STOP_TIMEOUT` for each.
    """
    global _exiting
    with _RUNNING_LOCK:
        _exiting = True
        for process in _RUNNING:
            _kill_group(process)
    for _ in _WORKERS:
        _QUEUE.put(None)
    for worker in _WORKERS:
        worker.join(STOP_TIMEOUT)


def _source_key(library: Library) -> tuple[str, Path]:
    """The cache key of a library of :func:`compiled_from` and its path."""
    names = library.names
    flags = [*_flags(library.flat), *COMPILER_FLAGS]
    digest = source_digest(library.sources)
    text = "|".join([library.description, *names, digest, ca.__version__, _processor(), *flags])
    key = hashlib.sha256(text.encode()).hexdigest()[:20]
    return key, cache_dir() / f"{names[0]}_{key}.so"


def compiled_source(source: Path, defines: dict[str, int] | None = None) -> Path | None:
    """A hand-written C file compiled into a shared library in the cache, or None after a warning.

    For kernels that are loaded with :mod:`ctypes` rather than as CasADi Functions; ``defines``
    are its macros (``-DNAME=value``: sizes fixed at compile time). The key hashes the file, the
    macros, the processor and the flags (those of an MX Function's code: -O3 for this
    processor); a damaged library is rebuilt, and a compiler that fails or a cache that cannot
    be written leaves the caller its own fallback, with a RuntimeWarning that says why.
    """
    macros = [f"-D{name}={value}" for name, value in sorted((defines or {}).items())]
    flags = [*_flags(False), *COMPILER_FLAGS, *macros]
    digest = hashlib.sha256(source.read_bytes())
    digest.update("|".join([_processor(), *flags]).encode())
    library = cache_dir() / f"{source.stem}_{digest.hexdigest()[:20]}.so"
    if library.is_file() and damage(library) is None:
        return library
    compiler = find_compiler()
    if compiler is None:
        warnings.warn(
            f"no C compiler found (set $CC or install gcc): {source.name} runs in numpy",
            RuntimeWarning,
            stacklevel=3,
        )
        return None
    _remove(library)
    try:
        library.parent.mkdir(parents=True, exist_ok=True)
        scratch = _scratch_folder(library.parent)
        command = [compiler, *flags, str(source), "-o", str(scratch / library.name)]
        try:
            _compile_and_install(command, library, scratch)
        finally:
            shutil.rmtree(scratch, ignore_errors=True)
    except (_CompilerFailed, OSError) as error:
        warnings.warn(
            f"compiling {source.name} into {library} failed ({error}): it runs in numpy (fix "
            "the compiler, $CC or $CABLE_OCP_CACHE)",
            RuntimeWarning,
            stacklevel=3,
        )
        return None
    return library


def _first_line(error: Exception) -> str:
    """The first two lines of a CasADi error: a source location, then the reason."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    return " ".join(lines[:2])
