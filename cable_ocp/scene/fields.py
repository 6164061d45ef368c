"""The scene's fields as rows: path, type, default, unit, allowed range and meaning.

Read from the declarations of :mod:`cable_ocp.scene.schema`, never typed twice: the site's
tables (``docs/_ext/cable_ocp_docs.py``) and ``cable-ocp schema [KEY]`` both print these rows.
"""

from __future__ import annotations

import math
from dataclasses import MISSING, fields

NUMERIC = ("float", "int", "vec3")
# The numbers of a scene that have no unit (coefficients, counts, a seed, a ratio), by field path.
# A number declared without a unit that is not listed here is reported as missing one (the site's
# build then fails, and tests/test_site.py): give it its unit in schema.py, or list it here.
DIMENSIONLESS = frozenset({
    "hydrodynamics.drag_normal", "hydrodynamics.drag_axial", "hydrodynamics.added_mass_normal",
    "hydrodynamics.added_mass_axial", "hydrodynamics.quadrature_points", "model.elements",
    "winch.knots", "numerics.output_every", "end.payload.drag", "end.payload.added_mass",
    "top.heave.sea_state.peak_enhancement", "top.heave.sea_state.components",
    "top.heave.sea_state.seed", "cable.fill_factor", "cable.axial_damping",
})  # fmt: skip


def schema_sections() -> list[tuple[str, type]]:
    """``[(path, dataclass)]`` of every scene section, depth first from :class:`Scene`.

    An array of tables has ``[]`` after its path (``"seabed.hills[]"``).
    """
    from cable_ocp.scene.schema import Scene

    found, todo = [], [("", Scene)]
    while todo:
        path, cls = todo.pop(0)
        found.append((path, cls))
        for f in fields(cls):
            spec = f.metadata.get("spec")
            if spec is not None and spec.kind in ("section", "tuple") and spec.item is not None:
                child = f"{path}.{f.name}" if path else f.name
                todo.append((child + ("[]" if spec.kind == "tuple" else ""), spec.item))
    return found


def _default(f) -> str:
    if f.default is not MISSING:
        value = f.default
    elif f.default_factory is not MISSING:
        return "(table)"
    else:
        return "required"
    if value is None:
        return "None"
    if isinstance(value, float) and math.isfinite(value):
        return f"{value:g}"
    return repr(value) if isinstance(value, str) else str(value)


def _allowed(spec) -> str:
    if spec.kind == "choice":
        allowed = " | ".join(repr(c) for c in spec.choices)
    elif spec.kind in NUMERIC:
        allowed = spec.rule().replace(f" ({spec.unit})", "") or "any finite"
    elif spec.kind == "bool":
        allowed = "true | false"
    elif spec.kind == "section":
        allowed = "table"
    elif spec.kind == "tuple":
        allowed = "array of tables"
    else:
        allowed = "text" if spec.kind == "str" else "file path"
    return allowed + (" (optional)" if spec.optional else "")


def field_rows(cls, path: str = "") -> list[dict[str, str]]:
    """One row per declared field of the scene dataclass ``cls`` at ``path``.

    Each row has the field's ``field`` (name), ``path`` (dotted, as ``--set`` takes it),
    ``kind``, ``default``, ``unit``, ``range`` and ``meaning``; ``missing`` names what the
    declaration lacks (a number without a unit, not listed in :data:`DIMENSIONLESS`; a meaning),
    empty when nothing.
    """
    rows = []
    for f in fields(cls):
        spec = f.metadata.get("spec")
        if spec is None:
            continue
        dotted = f"{path.replace('[]', '')}.{f.name}".lstrip(".")
        missing = ""
        if spec.kind not in NUMERIC:
            unit = "—"
        elif spec.unit:
            unit = spec.unit
        else:
            unit = "1"
            missing = "" if dotted in DIMENSIONLESS else "a unit"
        if not spec.doc:
            missing = " and ".join(filter(None, [missing, "a meaning"]))
        kind = spec.item.__name__ if spec.item is not None else spec.kind
        rows.append({"field": f.name, "path": dotted, "kind": kind, "default": _default(f),
                     "unit": unit, "range": _allowed(spec), "meaning": spec.doc,
                     "missing": missing})  # fmt: skip
    return rows


def all_rows() -> list[dict[str, str]]:
    """The rows of every section, in :func:`schema_sections` order."""
    return [row for path, cls in schema_sections() for row in field_rows(cls, path)]


def rows_under(key: str) -> list[dict[str, str]]:
    """The rows whose dotted path is ``key`` or lies under it (``"cable"``, ``"cable.diameter"``).

    Raises
    ------
    ValueError
        Naming the key and the top-level sections, when no field matches.
    """
    key = key.strip().strip(".")
    rows = [r for r in all_rows() if r["path"] == key or r["path"].startswith(key + ".")]
    if not rows:
        sections = sorted({r["path"].split(".")[0] for r in all_rows()})
        raise ValueError(
            f"schema key {key!r} names no scene field; give a section or a field under one of: "
            + ", ".join(sections)
        )
    return rows
