"""A scene family: a base scene and ranges of its fields, from which scenes are drawn.

A family file is a sweep file's random design without its count (:mod:`cable_ocp.sweep.spec`)::

    name = "hill_tow"
    description = "paper_hill with heave and current"
    scene = "paper_hill"            # a bundled scene's name, or a path relative to this file
    hold = 60.0                     # optional: the base is the scene's landing held this long
    [set]                           # dotted-key overrides of the base
    "numerics.duration" = 210.0
    [ranges]                        # [low, high] or componentwise [[low...], [high...]]
    "top.tow.surge_speed" = [1.0, 1.3]
    "environment.current" = [[0, 0, 0], [0.3, 0.1, 0]]

``hold`` (s) makes the base :func:`cable_ocp.lowering.hold.hold_scene` of the scene (deploy's
kind: the load landed and held above its target, the vessel on station), the ranges then drawn
on it. :meth:`Family.draw` draws ``n`` scenes by a seeded Latin hypercube; its
:attr:`Family.fingerprint` identifies the family in a policy's file.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from cable_ocp.scene.bundled import models_dir
from cable_ocp.scene.schema import Scene, SceneError, load_scene
from cable_ocp.sweep.spec import draw, record_hash

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

KEYS = ("name", "description", "scene", "hold", "set", "ranges")
DESIGN = "latin-hypercube"


def bundled_families() -> dict[str, Path]:
    """The family files shipped in ``models/families``, by name."""
    return {path.stem: path for path in sorted((models_dir() / "families").glob("*.toml"))}


@dataclass(frozen=True)
class Family:
    """A validated family file (module docstring).

    Attributes
    ----------
    name : str
    description : str
    base : Scene
        The base scene, ``[set]`` applied (and held, with ``hold``).
    ranges : dict
        Dotted key -> ``[low, high]``.
    hold : float or None, s
    text : str
        The family file's text.
    """

    name: str
    description: str
    base: Scene
    ranges: dict
    hold: float | None
    text: str

    @property
    def fingerprint(self) -> str:
        """Hash of the base scene, the ranges and the hold (16 hex digits)."""
        return record_hash({"base": self.base.to_dict(), "ranges": self.ranges, "hold": self.hold})

    def record(self) -> dict:
        """What a policy keeps of its family: name, description, fingerprint, ranges, file."""
        return {
            "name": self.name,
            "description": self.description,
            "fingerprint": self.fingerprint,
            "ranges": self.ranges,
            "hold": self.hold,
            "text": self.text,
        }

    def draws(self, n: int, seed: int) -> list[dict]:
        """The overrides of ``n`` scenes drawn by the seeded Latin hypercube."""
        return draw(self.ranges, self.base, n, seed, DESIGN, "ranges")

    def draw(self, n: int, seed: int) -> list[Scene]:
        """``n`` scenes of the family, drawn with ``seed`` (the same seed, the same scenes).

        Raises
        ------
        ValueError
            A drawn scene that the schema refuses, naming the key and the value.
        """
        scenes = []
        for case, overrides in enumerate(self.draws(n, seed)):
            try:
                scenes.append(self.base.updated(overrides))
            except SceneError as error:
                raise ValueError(
                    f"family {self.name}: scene {case} drawn with {json.dumps(overrides)}: {error}"
                ) from None
        return scenes


def _fail(path: Path, key: str, detail: str) -> ValueError:
    return ValueError(f"family file {path}: {key}{detail}")


def load_family(path: str | Path) -> Family:
    """Read and validate a family file (or a bundled family's name).

    Raises
    ------
    ValueError
        Naming the family file's key at fault (an unknown key, a bad range, a scene the schema
        refuses), before any scene is run.
    """
    if isinstance(path, Family):
        return path
    path = Path(path)
    if not path.exists() and str(path) in bundled_families():
        path = bundled_families()[str(path)]
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError) as error:
        raise ValueError(f"family file {path}: cannot be read ({error})") from None
    except tomllib.TOMLDecodeError as error:
        raise ValueError(f"family file {path}: invalid TOML: {error}") from None
    for key in data:
        if key not in KEYS:
            raise _fail(path, key, f": unknown key; allowed keys: {', '.join(KEYS)}")
    if "scene" not in data or not isinstance(data["scene"], str):
        raise _fail(path, "scene", ": missing, or not a bundled scene's name or a file path")
    scene = data["scene"]
    local = path.parent / scene
    fixed = data.get("set", {})
    if not isinstance(fixed, dict):
        raise _fail(path, "set", f": expected a table, got {fixed!r}")
    try:
        base = load_scene(local if local.is_file() else scene, fixed)
    except SceneError as error:
        raise _fail(path, "set", f": {error}") from None
    except (OSError, ValueError) as error:
        raise _fail(path, "scene", f" = {scene!r}: {error}") from None
    hold = data.get("hold")
    if hold is not None:
        if isinstance(hold, bool) or not isinstance(hold, int | float) or not hold > 0:
            raise _fail(path, "hold", f" = {hold!r}: expected a duration > 0 (s)")
        from cable_ocp.lowering.hold import hold_scene

        base = hold_scene(base, duration=float(hold))
    ranges = data.get("ranges", {})
    family = Family(
        name=str(data.get("name", path.stem)),
        description=str(data.get("description", "")),
        base=base,
        ranges=ranges,
        hold=None if hold is None else float(hold),
        text=text,
    )
    family.draws(1, 0)  # the ranges checked before any work (a ValueError naming the key)
    return family
