"""Sweep files: TOML read, validated and expanded into cases, every case's scene built up front.

A sweep file names a scene, a task and the overrides of each case::

    scene = "../paper_flat.toml"   # relative to the sweep file, or a bundled scene name
    task = "optimize"              # or "simulate"
    method = "shooting"            # optimize only: "shooting" (old name "ipopt") or "nelder-mead"
    [optimizer]                    # optimize only: the fields of the model, grid, transcription
                                   # and solver settings (and solver); unset ones are optimize()'s
    elements = 3
    [set]                          # dotted-key overrides shared by every case
    "numerics.duration" = 60.0
    [grid]                         # full factorial: one list of values per dotted key
    "environment.current" = [[0, 0, 0], [0.5, 0, 0]]
    "top.tow.surge_speed" = [0.8, 1.16]

or, instead of ``[grid]``, a random design::

    [sample]
    n = 16
    seed = 1
    design = "latin-hypercube"     # or "uniform"
    [sample.ranges]
    "top.tow.surge_speed" = [0.8, 1.4]            # [low, high]
    "environment.current" = [[0, 0, 0], [1, 0.5, 0]]   # componentwise [low, high] vectors

A file path among the overrides (``"seabed.grid.file"``, ``"top.table.file"``, in ``[set]`` or
``[grid]``) is relative to the sweep file's folder, as the scene is; the base scene's own paths
stay relative to the base scene.

Every error is a ``ValueError`` naming the sweep file key (and the case), raised before any
case runs: a bad value, a scene the schema refuses (an H_s of 1e200), or a case whose run cannot
fit in memory (:mod:`cable_ocp.simulation.budget`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import numbers
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from cable_ocp.control.settings import OcpSettings
from cable_ocp.control.solvers import (
    SHOOTING,
    SOLVERS,
    ocp_settings_from,
    solver_for,
    transcription_named,
)
from cable_ocp.scene.bundled import models_dir
from cable_ocp.scene.schema import Scene, SceneError, load_scene
from cable_ocp.simulation.budget import check_memory, check_simulation_memory, optimisation_memory
from cable_ocp.simulation.integrate import step_count

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

TOP_KEYS = ("scene", "description", "task", "method", "optimizer", "set", "grid", "sample")
TASKS = ("simulate", "optimize")
DESIGNS = ("latin-hypercube", "uniform")
SAMPLE_KEYS = ("n", "seed", "design", "ranges")
MAX_CASES = 100_000


@dataclass(frozen=True)
class Case:
    """One case of a sweep.

    Attributes
    ----------
    index : int
        Position in the sweep (0-based), the ``case`` coordinate of the results.
    overrides : dict
        The swept dotted keys and their values in this case (the ``[set]`` keys are not repeated).
    scene : Scene
        The validated scene of the case (``[set]`` and ``overrides`` applied).
    fingerprint : str
        Hash of the case's full scene, task, method and optimiser settings: a case file with
        another fingerprint belongs to another sweep.
    """

    index: int
    overrides: dict
    scene: Scene
    fingerprint: str


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep file.

    Attributes
    ----------
    path : Path
        The sweep file.
    scene_path : Path
        The base scene file.
    task : str
        ``"simulate"`` or ``"optimize"``.
    method : str
        ``"shooting"`` or ``"nelder-mead"`` (used by ``optimize``).
    settings : OcpSettings or None
        Optimiser settings (None for ``simulate``).
    fixed : dict
        The ``[set]`` overrides.
    swept : tuple of str
        The swept dotted keys, in file order.
    design : str
        ``"grid"``, ``"latin-hypercube"``, ``"uniform"`` or ``"single"`` (no sweep table).
    cases : tuple of Case
    text : str
        The sweep file's text (stored with the results).
    """

    path: Path
    scene_path: Path
    task: str
    method: str
    settings: OcpSettings | None
    fixed: dict
    swept: tuple[str, ...]
    design: str
    cases: tuple[Case, ...]
    text: str


def _fail(key: str, detail: str) -> ValueError:
    return ValueError(f"{key}{detail}")


def _table(data: dict, key: str) -> dict:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise _fail(key, f": expected a table, got {type(value).__name__} {value!r}")
    return value


def _find_scene(value: Any, sweep_path: Path) -> Path:
    """The scene file: relative to the sweep file, else a bundled scene name."""
    if not isinstance(value, str) or not value:
        raise _fail("scene", f": expected a scene file path or bundled scene name, got {value!r}")
    models = models_dir()
    candidates = [sweep_path.parent / value, models / value, models / f"{value}.toml"]
    for candidate in candidates:
        if candidate.is_file():
            return candidate.resolve()
    bundled = ", ".join(sorted(p.stem for p in models.glob("*.toml")))
    raise _fail(
        "scene",
        f" = {value!r}: file not found (relative to {sweep_path.parent}); bundled scenes: "
        f"{bundled}",
    )


