"""The analytic elastic catenary (paper eq. 34), the reference for the statics check.

A cable of length ``L`` and weight ``w`` per unit length is pinned at the origin (``s = 0``) and
loaded at its other end (``s = L``) by the horizontal force ``H`` and the vertical force ``V``
(upward). Coordinates are in the vertical plane of the load: ``x`` along ``H``, ``z`` up.
"""

from __future__ import annotations

import numpy as np


def catenary_shape(
    s: np.ndarray,
    length: float,
    weight_per_length: float,
    horizontal: float,
    vertical: float,
    axial_stiffness: float = np.inf,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position and tension along an elastic catenary (eq. 34a-c).

    Parameters
    ----------
    s : array, m
        Unstretched arc length from the pinned end.
    length : float, m
        L.
    weight_per_length : float, N/m
        ``w = rho A g``.
    horizontal, vertical : float, N
        H and V at the loaded end (H > 0).
    axial_stiffness : float, N
        ``EA``; ``inf`` gives the inextensible catenary.

    Returns
    -------
    x, z : arrays, m
    tension : array, N
    """
    if horizontal <= 0:
        raise ValueError(f"horizontal = {horizontal} N must be > 0 for a catenary")
    s = np.asarray(s, dtype=float)
    w, h = weight_per_length, horizontal
    base = vertical - w * length
    local = base + w * s
    x = h * s / axial_stiffness + h / w * (np.arcsinh(local / h) - np.arcsinh(base / h))
    z = s / axial_stiffness * (base + w * s / 2) + h / w * (
        np.sqrt(1 + (local / h) ** 2) - np.sqrt(1 + (base / h) ** 2)
    )
    return x, z, np.hypot(h, local)


def relative_errors(approximate: np.ndarray, exact: np.ndarray) -> np.ndarray:
    """Relative error ``|f_c - f_a| / |f_a|`` of eq. 35 (as a fraction, not in %)."""
    return np.abs((approximate - exact) / exact)
