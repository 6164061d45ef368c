"""The JONSWAP spectrum of a scene's sea state: its shape and the band its components cover.

Used by the sea state's components (:mod:`cable_ocp.drive.sea_state`) and by the choice of the
rope's axial fidelity (:mod:`cable_ocp.scene.axial_choice`), which weighs the waves against the
line's axial period.
"""

from __future__ import annotations

import numpy as np

BAND = (0.5, 3.0)  # the components' band, in units of the peak frequency
SIGMA_BELOW, SIGMA_ABOVE = 0.07, 0.09  # JONSWAP peak widths below and above the peak


def jonswap_shape(frequency: np.ndarray, peak_period: float, gamma: float) -> np.ndarray:
    """The JONSWAP spectrum's shape at the angular frequencies ``frequency`` (rad/s), unscaled.

    ``w^-5 exp(-5/4 (w_p / w)^4) gamma^r`` with ``r = exp(-(w - w_p)^2 / (2 sigma^2 w_p^2))``.
    """
    peak = 2 * np.pi / peak_period
    w = np.asarray(frequency, dtype=float)
    sigma = np.where(w <= peak, SIGMA_BELOW, SIGMA_ABOVE)
    enhancement = gamma ** np.exp(-((w - peak) ** 2) / (2 * sigma**2 * peak**2))
    return w**-5 * np.exp(-1.25 * (peak / w) ** 4) * enhancement