def _field_spec(key: str):
    """The schema's declaration of a dotted scene key, or None if there is no such field."""
    cls, spec = Scene, None
    for part in key.split("."):
        if spec is not None and spec.kind != "section":
            return None
        declared = {f.name: f.metadata["spec"] for f in fields(cls) if "spec" in f.metadata}
        spec = declared.get(part)
        if spec is None:
            return None
        cls = spec.item
    return spec


def _anchored(key: str, value: Any, folder: Path) -> Any:
    """An override's value with its relative file paths made relative to ``folder``."""
    spec = _field_spec(key)
    if spec is None:
        return value
    if (
        spec.kind == "path"
        and isinstance(value, str)
        and not Path(value).expanduser().is_absolute()
    ):
        return str(folder / Path(value).expanduser())
    if spec.kind == "section" and isinstance(value, dict):
        return {name: _anchored(f"{key}.{name}", v, folder) for name, v in value.items()}
    return value


def _anchored_all(overrides: dict, folder: Path) -> dict:
    return {key: _anchored(key, value, folder) for key, value in overrides.items()}


def bundled_sweeps() -> dict[str, Path]:
    """The example sweep files shipped with the package (``models/sweeps/``), by name."""
    return {p.stem: p for p in sorted((models_dir() / "sweeps").glob("*.toml"))}


def _find_sweep(path: Path) -> Path:
    """The sweep file: a path, else the name of a bundled example (``"tow_speeds"``)."""
    if path.exists() or path.parent != Path("."):
        return path.resolve()
    examples = bundled_sweeps()
    name = path.name.removesuffix(".toml")
    if name in examples:
        return examples[name]
    raise ValueError(
        f"sweep file {path}: not found (nor a bundled example: {', '.join(examples) or 'none'})"
    )


def _settings(data: dict, task: str) -> OcpSettings | None:
    """The ``[optimizer]`` table as one optimize's settings (each field checked by its class).

    A ``method`` given names the transcription; the solver must run on it (none given: the one
    that does, :func:`~cable_ocp.control.solvers.solver_for`).
    """
    options = dict(_table(data, "optimizer"))
    if task == "simulate":
        if options or "method" in data:
            key = "optimizer" if options else "method"
            raise _fail(key, ": only allowed with task = 'optimize'")
        return None
    try:
        solver = solver_for(data.get("method"), options.pop("solver", None))
    except ValueError as error:
        raise _fail("optimizer.solver", f": {error}") from None
    try:
        # Unset fields keep optimize()'s defaults: a reduced model derived from the scene.
        return ocp_settings_from(options, solver)
    except ValueError as error:
        raise _fail("optimizer", f": {error}") from None


def _kind(value: Any) -> str | None:
    """What a swept value is, or None if it cannot be a coordinate of the Dataset."""
    if isinstance(value, bool):
        return "boolean"
    if isinstance(value, numbers.Real):
        return "number"
    if isinstance(value, str):
        return "string"
    if isinstance(value, list) and value and all(_is_number(v) for v in value):
        return "vector"
    return None


def _grid(table: dict) -> tuple[tuple[str, ...], list[dict], list[dict]]:
    """The full factorial: swept keys, each case's overrides and each case's grid positions."""
    for key, values in table.items():
        if not isinstance(values, list) or not values:
            raise _fail(f"grid.{key}", f": expected a non-empty list of values, got {values!r}")
        kinds = set()
        for position, value in enumerate(values):
            kind = _kind(value)
            if kind is None:
                raise _fail(
                    f"grid.{key}[{position}]",
                    f" = {value!r:.60}: a swept value must be a number, a string, a boolean or "
                    "a list of numbers (it becomes a coordinate of sweep.nc); sweep the fields "
                    'of a table one by one, e.g. "top.tow.surge_speed"',
                )
            if kind == "number" and not math.isfinite(value):
                raise _fail(f"grid.{key}[{position}]", f" = {value!r}: must be finite")
            kinds.add(kind)
        if len(kinds) > 1:
            raise _fail(
                f"grid.{key}",
                f": values of one key must be of one kind, got {', '.join(sorted(kinds))}",
            )
    keys = tuple(table)
    count = math.prod(len(v) for v in table.values())
    if count > MAX_CASES:
        raise _fail("grid", f": {count} cases; at most {MAX_CASES}")
    combos = itertools.product(*(range(len(table[k])) for k in keys))
    positions = [dict(zip(keys, combo, strict=True)) for combo in combos]
    overrides = [{k: table[k][p] for k, p in case.items()} for case in positions]
    return keys, overrides, positions


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)


