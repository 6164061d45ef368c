"""Scene files: TOML loaded into frozen, validated dataclasses.

This is the only module that reads scene files. Every field is declared once, with its default,
type, allowed range, unit and meaning (``_param``); one generic checker enforces those declarations
in each dataclass's ``__post_init__``, so direct construction and :func:`dataclasses.replace` are
validated exactly like a loaded file. Every error is a :class:`SceneError` (a ``ValueError``)
whose message starts with the full field path, e.g. ``cable.length = -3.0 is out of range: must
be > 0 (m)``.
"""

from __future__ import annotations

import copy
import errno
import math
import os
import stat
from collections.abc import Callable, Collection, Mapping, Set
from dataclasses import MISSING, dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from cable_ocp.scene.bathymetry import GridError, read_grid
from cable_ocp.scene.bundled import closest_names, scene_names, scene_path
from cable_ocp.scene.hanging import check_hanging
from cable_ocp.scene.line_mesh import FEWEST_ELEMENTS, LineMesh
from cable_ocp.scene.rules import EXPECTED, Fault, FieldRule, SceneError

__all__ = [
    "Cable",
    "CurrentRow",
    "EndLoad",
    "EndPayload",
    "Environment",
    "Hill",
    "Hydrodynamics",
    "Lowering",
    "ModelOptions",
    "Numerics",
    "Heave",
    "RaoRow",
    "Scene",
    "SceneError",
    "SeaState",
    "Seabed",
    "SeabedGrid",
    "TableProfile",
    "TopMotion",
    "TowProfile",
    "Winch",
    "load_scene",
    "scene_from_dict",
]

Vector3 = tuple[float, float, float]

MAX_STEPS = 10**8  # RK4 steps of a simulation: numerics.duration / numerics.step
MAX_LINE_ELEMENTS = 1000  # elements of a line on the drum at its longest (as model.elements)
# Rows of environment.current_profile: every row adds the same instructions to the drag at each
# Gauss point (about 390 at n = 15, against 19 000 for the whole right-hand side with 3 rows), so
# 100 rows double the model's size, compile time and cost per step; thin a longer profile.
MAX_CURRENT_ROWS = 100
# The fastest currents at sea, the tidal streams of straits such as Saltstraumen, run at about
# 10 m/s; the statics still find the hanging line there (paper_hill: measured), not at 50 m/s.
CURRENT_LIMIT = 10.0  # m/s, each component
CURRENT_REASON = "currents at sea stay under 10 m/s, the fastest tidal streams"
REQUIRED_TABLES = ("model", "top", "numerics")  # tables every scene file must have


def whole_steps(duration: float, step: float) -> int | None:
    """The number of steps of ``step`` (s) in ``duration`` (s), or None if not whole (to 1e-9)."""
    ratio = duration / step
    if not math.isfinite(ratio):
        return None
    count = round(ratio)
    if count < 1 or abs(count * step - duration) > 1e-9 * max(duration, 1.0):
        return None
    return count


def _param(default: Any = MISSING, kind: str = "float", doc: str = "", **spec: Any) -> Any:
    """Declare a scene field: default, kind, meaning and constraints (see ``FieldRule``)."""
    meta = {"spec": FieldRule(kind, doc, **spec)}
    if kind == "section" and not spec.get("optional"):
        return field(default_factory=spec["item"], metadata=meta)
    return field(default=default, metadata=meta)


def _short(value: Any) -> str:
    """``repr(value)``, shortened in the middle if long (a 400-digit integer, a long string)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:20]}...{text[-8:]} ({len(text)} characters)"


def _describe(value: Any) -> str:
    return f"{type(value).__name__} {_short(value)}"


def _number(value: Any, path: str, spec: FieldRule) -> float | int:
    """Check one number (of an ``int``, ``float`` or ``vec3`` field) against ``spec``."""
    integer = spec.kind == "int"
    fault = Fault("missing", "set") if value is None else spec.fault(value)
    if fault is None:
        return int(value) if integer else float(value)
    if fault.what in ("type", "missing"):
        raise SceneError(path, f": expected {EXPECTED[spec.kind]}, got {_describe(value)}")
    if fault.what == "finite":
        raise SceneError(path, f" = {_short(value)} is out of range: must be finite")
    value = int(value) if integer else float(value)
    why = f": {spec.why}" if spec.why else ""
    raise SceneError(path, f" = {_short(value)} is out of range: must be {spec.rule()}{why}")


def _check(spec: FieldRule, value: Any, path: str) -> Any:
    """Validate and normalise one field value (the single checker used by every dataclass)."""
    if value is None and spec.optional:
        return None
    kind = spec.kind
    if kind in ("float", "int"):
        return _number(value, path, spec)
    fault = spec.fault(value) if kind in ("bool", "str", "choice") else None
    if fault is not None and fault.what == "choice":
        allowed = ", ".join(repr(c) for c in spec.choices)
        raise SceneError(path, f" = {_short(value)} is not allowed: must be one of {allowed}")
    if fault is not None:
        raise SceneError(path, f": expected {fault.expected}, got {_describe(value)}")
    if kind == "path":
        if not isinstance(value, str | os.PathLike) or "\0" in str(value):
            raise SceneError(path, f": expected a file path string, got {_describe(value)}")
        value = _existing_file(path, value)
    if kind in ("vec3", "tuple"):
        if isinstance(value, str | bytes | Mapping | Set) or not isinstance(value, Collection):
            expected = "3 numbers" if kind == "vec3" else "a list"
            raise SceneError(path, f": expected {expected}, got {_describe(value)}")
        if kind == "vec3" and len(value) != 3:
            raise SceneError(
                path, f": expected 3 numbers, got {type(value).__name__} of length {len(value)}"
            )
        if kind == "vec3":
            return tuple(_number(v, f"{path}[{k}]", spec) for k, v in enumerate(value))
        for k, v in enumerate(value):
            if not isinstance(v, spec.item):
                expected = f"a {spec.item.__name__}"
                raise SceneError(f"{path}[{k}]", f": expected {expected}, got {_describe(v)}")
        return tuple(value)
    if kind == "section" and not isinstance(value, spec.item):
        raise SceneError(path, f": expected a {spec.item.__name__}, got {_describe(value)}")
    return value


def _existing_file(path: str, value: str | os.PathLike) -> str:
    """The absolute path of a regular file, or one SceneError saying what ``value`` is instead.

    The error shows the whole path (never shortened: it is what the user must find).
    """
    try:
        resolved = Path(value).resolve()
        kind = resolved.stat().st_mode
    except RuntimeError:  # Python < 3.13 raises it for a loop of symbolic links
        raise SceneError(path, f" = {str(value)!r}: a loop of symbolic links") from None
    except OSError as error:
        if error.errno == errno.ELOOP:
            raise SceneError(path, f" = {str(value)!r}: a loop of symbolic links") from None
        if isinstance(error, FileNotFoundError):
            raise SceneError(path, f" = {str(resolved)!r}: file not found") from None
        raise SceneError(path, f" = {str(value)!r}: cannot be read ({error.strerror})") from None
    if stat.S_ISDIR(kind):
        raise SceneError(path, f" = {str(resolved)!r}: is a folder, not a file")
    if not stat.S_ISREG(kind):
        raise SceneError(
            path, f" = {str(resolved)!r}: not a regular file (a pipe, socket or device)"
        )
    return str(resolved)


class _Validated:
    """Base of the scene dataclasses: generic validation, ``to_dict`` and error helpers."""

    _section: ClassVar[str] = ""

    def __post_init__(self) -> None:
        for f in fields(self):
            if "spec" in f.metadata:
                value = _check(f.metadata["spec"], getattr(self, f.name), self._path(f.name))
                object.__setattr__(self, f.name, value)
        self._check_relations()

    def _check_relations(self) -> None:
        """Check constraints between fields (overridden where there are any)."""

    def _path(self, name: str) -> str:
        return f"{self._section}.{name}" if self._section else name

    def _fail(self, name: str, rule: str) -> SceneError:
        unit = next(f.metadata["spec"].unit for f in fields(self) if f.name == name)
        unit = f" ({unit})" if unit else ""
        detail = f" = {getattr(self, name)!r} is out of range: must be {rule}{unit}"
        return SceneError(self._path(name), detail)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (lists for vectors, optional fields left out when None)."""
        return {
            f.name: _plain(getattr(self, f.name))
            for f in fields(self)
            if "spec" in f.metadata and getattr(self, f.name) is not None
        }


