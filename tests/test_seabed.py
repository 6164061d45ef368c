"""The clearance error is the integrand of eq. 39, with the seabed delta below the end's start."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.scene import Hill
from cable_ocp.seabed import clearance_error, rms_objective, seabed_height

HILLS = (Hill(height=15.0, x0=70.0, y0=20.0, width_x=20.0, width_y=20.0),)


@pytest.mark.parametrize("delta", [0.0, 5.0, 12.5])
def test_clearance_error_is_the_paper_integrand(delta):
    """e = z_E + z_sb - z(x, y) - delta with z_sb = -(z_E(0) - delta), for any delta (eq. 39)."""
    rng = np.random.default_rng(7)
    end = np.column_stack(
        [rng.uniform(0, 140, 50), rng.uniform(-10, 40, 50), rng.uniform(-300, -280, 50)]
    )
    z_sb = -(end[0, 2] - delta)
    paper = end[:, 2] + z_sb - seabed_height(HILLS, end[:, 0], end[:, 1]) - delta
    assert np.allclose(clearance_error(HILLS, end), paper, atol=1e-12)


def test_an_end_that_follows_the_hill_has_zero_objective():
    """The end starts delta above the flat level and keeps delta above the hill: Omega = 0.

    (A start over a hill's flank is ``delta - z(x_E(0), y_E(0))`` above it: eq. 39 measures from
    the flat level.)
    """
    t = np.linspace(0.0, 210.0, 2101)
    x, y = t - 100.0, np.full(t.shape, 20.0)  # from flat ground over the hill top at 170 s
    start = -295.0
    z = start + seabed_height(HILLS, x, y)
    error = clearance_error(HILLS, np.column_stack([x, y, z]))
    assert rms_objective(t, error) < 1e-12
    assert rms_objective(t, clearance_error((), np.column_stack([x, y, z]))) > 1.0
