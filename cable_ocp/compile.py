"""C code generation of CasADi Functions, compiled once and cached on disk (DESIGN.md §2, §9).

A Function is written as C, optionally with its first forward and reverse derivatives (one
direction each, so the code stays small; CasADi calls them once per direction), compiled with
the system C compiler into a shared library and loaded back as an external Function. The library
is cached under a key that hashes the Function itself (its serialised expression graph), the
caller's description, the CasADi version and the compiler flags, so a second run loads it without
compiling, and a change to the model (and nothing else) compiles anew.
"""

from __future__ import annotations

import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import time
import warnings
from pathlib import Path

import casadi as ca

COMPILER_FLAGS = ("-fPIC", "-shared")


def optimisation_flags(function: ca.Function) -> tuple[str, ...]:
    """The C compiler's optimisation flags for a Function's code.

    A flat SX Function is one long straight-line C function, for which -O1 compiles in a
    fraction of -O2's time at the same speed (measured at n = 15: 14.4 vs 14.3 us per call). An
    MX Function (loops over small Functions, :mod:`cable_ocp.structured`) compiles in seconds, so
    it gets -O3 for this processor: at n = 100, 56 us against 63 us at -O2 (-ffast-math would
    gain 10 % more, but lets the compiler assume that no NaN occurs, which blow-up detection
    relies on).
    """
    return ("-O1",) if function.is_a("SXFunction") else ("-O3", "-march=native")


def _processor() -> str:
    """The processor's model name: code built for one processor may not run on another."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def cache_dir() -> Path:
    """Folder of compiled libraries: ``$CABLE_OCP_CACHE`` or ``~/.cache/cable_ocp``."""
    return Path(os.environ.get("CABLE_OCP_CACHE", Path.home() / ".cache" / "cable_ocp"))


def find_compiler() -> str | None:
    """Path of the C compiler (``$CC``, ``cc`` or ``gcc``), or None."""
    for name in (os.environ.get("CC"), "cc", "gcc"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def cache_key(function: ca.Function, description: str) -> str:
    """Key of a compiled Function: its expression graph, what built it, CasADi and the flags.

    Serialising the graph takes about 0.7 s at n = 100, against minutes of compiling.
    """
    digest = hashlib.sha256(function.serialize().encode())
    flags = [*optimisation_flags(function), *COMPILER_FLAGS]
    digest.update("|".join([description, ca.__version__, _processor(), *flags]).encode())
    return digest.hexdigest()[:20]


class CompileReport:
    """What :func:`compiled` did: ``cache_hit`` (bool) and ``compile_time`` (s)."""

    def __init__(self, cache_hit: bool, compile_time: float, library: Path | None):
        self.cache_hit, self.compile_time, self.library = cache_hit, compile_time, library

    def __repr__(self) -> str:
        return (
            f"CompileReport(cache_hit={self.cache_hit}, compile_time={self.compile_time:.2f} s, "
            f"library={self.library})"
        )


def compiled(
    function: ca.Function, description: str, derivatives: bool = True, quiet: bool = True
) -> tuple[ca.Function, CompileReport]:
    """The Function compiled to C (with first derivatives), from the cache when possible.

    Parameters
    ----------
    function : casadi.Function
        An SX Function.
    description : str
        Everything that determines the Function (e.g. the model spec and the step), hashed into
        the cache key together with the package's sources.
    derivatives : bool
        Also generate the first forward and reverse derivatives (needed by optimisation, not by
        simulation; they roughly triple the code).
    quiet : bool
        No message about compiling.

    Returns
    -------
    function : casadi.Function
        The external (compiled) Function, or ``function`` itself when no C compiler is found (a
        warning says so).
    report : CompileReport
    """
    compiler = find_compiler()
    if compiler is None:
        warnings.warn(
            "no C compiler found (set $CC or install gcc): using the interpreted model",
            RuntimeWarning,
            stacklevel=2,
        )
        return function, CompileReport(False, 0.0, None)
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    name = function.name()
    key = cache_key(function, f"{description}|derivatives={derivatives}")
    library = folder / f"{name}_{key}.so"
    if library.exists():
        return ca.external(name, str(library)), CompileReport(True, 0.0, library)
    started = time.perf_counter()
    if not quiet:
        print(f"compiling {name} to C (cached in {folder}) ...", flush=True)
    with tempfile.TemporaryDirectory(dir=folder) as scratch:
        source = Path(scratch) / f"{name}.c"
        generator = ca.CodeGenerator(source.name, {"with_header": False})
        generator.add(function)
        if derivatives:
            generator.add(function.forward(1))
            generator.add(function.reverse(1))
        generator.generate(str(Path(scratch)) + os.sep)
        target = Path(scratch) / library.name
        result = subprocess.run(
            [
                compiler,
                *optimisation_flags(function),
                *COMPILER_FLAGS,
                str(source),
                "-o",
                str(target),
                "-lm",
            ],  # fmt: skip
            capture_output=True,
            text=True,
        )
        if result.returncode != 0:
            raise RuntimeError(f"compiling {name} failed:\n{result.stderr[-2000:]}")
        os.replace(target, library)  # atomic: a half-written library is never seen
    elapsed = time.perf_counter() - started
    return ca.external(name, str(library)), CompileReport(False, elapsed, library)