def _plain(value: Any) -> Any:
    if isinstance(value, _Validated):
        return value.to_dict()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def _section(path: str) -> Callable[[type], type]:
    """Set a dataclass's section path and append its field reference to its docstring."""

    def wrap(cls: type) -> type:
        cls._section = path
        lines = ["", "    Attributes", "    ----------"]
        for f in fields(cls):
            if "spec" in f.metadata:
                s = f.metadata["spec"]
                rule = s.rule() if s.kind in ("float", "int", "vec3") else s.unit
                kind = f"{s.item.__name__}" if s.item else s.kind
                optional = ", optional" if s.optional else ""
                lines += [f"    {f.name} : {kind}{optional}", f"        {s.doc} {rule}".rstrip()]
        cls.__doc__ = (cls.__doc__ or "").rstrip() + "\n" + "\n".join(lines) + "\n"
        return cls

    return wrap


@_section("cable")
@dataclass(frozen=True)
class Cable(_Validated):
    """The cable's geometry and material."""

    length: float = _param(300.0, doc="Length L.", gt=0, unit="m")
    diameter: float = _param(0.07, doc="Diameter d.", gt=0, unit="m")
    density: float = _param(6500.0, doc="Density rho.", gt=0, unit="kg/m^3")
    youngs_modulus: float = _param(1e11, doc="Young's modulus E.", gt=0, unit="Pa")
    shear_modulus: float = _param(8e10, doc="Shear modulus G.", gt=0, unit="Pa")
    area: float | None = _param(
        None, doc="Cross-section area A; None means pi d^2/4.", gt=0, unit="m^2", optional=True
    )
    bending_damping: float = _param(
        0.0, doc="Rayleigh time constant: damping = bending_damping x stiffness.", ge=0, unit="s"
    )
    torsion_damping: float = _param(0.0, doc="Rayleigh time constant for torsion.", ge=0, unit="s")
    axial_stiffness: float | None = _param(
        None, doc="Axial stiffness EA; None means youngs_modulus x area x fill_factor.", gt=0,
        unit="N", optional=True,
    )  # fmt: skip
    fill_factor: float = _param(
        1.0, doc="Metallic-area fraction of a wire rope: EA = E A f (1: a solid section).",
        ge=0.1, le=1.0, why="the metal fills a fraction of the rope's circle: about 0.5 to 0.8 "
        "in a wire rope, 1 in a solid bar",
    )  # fmt: skip
    axial_damping: float = _param(
        0.02, doc="Axial structural damping, as a ratio of critical of the line's first axial "
        "mode.", ge=0, le=1,
    )  # fmt: skip

    def _check_relations(self) -> None:
        if self.axial_stiffness is not None and self.fill_factor != 1.0:
            raise SceneError(
                self._path("fill_factor"),
                f" = {self.fill_factor!r} beside cable.axial_stiffness = "
                f"{self.axial_stiffness!r} N: give one of the two (axial_stiffness is EA itself; "
                "fill_factor scales youngs_modulus x area when EA is left out)",
            )
        derived = ("cross_section_area", "mass_per_length", "bending_stiffness")
        for name in (*derived, "torsional_stiffness", "axial_stiffness_value"):
            try:
                finite = math.isfinite(getattr(self, name))
            except OverflowError:
                finite = False
            if not finite:
                raise SceneError(
                    "cable",
                    f": {name} overflows (diameter = {self.diameter!r} m, density = "
                    f"{self.density!r} kg/m^3, youngs_modulus = {self.youngs_modulus!r} Pa, "
                    f"shear_modulus = {self.shear_modulus!r} Pa): use physical values",
                )

    @property
    def cross_section_area(self) -> float:
        """Cross-section area A, m^2 (``area`` if given, else pi d^2/4)."""
        return self.area if self.area is not None else math.pi * self.diameter**2 / 4

    @property
    def mass_per_length(self) -> float:
        """Mass per unit length mu = rho A, kg/m."""
        return self.density * self.cross_section_area

    @property
    def bending_stiffness(self) -> float:
        """Bending stiffness EI = E pi d^4/64, N m^2."""
        return self.youngs_modulus * math.pi * self.diameter**4 / 64

    @property
    def torsional_stiffness(self) -> float:
        """Torsional stiffness G I_p = G pi d^4/32, N m^2."""
        return self.shear_modulus * math.pi * self.diameter**4 / 32

    @property
    def axial_stiffness_value(self) -> float:
        """Effective axial stiffness EA, N (``axial_stiffness`` if given, else E A f)."""
        if self.axial_stiffness is not None:
            return self.axial_stiffness
        return self.youngs_modulus * self.cross_section_area * self.fill_factor