def _range_bounds(
    key: str, value: Any, table: str = "sample.ranges"
) -> tuple[np.ndarray, np.ndarray, bool]:
    """``[low, high]`` (scalar) or ``[[low...], [high...]]`` (vector) -> (low, high, is_vector).

    ``table``: where the range is, for the error.
    """
    where = f"{table}.{key}"
    hint = ": expected [low, high] numbers or [[low, ...], [high, ...]] vectors"
    if not isinstance(value, list) or len(value) != 2:
        raise _fail(where, f"{hint}, got {value!r}")
    low, high = value
    vector = isinstance(low, list)
    if vector:
        if not isinstance(high, list) or len(low) != len(high) or not low:
            raise _fail(where, f"{hint}, got {value!r}")
        low, high = list(low), list(high)
    else:
        low, high = [low], [high]
    if not all(_is_number(v) for v in low + high):
        raise _fail(where, f"{hint}, got {value!r}")
    low, high = np.array(low, dtype=float), np.array(high, dtype=float)
    if np.any(low > high):
        raise _fail(where, f" = {value!r}: low must be <= high")
    return low, high, vector


def _sample(table: dict, base: Scene) -> tuple[str, tuple[str, ...], list[dict]]:
    for name in table:
        if name not in SAMPLE_KEYS:
            raise _fail(f"sample.{name}", f": unknown key; allowed keys: {', '.join(SAMPLE_KEYS)}")
    n, seed = table.get("n"), table.get("seed", 0)
    design = table.get("design", "latin-hypercube")
    if isinstance(n, bool) or not isinstance(n, int) or not 1 <= n <= MAX_CASES:
        raise _fail("sample.n", f" = {n!r}: must be an integer in [1, {MAX_CASES}]")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise _fail("sample.seed", f" = {seed!r}: must be an integer >= 0")
    if design not in DESIGNS:
        raise _fail("sample.design", f" = {design!r}: must be one of {', '.join(DESIGNS)}")
    ranges = table.get("ranges", {})
    overrides = draw(ranges, base, n, seed, design)
    return design, tuple(ranges), overrides


def draw(
    ranges: Any, base: Scene, n: int, seed: int, design: str, table: str = "sample.ranges"
) -> list[dict]:
    """``n`` cases' overrides drawn in ``ranges`` (dotted key -> ``[low, high]``), seeded.

    The random design of a sweep's ``[sample]`` (module docstring), and a policy's family's
    scenes (:mod:`cable_ocp.policy.family`). ``table`` names the ranges in errors: a ValueError
    names the key at fault. A key whose base value is an integer draws integers.
    """
    if not isinstance(ranges, dict):
        raise _fail(table, f": expected a table, got {ranges!r}")
    if not ranges:
        raise _fail(table, ": expected a table of at least one dotted key")
    bounds = {key: _range_bounds(key, value, table) for key, value in ranges.items()}
    integers = {key: isinstance(_base_value(base, key), int) for key in bounds}
    width = sum(low.size for low, _, _ in bounds.values())
    rng = np.random.default_rng(seed)
    if design == "uniform":
        unit = rng.random((n, width))
    else:
        from scipy.stats import qmc

        unit = qmc.LatinHypercube(d=width, seed=rng).random(n)
    overrides = [{} for _ in range(n)]
    column = 0
    for key, (low, high, vector) in bounds.items():
        values = low + unit[:, column : column + low.size] * (high - low)
        column += low.size
        for case, row in zip(overrides, values, strict=True):
            if integers[key]:
                case[key] = int(round(float(row[0])))
            else:
                case[key] = [float(v) for v in row] if vector else float(row[0])
    return overrides


def _base_value(scene: Scene, key: str) -> Any:
    """The base scene's value at a dotted key (None if there is none)."""
    node: Any = scene.to_dict()
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return None if isinstance(node, bool) else node


def _blame(error: SceneError, case: int, overrides: dict, positions: dict | None) -> str:
    """Name the sweep file key behind a scene error of one case (``positions``: in the grid)."""
    for key, value in overrides.items():
        if error.path == key or error.path.startswith((key + ".", key + "[")):
            if positions is not None:
                return f"grid.{key}[{positions[key]}] = {value!r} (case {case}): {error}"
            return f"sample.ranges.{key}: drawn value {value!r} (case {case}): {error}"
    return f"case {case} with {json.dumps(overrides)}: {error}"


def fingerprint(scene: Scene, task: str, method: str, settings: Any) -> str:
    """Hash of everything that determines a case's result (scene, task, method, settings)."""
    record = {
        "scene": scene.to_dict(),
        "task": task,
        "method": method if task == "optimize" else None,
        "settings": asdict(settings) if settings is not None else None,
    }
    return record_hash(record)


