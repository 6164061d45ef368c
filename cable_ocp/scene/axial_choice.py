"""Rigid or elastic rope: the scene's ``model.axial``, and the rule that ``auto`` applies.

The line and its payload are a spring and a mass. Their first axial period (DNV-RP-H103 §5.2)

    T0 = 2 pi sqrt((M + A33 + (m + a_t) L / 3) / (EA / L))

(``M`` the payload's mass, ``A33`` its added mass, ``m`` and ``a_t`` the line's mass and axial
added mass per metre, ``L`` the longest line the scene reaches) is set against what excites it:
the sea state's band, a sinusoidal heave, and the drum's bandwidth (its acceleration limit over
its rate limit). A rigid rope moves the payload with the top; the elastic one answers each
frequency ``w`` through the transmissibility of a damped oscillator (``b = w T0 / 2 pi``, ``zeta``
the scene's ``cable.axial_damping``)::

    payload:  H_x = (1 + 2 i zeta b) / (1 - b^2 + 2 i zeta b)
    tension:  H_T = 1 / (1 - b^2 + 2 i zeta b)

The rigid rope's error is the larger of ``|A - 1|`` over both, ``A`` the root-mean-square of
``|H|`` weighted by the heave's spectrum (for the payload) or the top acceleration's (``w^4``
times it, for the tension). ``auto`` chooses the elastic rope where that error exceeds
:data:`RIGID_ERROR`; the rest keep the paper's rigid rope, whose figures stay as they were.

A line paid out by elements (``[winch.line]``) is judged at the longest line it reaches: its
strain and ``EA / L`` follow the line out (:mod:`cable_ocp.model.line_state`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cable_ocp.scene.schema import SceneError
from cable_ocp.scene.wave_spectrum import BAND, jonswap_shape

# The rigid rope's largest accepted error in the payload's heave or the dynamic tension (2 %: the
# validation asks 5 % of the heave and 10 % of the tension range, with room for the estimate).
RIGID_ERROR = 0.02
SPECTRUM_POINTS = 400  # frequencies across the sea state's band
# The largest static strain an elastic rope may hang at: beyond any working rope (steel wire
# breaks at 1-2 %, HMPE near 4 %, nylon near 20 %), and the uniform strain is a small-strain model.
STRAIN_MAX = 0.1


@dataclass(frozen=True)
class AxialChoice:
    """The rope a scene gets along its axis, and why.

    Attributes
    ----------
    elastic : bool
        Whether the scene's rope stretches along its axis (else it is rigid, inextensible).
    mode : str
        The scene's ``model.axial``: "rigid", "elastic" or "auto".
    period : float, s
        ``T0`` of the longest line the scene reaches.
    line_length : float, m
        That line.
    excitation_period : float or None, s
        The shortest period that excites the line (None: nothing does).
    rigid_error : float
        The rigid rope's estimated error in the payload's heave or the dynamic tension.
    """

    elastic: bool
    mode: str
    period: float
    line_length: float
    excitation_period: float | None
    rigid_error: float

    @property
    def note(self) -> str:
        """One line for a run's notes: what was chosen and why."""
        rope = "elastic" if self.elastic else "rigid"
        where = (
            "neither heave nor the drum excites it"
            if self.excitation_period is None
            else f"excited down to {self.excitation_period:.3g} s, the rigid rope errs by "
            f"{100 * self.rigid_error:.2g} % (limit {100 * RIGID_ERROR:g} %)"
        )
        return (
            f"axial: {rope} rope (model.axial = {self.mode!r}); first axial period "
            f"T0 = {self.period:.3g} s on {self.line_length:.4g} m of line; {where}"
        )


def longest_line(scene) -> float:
    """The longest line out the scene reaches (m): its line plus what the drum may pay out."""
    line = scene.winch.line
    if line is not None:
        return scene.cable.length + line.pay_out_max
    return scene.cable.length + scene.winch.drum_radius * max(scene.winch.angle_max, 0.0)


def axial_period(scene, length: float) -> float:
    """First axial period ``T0`` (s) of ``length`` m of the scene's line with its payload."""
    cable, env = scene.cable, scene.environment
    water = env.fluid_density
    hyd = scene.hydrodynamics
    axial_added = water * cable.cross_section_area * hyd.added_mass_axial if hyd.added_mass else 0
    payload = scene.end.payload
    mass = payload.inertia_in(env) if payload is not None else 0.0
    line = (cable.mass_per_length + axial_added) * length / 3
    return 2 * math.pi * math.sqrt((mass + line) * length / cable.axial_stiffness_value)