@_section("environment.current_profile")
@dataclass(frozen=True)
class CurrentRow(_Validated):
    """One row of the current profile: the horizontal current at a height z.

    Between rows the current is linear in z; above the first row and below the last it keeps
    that row's value (``cable_ocp/model/current.py``).
    """

    z: float = _param(doc="Height of the row (the sea surface is 0).", le=0, unit="m")
    u: float = _param(
        0.0, doc="Current along x.", ge=-CURRENT_LIMIT, le=CURRENT_LIMIT, unit="m/s",
        why=CURRENT_REASON,
    )  # fmt: skip
    v: float = _param(
        0.0, doc="Current along y.", ge=-CURRENT_LIMIT, le=CURRENT_LIMIT, unit="m/s",
        why=CURRENT_REASON,
    )  # fmt: skip


@_section("environment")
@dataclass(frozen=True)
class Environment(_Validated):
    """Gravity and the surrounding fluid."""

    gravity: float = _param(9.81, doc="Gravitational acceleration g.", gt=0, unit="m/s^2")
    submerged: bool = _param(True, "bool", "Cable in water (true) or in air (false).")
    water_density: float = _param(
        1025.0, doc="Water density rho_w (> 0 when submerged).", ge=0, unit="kg/m^3"
    )
    current: Vector3 = _param(
        (0.0, 0.0, 0.0), "vec3", "Uniform current velocity.", ge=-CURRENT_LIMIT,
        le=CURRENT_LIMIT, unit="m/s", why=CURRENT_REASON,
    )  # fmt: skip
    current_profile: tuple[CurrentRow, ...] = _param(
        (), "tuple", f"Current by depth, rows from the surface down (none: uniform; at most "
        f"{MAX_CURRENT_ROWS} rows).", item=CurrentRow,
    )  # fmt: skip

    @property
    def fluid_density(self) -> float:
        """Density of the fluid around the rope (kg/m^3): ``water_density`` submerged, 0 in air."""
        return self.water_density if self.submerged else 0.0

    def _check_relations(self) -> None:
        if self.submerged and self.water_density <= 0:
            raise self._fail("water_density", "> 0 when environment.submerged is true")
        rows = self.current_profile
        if len(rows) > MAX_CURRENT_ROWS:
            raise SceneError(
                self._path("current_profile"),
                f": {len(rows)} rows; at most {MAX_CURRENT_ROWS}: each row adds to the drag at "
                f"every Gauss point, so the model's size, compile time and cost per step grow "
                f"with the rows ({MAX_CURRENT_ROWS} rows double them). Thin the profile (e.g. "
                "keep the rows where the current's slope in depth changes)",
            )
        for k in range(1, len(rows)):
            if rows[k].z >= rows[k - 1].z:
                raise SceneError(
                    f"{self._path('current_profile')}[{k}].z",
                    f" = {rows[k].z!r} is out of range: must be < {self._path('current_profile')}"
                    f"[{k - 1}].z = {rows[k - 1].z!r} (m; rows from the surface down)",
                )
        if rows and any(self.current):
            raise SceneError(
                self._path("current"),
                f" = {list(self.current)!r}: give a uniform current or "
                "environment.current_profile, not both",
            )


@_section("hydrodynamics")
@dataclass(frozen=True)
class Hydrodynamics(_Validated):
    """Morison drag and added mass (ignored when the cable is in air)."""

    drag: bool = _param(True, "bool", "Morison drag on.")
    drag_normal: float = _param(1.0, doc="Normal drag coefficient C_dn.", ge=0)
    drag_axial: float = _param(0.1, doc="Axial drag coefficient C_dt.", ge=0)
    added_mass: bool = _param(True, "bool", "Added mass on.")
    added_mass_normal: float = _param(1.0, doc="Normal added-mass C_a = C_M - 1.", ge=0)
    added_mass_axial: float = _param(0.0, doc="Axial added-mass coefficient.", ge=0)
    quadrature_points: int = _param(3, "int", "Gauss points per element for drag.", ge=1, le=8)


@_section("model")
@dataclass(frozen=True)
class ModelOptions(_Validated):
    """Discretisation and which internal forces the model carries."""

    elements: int = _param(15, "int", "n; the model has n+1 rigid elements.", ge=1, le=1000)
    torsion: bool = _param(False, "bool", "6-DOF elements with torsion springs.")
    bending: bool = _param(True, "bool", "Bending springs on.")
    axial: str = _param(
        "auto", "choice", "Axial compliance of the rope: rigid elements, elastic, or chosen from "
        "the scene (auto: elastic where the line's first axial period reaches its excitation).",
        choices=("rigid", "elastic", "auto"),
    )  # fmt: skip


@_section("top.tow")
@dataclass(frozen=True)
class TowProfile(_Validated):
    """The tow of ``top.motion = "tow"``: v_x = U S(t/T_r), v_y = W sin^2(pi t/T).

    CONVENTIONS.md §6.
    The defaults are the reconstruction of the paper's vessel motion.
    """

    surge_speed: float = _param(1.16, doc="Final surge speed U.", unit="m/s")
    sway_speed: float = _param(0.40, doc="Sway speed amplitude W.", unit="m/s")
    ramp_time: float = _param(30.0, doc="Surge ramp time T_r.", gt=0, unit="s")
    sway_period: float = _param(210.0, doc="Sway period T.", gt=0, unit="s")


@_section("top.table")
@dataclass(frozen=True)
class TableProfile(_Validated):
    """The table of ``top.motion = "table"``: top positions at given times, splined."""

    file: str = _param(kind="path", doc="CSV with columns t, x, y, z (s, m); absolute path.")


@_section("top.heave.sea_state.rao")
@dataclass(frozen=True)
class RaoRow(_Validated):
    """One row of the vessel's RAO table: its response per metre of wave amplitude at a frequency.

    A response is ``gain a cos(w t + phi + phase)`` for a wave component ``a cos(w t + phi)``;
    between rows the gains and phases are linear in w, beyond the table's ends they are held.
    """

    frequency: float = _param(doc="Angular frequency w.", gt=0, unit="rad/s")
    heave: float = _param(1.0, doc="Heave gain.", ge=0, unit="m/m")
    heave_phase: float = _param(0.0, doc="Heave phase lead.", unit="rad")
    roll: float = _param(0.0, doc="Roll gain (about x).", ge=0, unit="rad/m")
    roll_phase: float = _param(0.0, doc="Roll phase lead.", unit="rad")
    pitch: float = _param(0.0, doc="Pitch gain (about y).", ge=0, unit="rad/m")
    pitch_phase: float = _param(0.0, doc="Pitch phase lead.", unit="rad")


