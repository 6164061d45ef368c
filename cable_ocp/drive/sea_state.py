"""Motion of the winch in a sea state: a JONSWAP spectrum as random-phase components.

The sea surface at the vessel is a sum of ``N`` cosines, ``eta(t) = sum_i a_i cos(w_i t + phi_i)``.
The band ``[0.5, 3] w_p`` (``w_p = 2 pi / T_p``) is cut into ``N`` bins of equal width ``dw``; each
component's frequency is drawn uniformly inside its bin and its phase uniformly in ``[0, 2 pi)``
(numpy's default generator with the scene's seed, so a seed gives one record; the drawn frequencies
keep the record from repeating after ``2 pi / dw``). The amplitudes are ``a_i = sqrt(2 S(w_i) dw)``
of the JONSWAP spectrum (DNV-RP-C205 §3.5.5)

    S(w) ~ w^-5 exp(-5/4 (w_p / w)^4) gamma^exp(-(w - w_p)^2 / (2 sigma^2 w_p^2)),

sigma = 0.07 below the peak and 0.09 above, scaled so that the components carry the spectrum's
variance exactly: ``sum a_i^2 / 2 = m0 = (H_s / 4)^2``.

The vessel responds through its RAO table (amplitude and phase per frequency, interpolated
linearly in w and held beyond the table's ends): heave ``h``, roll ``r`` (about x) and pitch
``p`` (about y), each ``sum_i a_i |R(w_i)| cos(w_i t + phi_i + eps(w_i))``. Without a table the
vessel heaves with the surface (``R_heave = 1``) and neither rolls nor pitches. The winch, at the
offset ``o`` from the centre of roll and pitch (vessel axes parallel to the world's: the heading
along x), moves by the small-angle rotation

    d(t) = h e_z + (r, p, 0) x o = (p o_z, -r o_z, h + r o_y - p o_x),

less its value at t = 0, so that the winch is at ``top.start`` when the run starts.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cable_ocp.scene.wave_spectrum import BAND, jonswap_shape


@dataclass(frozen=True)
class WaveComponents:
    """The sea surface at the vessel as ``sum_i a_i cos(w_i t + phi_i)``.

    Attributes
    ----------
    frequencies : array (N,), rad/s
    amplitudes : array (N,), m
    phases : array (N,), rad
    """

    frequencies: np.ndarray
    amplitudes: np.ndarray
    phases: np.ndarray


def wave_components(
    significant_height: float, peak_period: float, gamma: float, count: int, seed: int
) -> WaveComponents:
    """Random-phase components of a JONSWAP sea (module docstring).

    Parameters
    ----------
    significant_height : float, m
        ``H_s = 4 sqrt(m0)``.
    peak_period : float, s
        ``T_p``.
    gamma : float
        Peak enhancement (1: Pierson-Moskowitz; 3.3: the JONSWAP mean).
    count : int
        Number of components ``N``.
    seed : int
        Seed of the frequencies within their bins and of the phases.
    """
    peak = 2 * np.pi / peak_period
    edges = np.linspace(BAND[0] * peak, BAND[1] * peak, count + 1)
    width = edges[1] - edges[0]
    rng = np.random.default_rng(seed)
    frequencies = edges[:-1] + width * rng.uniform(size=count)
    phases = rng.uniform(0.0, 2 * np.pi, size=count)
    energy = 2 * jonswap_shape(frequencies, peak_period, gamma) * width
    scale = (significant_height / 4) ** 2 / (energy.sum() / 2)
    return WaveComponents(frequencies, np.sqrt(energy * scale), phases)


def responses(sea_state, waves: WaveComponents) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Amplitude (m or rad) and phase (rad) per component of heave, roll and pitch.

    The RAO table's columns interpolated at the components' frequencies (module docstring).
    """
    rows, w = sea_state.rao, waves.frequencies
    if not rows:
        zero = np.zeros_like(w)
        still = (zero, zero)
        return {"heave": (waves.amplitudes, waves.phases), "roll": still, "pitch": still}
    table = np.array([row.frequency for row in rows])
    out = {}
    for motion in ("heave", "roll", "pitch"):
        gain = np.interp(w, table, [getattr(row, motion) for row in rows])
        lead = np.interp(w, table, [getattr(row, f"{motion}_phase") for row in rows])
        out[motion] = (waves.amplitudes * gain, waves.phases + lead)
    return out


def sea_state_motion(sea_state) -> Callable[[np.ndarray], tuple[np.ndarray, ...]]:
    """The winch's displacement in a scene's ``[top.heave.sea_state]`` (module docstring).

    Returns
    -------
    callable
        ``t -> (position, velocity, acceleration)``, arrays (3, len(t)) in m, m/s, m/s^2; the
        position is 0 at t = 0.
    """
    waves = wave_components(
        sea_state.significant_height,
        sea_state.peak_period,
        sea_state.peak_enhancement,
        sea_state.components,
        sea_state.seed,
    )
    ox, oy, oz = sea_state.winch_offset
    # Each motion's unit displacement of the winch (m per m of heave, per rad of roll or pitch).
    lever = {"heave": (0.0, 0.0, 1.0), "roll": (0.0, -oz, oy), "pitch": (oz, 0.0, -ox)}
    w = waves.frequencies
    # Each axis's displacement is sum_j a_j cos(w_j t + phase_j) over the motions that move it;
    # cos(w t + p) = cos(w t) cos(p) - sin(w t) sin(p), so one cosine and one sine of w t serve
    # every motion and axis: the weights of cos(w t) and sin(w t) per axis (3, components).
    # The position is taken from t = 0, where cos(w t) = 1 and sin(w t) = 0 exactly.
    cos_weight, sin_weight = np.zeros((3, w.size)), np.zeros((3, w.size))
    for name, (amplitude, phase) in responses(sea_state, waves).items():
        if not (np.any(amplitude) and np.any(lever[name])):
            continue
        direction = np.array(lever[name])[:, None]
        cos_weight += direction * (amplitude * np.cos(phase))
        sin_weight -= direction * (amplitude * np.sin(phase))

    # The rates' weights once, not at every call (the closed loop calls twice a sample).
    cos_rate, sin_rate = cos_weight * w, sin_weight * w
    cos_curvature, sin_curvature = cos_weight * w**2, sin_weight * w**2

    def motion(t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        angle = np.outer(w, t)
        cos, sin = np.cos(angle), np.sin(angle)
        position = cos_weight @ (cos - 1.0) + sin_weight @ sin
        velocity = sin_rate @ cos - cos_rate @ sin
        acceleration = -(cos_curvature @ cos + sin_curvature @ sin)
        return position, velocity, acceleration

    return motion