def record_hash(record: dict) -> str:
    """16 hex digits of SHA-256 over ``record`` as sorted JSON (a sweep case's, a family's)."""
    text = json.dumps(record, sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _check_intervals(scene: Scene, settings: Any, case: int) -> None:
    """IPOPT's shooting intervals must divide the RK4 steps: checked before any solve.

    Intervals left to the optimiser (None) are derived so that they divide them.
    """
    if settings is None or settings.intervals is None:
        return
    step = settings.step or scene.numerics.step
    try:
        steps = step_count(scene.numerics.duration, step)
    except ValueError as error:
        raise _fail("optimizer.step", f" = {step} (case {case}): {error}") from None
    if steps % settings.intervals:
        raise _fail(
            "optimizer.intervals",
            f" = {settings.intervals} (case {case}): must divide the {steps} RK4 steps "
            f"(numerics.duration = {scene.numerics.duration} s, step = {step} s)",
        )


def _check_memory(scene: Scene, settings: Any, case: int) -> None:
    """Each case's runs must fit in memory: the scene's simulation, and an optimiser's horizon."""
    try:
        check_simulation_memory(scene)
        if settings is not None and SOLVERS[settings.solver].transcription is SHOOTING:
            step = settings.step or scene.numerics.step
            estimate = optimisation_memory(scene, step, elements=settings.elements)
            check_memory(estimate, f"optimizer.step = {step} s", "give a longer optimizer.step")
    except ValueError as error:
        raise ValueError(f"case {case}: {error}") from None


def load_sweep(path: str | Path) -> SweepSpec:
    """Read a sweep file, expand its cases and build (validate) every case's scene.

    Parameters
    ----------
    path : path-like
        The sweep TOML file, or the name of a bundled example (:func:`bundled_sweeps`).

    Returns
    -------
    SweepSpec

    Raises
    ------
    ValueError
        Naming the sweep file key (and case) at fault, before any case runs.
    """
    path = _find_sweep(Path(path))
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as error:
        raise ValueError(f"sweep file {path}: cannot be read: {error}") from None
    except UnicodeDecodeError as error:
        raise ValueError(
            f"sweep file {path}: not a text file (TOML must be UTF-8: byte {error.start} is "
            f"{error.object[error.start : error.start + 1]!r})"
        ) from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"sweep file {path}: invalid TOML: {error}") from None
    except RecursionError:
        raise ValueError(f"sweep file {path}: invalid TOML: nested too deeply") from None
    for key in data:
        if key not in TOP_KEYS:
            raise _fail(key, f": unknown key; allowed keys: {', '.join(TOP_KEYS)}")
    if "scene" not in data:
        raise _fail("scene", ": missing required key (the base scene file)")
    scene_path = _find_scene(data["scene"], path)
    task = data.get("task", "simulate")
    if task not in TASKS:
        raise _fail("task", f" = {task!r}: must be one of {', '.join(TASKS)}")
    try:
        method = transcription_named(data.get("method", SHOOTING.name)).name
    except ValueError as error:
        raise _fail("method", f": {error}") from None
    settings = _settings(data, task)
    fixed = _table(data, "set")
    try:
        base = load_scene(scene_path, _anchored_all(fixed, path.parent))
    except SceneError as error:
        culprit = [k for k in fixed if error.path == k or error.path.startswith((k + ".", k + "["))]
        raise _fail(f"set.{culprit[0]}" if culprit else "set", f": {error}") from None
    grid, sample = _table(data, "grid"), _table(data, "sample")
    if grid and sample:
        raise _fail("sample", ": give either [grid] or [sample], not both")
    positions: list = []
    if grid:
        design = "grid"
        swept, overrides, positions = _grid(grid)
    elif sample:
        design, swept, overrides = _sample(sample, base)
    else:
        design, swept, overrides = "single", (), [{}]
    cases = []
    for index, case in enumerate(overrides):
        try:
            scene = base.updated(_anchored_all(case, path.parent))
        except SceneError as error:
            where = positions[index] if positions else None
            raise ValueError(_blame(error, index, case, where)) from None
        _check_intervals(scene, settings, index)
        _check_memory(scene, settings, index)
        cases.append(Case(index, case, scene, fingerprint(scene, task, method, settings)))
    for key, values in grid.items():
        lengths = sorted({len(v) for v in values if isinstance(v, list)})
        if len(lengths) > 1:  # one coordinate per component needs one length
            raise _fail(f"grid.{key}", f": vectors of {lengths} numbers; give one length")
    return SweepSpec(
        path=path,
        scene_path=scene_path,
        task=task,
        method=method,
        settings=settings,
        fixed=dict(fixed),
        swept=swept,
        design=design,
        cases=tuple(cases),
        text=text,
    )