@_section("top.heave.sea_state")
@dataclass(frozen=True)
class SeaState(_Validated):
    """A JONSWAP sea state that moves the winch (``cable_ocp/drive/sea_state.py``).

    Random-phase components of the spectrum, reproducible by ``seed``; the vessel heaves with
    the sea surface, or responds through the ``rao`` table (heave, roll, pitch), and the winch at
    ``winch_offset`` from the centre of roll and pitch follows (small angles, the vessel's heading
    along x).
    """

    significant_height: float = _param(
        doc="Significant wave height H_s.", gt=0, le=30, unit="m",
        why="the highest seas measured have a significant height of about 20 m",
    )  # fmt: skip
    peak_period: float = _param(
        doc="Spectral peak period T_p.", ge=1, le=30, unit="s",
        why="waves at sea peak between about 1 s (ripples of a light wind) and 25 s (the "
        "longest ocean swell)",
    )  # fmt: skip
    peak_enhancement: float = _param(3.3, doc="JONSWAP peak enhancement gamma.", ge=1)
    components: int = _param(100, "int", "Number of wave components.", ge=1, le=10000)
    seed: int = _param(0, "int", "Seed of the components' frequencies and phases.", ge=0)
    winch_offset: Vector3 = _param(
        (0.0, 0.0, 0.0), "vec3", "Winch from the centre of roll and pitch.", unit="m"
    )
    rao: tuple[RaoRow, ...] = _param(
        (), "tuple", "RAO rows by increasing frequency (none: heave with the surface).",
        item=RaoRow,
    )  # fmt: skip

    def _check_relations(self) -> None:
        for k in range(1, len(self.rao)):
            if self.rao[k].frequency <= self.rao[k - 1].frequency:
                raise SceneError(
                    f"{self._path('rao')}[{k}].frequency",
                    f" = {self.rao[k].frequency!r} is out of range: must be > "
                    f"{self._path('rao')}[{k - 1}].frequency = {self.rao[k - 1].frequency!r} "
                    "(rad/s; rows by increasing frequency)",
                )


@_section("top.heave")
@dataclass(frozen=True)
class Heave(_Validated):
    """The vessel's heave at the winch: a sine, a sea state, or both (the section switches it on).

    ``compensation`` applies to the winch's whole vertical motion, whatever its source.
    """

    amplitude: float | None = _param(
        None, doc="Amplitude of a sinusoidal heave (needed without a sea state).", ge=0, unit="m",
        optional=True,
    )  # fmt: skip
    period: float = _param(10.0, doc="Period of the sinusoidal heave.", gt=0, unit="s")
    compensation: bool = _param(False, "bool", "Heave compensated at the top by the winch.")
    sea_state: SeaState | None = _param(
        None, "section", "[top.heave.sea_state]", item=SeaState, optional=True
    )

    def _check_relations(self) -> None:
        if self.amplitude is None and self.sea_state is None:
            raise SceneError(
                self._path("amplitude"),
                ": missing required key (or give a sea state, [top.heave.sea_state])",
            )


@_section("top")
@dataclass(frozen=True)
class TopMotion(_Validated):
    """Prescribed motion of the top point A_{n+1}, carried by the vessel (CONVENTIONS.md §6).

    The profile's own numbers are in the sub-table of its name (``[top.tow]``, ``[top.table]``),
    which only that profile may have; ``[top.tow]`` may be left out for the paper's tow. A
    ``[top.heave]`` table adds heave to any profile: a sine, a sea state or both.
    """

    motion: str = _param("fixed", "choice", "Profile.", choices=("fixed", "tow", "table"))
    start: Vector3 = _param((0.0, 0.0, 0.0), "vec3", "Position at t = 0.", unit="m")
    tow: TowProfile | None = _param(None, "section", "[top.tow]", item=TowProfile, optional=True)
    table: TableProfile | None = _param(
        None, "section", "[top.table]", item=TableProfile, optional=True
    )
    heave: Heave | None = _param(None, "section", "[top.heave]", item=Heave, optional=True)

    @property
    def heave_compensated(self) -> bool:
        """Whether the winch compensates a heave of the top."""
        return self.heave is not None and self.heave.compensation

    @property
    def has_heave(self) -> bool:
        """Whether the vessel heaves: a sine of non-zero amplitude or a sea state."""
        heave = self.heave
        return heave is not None and (bool(heave.amplitude) or heave.sea_state is not None)

    @property
    def tow_profile(self) -> TowProfile:
        """The tow's numbers: ``[top.tow]``, or the paper's tow where that table is left out."""
        return self.tow if self.tow is not None else TowProfile()

    def _check_relations(self) -> None:
        if self.motion == "table" and self.table is None:
            raise SceneError(self._path("table"), ": required when top.motion = 'table'")
        for profile in ("tow", "table"):
            if profile != self.motion and getattr(self, profile) is not None:
                raise SceneError(
                    self._path(profile),
                    f": given, but top.motion = {self.motion!r} does not use it: remove "
                    f"[top.{profile}] or set top.motion = {profile!r}",
                )


@_section("end.payload")
@dataclass(frozen=True)
class EndPayload(_Validated):
    """A point mass at the free end E = A_0 with buoyancy, drag and added mass.

    The table is the switch: without ``[end.payload]`` there is no payload. A buoyant payload
    (``volume`` of water heavier than ``mass``) is held to the rules of
    :mod:`cable_ocp.scene.hanging`: on a rope denser than water its end must hang below the
    surface, with a sideways pull.
    """

    mass: float = _param(doc="Payload mass.", ge=0, unit="kg")
    volume: float = _param(0.0, doc="Payload volume (buoyancy).", ge=0, unit="m^3")
    drag_area: float = _param(0.0, doc="Payload drag area.", ge=0, unit="m^2")
    drag: float = _param(1.0, doc="Payload drag coefficient.", ge=0)
    added_mass: float = _param(1.0, doc="Payload added-mass coefficient.", ge=0)

    def weight_in(self, environment: Environment) -> float:
        """Its weight less its buoyancy in ``environment`` (N; negative: it floats)."""
        return (self.mass - environment.fluid_density * self.volume) * environment.gravity

    def inertia_in(self, environment: Environment) -> float:
        """Its mass with the fluid it drags along in ``environment``, ``M + C_a rho_w V`` (kg)."""
        return self.mass + self.added_mass * environment.fluid_density * self.volume