def _excitations(scene) -> list[tuple[np.ndarray, np.ndarray]]:
    """What moves the line: ``(frequencies rad/s, spectral weights)`` per source."""
    found = []
    heave = scene.top.heave
    if heave is not None and heave.sea_state is not None:
        sea = heave.sea_state
        peak = 2 * math.pi / sea.peak_period
        w = np.linspace(BAND[0] * peak, BAND[1] * peak, SPECTRUM_POINTS)
        found.append((w, jonswap_shape(w, sea.peak_period, sea.peak_enhancement)))
    if heave is not None and heave.amplitude:
        found.append((np.array([2 * math.pi / heave.period]), np.ones(1)))
    winch = scene.winch
    if winch.rate_max is not None and winch.acceleration_max is not None:
        found.append((np.array([winch.acceleration_max / winch.rate_max]), np.ones(1)))
    return found


def rigid_error(period: float, damping: float, frequencies, weights) -> float:
    """The rigid rope's error in the payload's heave or the dynamic tension (module docstring).

    Parameters
    ----------
    period : float, s
        ``T0``.
    damping : float
        ``zeta``.
    frequencies : array, rad/s
    weights : array
        The heave's spectral density at ``frequencies`` (any scale).
    """
    ratio = np.asarray(frequencies) * period / (2 * math.pi)
    denominator = 1 - ratio**2 + 2j * damping * ratio
    payload = np.abs((1 + 2j * damping * ratio) / denominator) ** 2
    tension = np.abs(1 / denominator) ** 2
    acceleration = np.asarray(weights) * np.asarray(frequencies) ** 4
    rms_payload = math.sqrt(np.sum(weights * payload) / np.sum(weights))
    rms_tension = math.sqrt(np.sum(acceleration * tension) / np.sum(acceleration))
    return max(abs(rms_payload - 1), abs(rms_tension - 1))


def static_strain(scene, length: float) -> float:
    """The static strain of ``length`` m of the scene's line hanging its load (at the top).

    The submerged weight of the line and the payload and the end force's size, over ``EA``.
    """
    cable, env = scene.cable, scene.environment
    line = abs(cable.density - env.fluid_density) * cable.cross_section_area * env.gravity * length
    payload = scene.end.payload
    load = abs(payload.weight_in(env)) if payload else 0.0
    force = math.hypot(*scene.end.force)
    return (line + load + force) / cable.axial_stiffness_value


def _check_static_strain(scene, length: float) -> None:
    """Refuse an elastic rope that would hang stretched beyond :data:`STRAIN_MAX`."""
    strain = static_strain(scene, length)
    if strain > STRAIN_MAX:
        field = "axial_stiffness" if scene.cable.axial_stiffness is not None else "fill_factor"
        raise SceneError(
            f"cable.{field}",
            f": EA = {scene.cable.axial_stiffness_value:.4g} N would stretch {length:.4g} m of "
            f"line by {100 * strain:.3g} % under its own weight and its load (at most "
            f"{100 * STRAIN_MAX:g} %: no working rope stretches so far, steel wire breaks at "
            "1-2 %); give the rope's real EA (cable.axial_stiffness, or youngs_modulus and "
            "fill_factor)",
        )


def axial_choice(scene) -> AxialChoice:
    """The rope the scene's ``model.axial`` gives (``auto``: by the rule of the module)."""
    length = longest_line(scene)
    period = axial_period(scene, length)
    excitations = _excitations(scene)
    damping = scene.cable.axial_damping
    error = max((rigid_error(period, damping, w, s) for w, s in excitations), default=0.0)
    shortest = min((2 * math.pi / w.max() for w, _ in excitations), default=None)
    mode = scene.model.axial
    elastic = mode == "elastic" or (mode == "auto" and error > RIGID_ERROR)
    if elastic:
        _check_static_strain(scene, length)
    if elastic and scene.model.torsion:
        raise SceneError(
            "model.axial",
            f" = {mode!r}: the elastic rope (T0 = {period:.3g} s) needs 5-DOF elements: set "
            "model.torsion = false, or model.axial = 'rigid'",
        )
    return AxialChoice(elastic, mode, period, length, shortest, error)