@_section("end")
@dataclass(frozen=True)
class EndLoad(_Validated):
    """Loads at the free end E = A_0: constant and time-varying force, optional payload.

    The time-varying force's component k is ``force_amplitude[k] * S((t - force_start) /
    force_ramp) * (sin(2 pi (t - force_start) / force_period[k]) if force_period[k] > 0 else 1)``.
    """

    force: Vector3 = _param((0.0, 0.0, 0.0), "vec3", "Constant force.", unit="N")
    force_amplitude: Vector3 = _param((0.0, 0.0, 0.0), "vec3", "Varying force.", unit="N")
    force_period: Vector3 = _param((0.0, 0.0, 0.0), "vec3", "0 = no oscillation.", ge=0, unit="s")
    force_start: float = _param(0.0, doc="Start of the varying force.", ge=0, unit="s")
    force_ramp: float = _param(0.0, doc="Smoothstep ramp time (0 = step).", ge=0, unit="s")
    payload: EndPayload | None = _param(
        None, "section", "[end.payload]", item=EndPayload, optional=True
    )


@_section("winch.line")
@dataclass(frozen=True)
class WinchLine(_Validated):
    """The line on the drum, in metres: a line paid out and hauled in by elements (paper §2).

    The table is the switch: with ``[winch.line]`` the line out at the start is
    ``cable.length``, the drum's angle range follows from ``winch.drum_radius``
    (``winch.angle_min = -haul_in_max / r_D``, ``winch.angle_max = pay_out_max / r_D``), and
    the model splits off or merges back an element at the top as the line goes out or in
    (CONVENTIONS.md §3, the line on the drum).
    """

    pay_out_max: float = _param(0.0, doc="Line the drum can pay out.", ge=0, unit="m")
    haul_in_max: float = _param(0.0, doc="Line the drum can haul in.", ge=0, unit="m")
    element_length: float = _param(10.0, doc="Delta, every element below the top.", gt=0, unit="m")
    top_length_min: float | None = _param(
        None, doc="Shortest top element (none: Delta / 2); the longest is 3/2 Delta more.",
        gt=0, unit="m", optional=True,
    )  # fmt: skip

    @property
    def mesh(self):
        """The :class:`~cable_ocp.scene.line_mesh.LineMesh` of the line's element lengths."""
        shortest = self.top_length_min
        half = self.element_length / 2
        return LineMesh(self.element_length, half if shortest is None else shortest)


@_section("winch")
@dataclass(frozen=True)
class Winch(_Validated):
    """Winch: drum, angle bounds, spline knots, top-element length bounds."""

    drum_radius: float = _param(0.5, doc="Drum radius r_D.", gt=0, unit="m")
    angle_min: float = _param(-16.0, doc="Lower bound of phi (haul-in).", le=0, unit="rad")
    angle_max: float = _param(24.0, doc="Upper bound of phi (pay-out).", ge=0, unit="rad")
    rate_max: float | None = _param(None, doc="Bound on |phi'|.", gt=0, unit="rad/s", optional=True)
    acceleration_max: float | None = _param(
        None, doc="Bound on |phi''|.", gt=0, unit="rad/s^2", optional=True
    )
    knots: int = _param(14, "int", "Cubic-spline subintervals p.", ge=1, le=200)
    top_length_min: float = _param(2.0, doc="Shortest top element.", gt=0, unit="m")
    top_length_max: float | None = _param(
        None, doc="Longest top element (none: winch.angle_max alone).", gt=0, unit="m",
        optional=True,
    )  # fmt: skip
    line: WinchLine | None = _param(None, "section", "[winch.line]", item=WinchLine, optional=True)

    def _check_relations(self) -> None:
        if self.line is not None:
            self._angles_from_line()
        elif self.angle_min >= self.angle_max:
            raise self._fail("angle_min", "< winch.angle_max")
        if self.top_length_max is not None and self.top_length_max <= self.top_length_min:
            raise self._fail("top_length_max", "> winch.top_length_min")

    def _angles_from_line(self) -> None:
        """Set the angle range from ``[winch.line]``; refuse another one given beside it."""
        derived = {
            "angle_min": 0.0 - self.line.haul_in_max / self.drum_radius,
            "angle_max": self.line.pay_out_max / self.drum_radius,
        }
        for name, value in derived.items():
            given = getattr(self, name)
            default = type(self).__dataclass_fields__[name].default
            if given not in (default, value):
                raise self._fail(
                    name,
                    f"{value!r}, set by [winch.line] (its metres over winch.drum_radius; leave "
                    "it out)",
                )
            object.__setattr__(self, name, value)


@_section("hill")
@dataclass(frozen=True)
class Hill(_Validated):
    """Gaussian hill z = height exp(-((x-x0)/width_x)^2 - ((y-y0)/width_y)^2) (eq. 40)."""

    height: float = _param(kind="float", doc="Height k.", unit="m")
    x0: float = _param(kind="float", doc="Centre x.", unit="m")
    y0: float = _param(kind="float", doc="Centre y.", unit="m")
    width_x: float = _param(kind="float", doc="Width p along x.", gt=0, unit="m")
    width_y: float = _param(kind="float", doc="Width q along y.", gt=0, unit="m")


@_section("seabed.grid")
@dataclass(frozen=True)
class SeabedGrid(_Validated):
    """A bathymetry grid: the seabed's absolute elevation (CONVENTIONS.md §5, §6).

    netCDF (``.nc``: ``variable`` over coordinates ``x``, ``y``) or CSV (``.csv``: columns x, y, z),
    in the scene's frame (z up, the sea surface at 0); read and checked when the scene is loaded
    (:mod:`cable_ocp.scene.bathymetry`).
    """

    file: str = _param(kind="path", doc="Grid file (.nc or .csv), relative to the scene file.")
    variable: str = _param("elevation", "str", "Elevation variable of a netCDF file.")

    def _check_relations(self) -> None:
        try:
            read_grid(self.file, self.variable)
        except GridError as error:
            raise SceneError(self._path("file"), f": {error}") from None


@_section("seabed")
@dataclass(frozen=True)
class Seabed(_Validated):
    """Seabed: hills (none = flat), an optional bathymetry grid, the clearance delta (eq. 39).

    Without a grid the seabed is relative (the paper's): its flat level lies delta below the end's
    start, the hills rise from it, and delta cancels from e(t) = z_E(t) - z_hill(x_E, y_E) -
    (z_E(0) - z_hill(x_E(0), y_E(0))). With a grid it is absolute (elevation of the grid plus the
    hills, z up from the sea surface) and delta is the target: e(t) = z_E - z_sb(x_E, y_E) -
    delta, from the hanging start on (CONVENTIONS.md §5). Either way the clearance z_E - z_sb is
    delta + e(t).
    """

    clearance: float = _param(
        5.0, doc="Clearance delta: the end's start (no grid) or target (grid) (eq. 39).", ge=0,
        unit="m",
    )  # fmt: skip
    hills: tuple[Hill, ...] = _param((), "tuple", "Hills, summed.", item=Hill)
    grid: SeabedGrid | None = _param(
        None, "section", "[seabed.grid]", item=SeabedGrid, optional=True
    )
    minimum_clearance: float | None = _param(
        None, doc="Hard minimum c_min of z_E - z_sb (<= clearance).", ge=0, unit="m",
        optional=True,
    )  # fmt: skip

    def _check_relations(self) -> None:
        if self.minimum_clearance is not None and self.minimum_clearance > self.clearance:
            raise self._fail("minimum_clearance", f"<= seabed.clearance = {self.clearance!r}")

    @property
    def absolute(self) -> bool:
        """Whether the seabed is absolute (a grid), so that delta is a target, not the start."""
        return self.grid is not None


@_section("numerics")
@dataclass(frozen=True)
class Numerics(_Validated):
    """Simulation horizon, RK4 step, Baumgarte gains and output."""

    duration: float = _param(100.0, doc="Horizon T.", gt=0, unit="s")
    step: float = _param(0.01, doc="RK4 step h (<= duration).", gt=0, unit="s")
    baumgarte_alpha: float = _param(
        1.0, doc="Baumgarte alpha (damping of bond drift).", ge=0, unit="1/s"
    )
    baumgarte_beta: float = _param(
        1.0, doc="Baumgarte beta (stiffness of bond drift).", ge=0, unit="1/s"
    )
    constraint_tolerance: float = _param(1e-6, doc="Largest bond residual.", gt=0, unit="m")
    output_every: int = _param(1, "int", "Keep every k-th RK4 step.", ge=1)

    def _check_relations(self) -> None:
        if self.step > self.duration:
            raise self._fail("step", f"<= numerics.duration = {self.duration!r}")
        if self.duration / self.step > MAX_STEPS:
            raise SceneError(
                "numerics.step",
                f" = {self.step!r} is out of range: must be >= numerics.duration / {MAX_STEPS:.0e}"
                f" = {self.duration / MAX_STEPS!r} s (at most {MAX_STEPS:.0e} RK4 steps)",
            )
        if whole_steps(self.duration, self.step) is None:
            raise SceneError(
                "numerics.step",
                f" = {self.step!r} s must divide numerics.duration = {self.duration!r} s into a "
                f"whole number of RK4 steps ({self.duration / self.step:.6g} here)",
            )


@_section("lowering")
@dataclass(frozen=True)
class Lowering(_Validated):
    """A landing: the end brought to a height above the seabed at a set time, slowly, then held.

    The table is the switch. The end should be ``height`` above the seabed under it at
    ``land_time`` (within ``height_tolerance``), arrive there no faster than ``landing_speed``,
    stay within ``hold_band`` of that height until ``numerics.duration`` (the hold), and the top
    tension should stay between ``tension_min`` (no slack) and ``tension_max`` all along
    (CONVENTIONS.md §5, lowering).
    """

    land_time: float = _param(
        kind="float", doc="T_land: when the end reaches its target height (<= duration).", gt=0,
        unit="s",
    )  # fmt: skip
    height: float = _param(
        kind="float", doc="Target height of the end above the seabed under it.", ge=0, unit="m"
    )
    height_tolerance: float = _param(
        0.1, doc="Largest landing error |z_E - z_sb - height| at land_time.", gt=0, unit="m"
    )
    landing_speed: float = _param(
        0.1, doc="Largest vertical speed of the end at land_time.", gt=0, unit="m/s"
    )
    tension_min: float = _param(0.0, doc="Least top tension (no slack).", ge=0, unit="N")
    tension_max: float | None = _param(
        None, doc="Largest top tension (the rope's working limit).", gt=0, unit="N",
        optional=True,
    )  # fmt: skip
    hold_band: float = _param(
        0.1, doc="Half-width of the band about the target height held after land_time.", gt=0,
        unit="m",
    )  # fmt: skip

    def _check_relations(self) -> None:
        if self.tension_max is not None and self.tension_max <= self.tension_min:
            raise self._fail("tension_max", f"> lowering.tension_min = {self.tension_min!r}")


@_section("")
@dataclass(frozen=True)
class Scene(_Validated):
    """A complete scene: the sections of a scene file, validated together.

    ``source`` is the absolute path of the file it was loaded from (None otherwise); it is neither
    compared nor exported by `to_dict`. The scene is hashable, so it can key a cache.

    In water its line must hang from the top in still water (:mod:`cable_ocp.scene.hanging`): a
    rope lighter than water needs a load at its end that outweighs its buoyancy; a buoyant end
    (payload or ``end.force``) on a rope denser than water must hang below the sea surface, and
    needs a sideways pull (``end.force``'s horizontal part) not to fold the rope into a slack
    bight.
    """

    name: str = _param("scene", "str", "Scene name (default: the file stem).")
    description: str = _param("", "str", "Free text.")
    cable: Cable = _param(kind="section", doc="[cable]", item=Cable)
    environment: Environment = _param(kind="section", doc="[environment]", item=Environment)
    hydrodynamics: Hydrodynamics = _param(kind="section", doc="[hydrodynamics]", item=Hydrodynamics)
    model: ModelOptions = _param(kind="section", doc="[model]", item=ModelOptions)
    top: TopMotion = _param(kind="section", doc="[top]", item=TopMotion)
    end: EndLoad = _param(kind="section", doc="[end]", item=EndLoad)
    winch: Winch = _param(kind="section", doc="[winch]", item=Winch)
    seabed: Seabed = _param(kind="section", doc="[seabed]", item=Seabed)
    numerics: Numerics = _param(kind="section", doc="[numerics]", item=Numerics)
    lowering: Lowering | None = _param(None, "section", "[lowering]", item=Lowering, optional=True)
    source: str | None = field(default=None, compare=False)

    def mesh(self, elements: int | None = None) -> tuple[float, float]:
        """The graded mesh of a model of ``elements`` (default: the scene's n), m.

        The winch's reach belongs to the winch: the top element is long enough at ``phi = 0`` to
        haul in all of ``r_D |winch.angle_min|`` and still be ``winch.top_length_min`` long, at
        any n. Below it the rest of the line is cut as the paper does (CONVENTIONS.md §3).

        Returns
        -------
        segment : float, m
            ``Delta = (L - l_top) / (n - 1/2)``: elements 1..n-1 are Delta long, element 0 Delta/2.
        top : float, m
            ``l_top = max(L / 2n, winch.top_length_min - r_D winch.angle_min)``, the top element
            at ``phi = 0``; ``L / 2n`` (the uniform mesh, Delta = L / n) whenever it has the
            reach.
        """
        n = elements or self.model.elements
        w = self.winch
        top = max(self.cable.length / (2 * n), w.top_length_min - w.drum_radius * w.angle_min)
        return (self.cable.length - top) / (n - 0.5), top

    @property
    def segment_length(self) -> float:
        """Segment length Delta of the scene's mesh (L / n when uniform, see :meth:`mesh`), m."""
        return self.mesh()[0]

    @property
    def top_element_length(self) -> float:
        """Length of the top element at ``phi = 0`` (Delta/2 when uniform, see :meth:`mesh`), m."""
        return self.mesh()[1]

    def _check_relations(self) -> None:
        check_hanging(self)
        lowering, numerics = self.lowering, self.numerics
        if lowering is not None and lowering.land_time > numerics.duration:
            raise lowering._fail("land_time", f"<= numerics.duration = {numerics.duration!r}")
        if lowering is not None and whole_steps(lowering.land_time, numerics.step) is None:
            raise SceneError(
                "lowering.land_time",
                f" = {lowering.land_time!r} s is not a whole number of numerics.step = "
                f"{numerics.step!r} s: the landing is checked, and its hold begins, on a step",
            )
        if self.winch.line is not None:
            self._check_line()
            return
        w, top = self.winch, self.top_element_length
        reach = w.top_length_min - w.drum_radius * w.angle_min
        if reach >= self.cable.length / 2:
            raise w._fail(
                "angle_min",
                f"> -(cable.length / 2 - winch.top_length_min) / winch.drum_radius = "
                f"{-(self.cable.length / 2 - w.top_length_min) / w.drum_radius!r} (the top element "
                f"that hauls it all in would be {reach!r} m, over half the cable)",
            )
        if w.top_length_max is not None and w.top_length_max < top:
            raise w._fail(
                "top_length_max",
                f">= the top element's length at phi = 0, max(cable.length / model.elements / 2, "
                f"winch.top_length_min - winch.drum_radius * winch.angle_min) = {top!r}",
            )

    def _check_line(self) -> None:
        """A line on the drum (``[winch.line]``) that its elements can follow from start to end.

        Each limit blames the field that breaks it: the mesh's (``element_length``,
        ``top_length_min``) when the line out at the start cannot be meshed, the drum's
        (``haul_in_max``, ``pay_out_max``) only when the line it leaves or reaches cannot.
        """
        line, mesh, length = self.winch.line, self.winch.line.mesh, self.cable.length
        fills = (
            f"the line out at the start, cable.length = {length!r} m, must fill three elements: "
            "3/2 winch.line.element_length + the shortest top element"
        )
        if length < mesh.shortest_line:
            below = LineMesh(line.element_length, 0.0).below_top(FEWEST_ELEMENTS)
            top_min = line.top_length_min
            if top_min is not None and length >= below + line.element_length / 2:
                raise line._fail(
                    "top_length_min",
                    f"<= cable.length - 3/2 winch.line.element_length = {length - below!r} "
                    f"({fills})",
                )
            # The longest Delta with (FEWEST - 1/2) Delta + top <= L, top = Delta / 2 if unset.
            elements = FEWEST_ELEMENTS - (0.0 if top_min is None else 0.5)
            largest = (length - (top_min or 0.0)) / elements
            raise line._fail("element_length", f"<= {largest!r} ({fills})")
        least = length - line.haul_in_max
        if least < mesh.shortest_line:
            raise line._fail(
                "haul_in_max",
                f"<= cable.length - {mesh.shortest_line!r} = "
                f"{length - mesh.shortest_line!r} (the line left must fill three "
                "elements: 3/2 winch.line.element_length + the shortest top element)",
            )
        most = length + line.pay_out_max
        # The shortest Delta with floor((most - top) / Delta + 1/2) <= MAX, top = Delta / 2
        # if unset.
        top_min = line.top_length_min
        shortest = (most - (top_min or 0.0)) / (
            MAX_LINE_ELEMENTS + (1.0 if top_min is None else 0.5)
        )
        longest = f"the longest line, cable.length + winch.line.pay_out_max = {most:.6g} m"
        if mesh.starting_elements(length) > MAX_LINE_ELEMENTS:
            raise line._fail(
                "element_length",
                f"> {shortest:.6g} (at most {MAX_LINE_ELEMENTS} elements in {longest})",
            )
        if mesh.starting_elements(most) > MAX_LINE_ELEMENTS:
            # most < (MAX + 1/2) Delta + top
            largest = mesh.below_top(MAX_LINE_ELEMENTS + 1) + mesh.top_length_min - length
            raise line._fail(
                "pay_out_max",
                f"< {largest:.6g} (at most {MAX_LINE_ELEMENTS} elements of "
                f"winch.line.element_length out; or winch.line.element_length > {shortest:.6g} "
                f"for {longest})",
            )
        if self.model.torsion:
            raise SceneError(
                "model.torsion", " = true: a line on the drum ([winch.line]) needs 5-DOF elements"
            )

    def updated(self, overrides: Mapping[str, Any]) -> Scene:
        """Return a new validated scene with dotted-key ``overrides`` applied (see `load_scene`)."""
        base_dir = Path(self.source).parent if self.source else None
        data = _apply_overrides(self.to_dict(), overrides)
        return _build(Scene, data, "", base_dir, source=self.source)


def _apply_overrides(data: Mapping[str, Any], overrides: Mapping[str, Any] | None) -> dict:
    """Copy ``data`` and set each dotted key of ``overrides`` (e.g. ``"model.elements"``)."""
    if overrides is not None and not isinstance(overrides, Mapping):
        raise TypeError(
            f"overrides: expected a mapping of dotted field paths to values (e.g. "
            f"{{'model.elements': 20}}), got {type(overrides).__name__}"
        )
    data = copy.deepcopy(dict(data))
    for key, value in (overrides or {}).items():
        parts = str(key).split(".")
        if not all(part.strip() for part in parts):
            raise SceneError(
                repr(str(key)),
                ": not a field path: a key names a field by its sections and name, dotted, none "
                "empty (e.g. 'model.elements'; cable-ocp schema lists them)",
            )
        node = data
        for depth, part in enumerate(parts[:-1]):
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                prefix = ".".join(parts[: depth + 1])
                raise SceneError(key, f": cannot set a key inside {prefix}, which is not a table")
        node[parts[-1]] = copy.deepcopy(value)  # a later key must not write into the caller's
    return data


def _build(cls: type, data: Any, path: str, base_dir: Path | None, **extra: Any) -> Any:
    """Build dataclass ``cls`` from the raw mapping ``data`` found at ``path``."""
    if not isinstance(data, Mapping):
        raise SceneError(path or "scene", f": expected a table, got {_describe(data)}")
    specs = {f.name: f for f in fields(cls) if "spec" in f.metadata}
    join = (lambda name: f"{path}.{name}") if path else str
    for name in data:
        if name not in specs:
            raise SceneError(join(name), f": unknown key; allowed keys: {', '.join(specs)}")
    for name, f in specs.items():
        if name not in data and f.default is MISSING and f.default_factory is MISSING:
            raise SceneError(join(name), ": missing required key")
    kwargs = dict(extra)
    relative = {}  # the field paths of relative file paths: how they were resolved
    for name, value in data.items():
        spec = specs[name].metadata["spec"]
        if spec.kind == "section" and not (value is None and spec.optional):
            value = _build(spec.item, value, join(name), base_dir)
        elif spec.kind == "tuple" and isinstance(value, list):
            value = [
                _build(spec.item, v, f"{join(name)}[{k}]", base_dir) for k, v in enumerate(value)
            ]
        elif spec.kind == "path" and isinstance(value, str):
            if not Path(value).expanduser().is_absolute():
                base = "the scene file's folder" if base_dir else "the working folder"
                relative[join(name)] = (
                    f" (the relative path {value!r} was resolved against {base}, "
                    f"{str(Path(base_dir or Path.cwd()).resolve())!r})"
                )
            value = str(Path(base_dir or Path.cwd()) / Path(value).expanduser())
        kwargs[name] = value
    try:
        return cls(**kwargs)
    except SceneError as err:
        err = err.relocated(cls._section, path)
        if err.path in relative:
            err = SceneError(err.path, err.detail + relative[err.path])
        raise err from None


def scene_from_dict(
    data: Mapping[str, Any], name: str = "scene", base_dir: str | os.PathLike | None = None
) -> Scene:
    """Build a validated scene from a nested dict shaped like a scene file.

    Parameters
    ----------
    data : Mapping
        Sections as nested mappings, as parsed from TOML or given by `Scene.to_dict`.
    name : str
        Scene name used when ``data`` has no ``name`` key.
    base_dir : path-like, optional
        Folder that relative file paths (``top.table``) are resolved against; default: cwd.

    Returns
    -------
    Scene
        The validated scene (``source`` is None).

    Raises
    ------
    SceneError
        A ``ValueError`` naming the offending field path and what is allowed.
    """
    data = {"name": name, **data}
    return _build(Scene, data, "", Path(base_dir) if base_dir is not None else None)


def scene_of(record: Mapping[str, Any], name: str = "scene") -> Scene:
    """The scene a result kept as its ``scene_record`` (:meth:`Scene.to_dict`), validated again.

    Raises
    ------
    ValueError
        If the record is empty (the result was written before scenes were kept), or a
        :class:`SceneError` naming the field that no longer validates.
    """
    if not record:
        raise ValueError(
            f"this result of scene {name!r} holds no scene (written before results kept "
            "theirs): load the scene file instead"
        )
    return scene_from_dict(record, name)


def load_scene(path: str | os.PathLike, overrides: Mapping[str, Any] | None = None) -> Scene:
    """Load and validate a TOML scene file.

    Parameters
    ----------
    path : path-like
        The scene file; its stem is the default scene name, its folder the base of relative paths.
    overrides : Mapping, optional
        Dotted keys and values applied before validation, e.g. ``{"model.elements": 30,
        "numerics.step": 0.01}``; unknown keys are rejected like unknown keys in the file.

    Returns
    -------
    Scene
        The validated scene, with ``source`` the absolute path of the file.

    Raises
    ------
    SceneError
        A ``ValueError`` naming the offending field path, or the file if it cannot be read (not
        found, a folder, not UTF-8), is not valid TOML, is empty or lacks one of the tables every
        scene file needs (:data:`REQUIRED_TABLES`: ``[model]``, ``[top]``, ``[numerics]``).
    """
    path = _scene_file(path)
    data = _read_toml(path)
    if not data:
        raise SceneError(str(path), f": empty scene file; {_NEEDS}")
    for table in REQUIRED_TABLES:
        if table not in data:
            raise SceneError(table, f": missing table [{table}] in {path}; {_NEEDS}")
    data = {"name": path.stem, **_apply_overrides(data, overrides)}
    return _build(Scene, data, "", path.parent, source=str(path.resolve()))


def _scene_file(path: str | os.PathLike) -> Path:
    """The file of a scene given as a path, or as a bundled scene's bare name (``"deploy"``).

    An existing file wins; a bare name that is no file is a bundled scene of that name, or a
    SceneError naming the closest bundled names when some are close (else the missing file).
    """
    given = Path(path)
    if given.exists() or given.parent != Path(".") or given.suffix not in ("", ".toml"):
        return given
    name = given.name.removesuffix(".toml")
    if name in scene_names():
        return scene_path(name)
    close = closest_names(name)
    if not close:
        return given  # reported as a missing file
    raise SceneError(
        str(given),
        f": neither a scene file nor a bundled scene (did you mean {' or '.join(close)}?); "
        "cable-ocp scenes lists them",
    )


_NEEDS = "a scene file needs at least the tables " + ", ".join(f"[{t}]" for t in REQUIRED_TABLES)


def _read_toml(path: Path) -> dict[str, Any]:
    """Parse the TOML file ``path``; every failure is a SceneError naming the file."""
    try:
        text = path.read_bytes().decode("utf-8")
    except FileNotFoundError:
        raise SceneError(str(path), ": scene file not found") from None
    except IsADirectoryError:
        raise SceneError(str(path), ": is a folder, not a scene file") from None
    except OSError as err:
        raise SceneError(str(path), f": cannot read the scene file ({err.strerror})") from None
    except UnicodeDecodeError as err:
        raise SceneError(
            str(path), f": not a UTF-8 text file (byte {err.start}); a scene file is TOML text"
        ) from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as err:
        raise SceneError(str(path), f": invalid TOML: {err}") from err
    except (ValueError, RecursionError) as err:  # a 5000-digit integer, arrays nested too deep
        raise SceneError(str(path), f": invalid TOML: {str(err)[:80]}") from None
