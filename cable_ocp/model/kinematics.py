"""Kinematics of one rigid finite element: rotation, axis direction and their rates.

Conventions (CONVENTIONS.md §3): z is up; an element's generalised coordinates are
``q_i = [x, y, z, psi, theta]`` (5 DOF) or ``[..., phi]`` (6 DOF, torsion). The element axis is
``e(psi, theta) = (cos(theta) cos(psi), sin(theta), cos(theta) sin(psi))``, so a hanging element has
``psi = pi/2, theta = 0`` and the chart is singular only for an element along ±y (theta = ±pi/2).
"""

from __future__ import annotations

import casadi as ca

# Paper axes (X, Y up, Z) -> our axes (x, y, z) = (X, -Z, Y).
_PAPER_TO_WORLD = ca.DM([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])

POSITION = slice(0, 3)
TWIST_ANGLE = 5


def axis_direction(psi: ca.SX, theta: ca.SX) -> ca.SX:
    """Unit vector along the element, from A_i towards A_{i+1}.

    Parameters
    ----------
    psi : SX, rad
        Angle in the vertical x-z plane.
    theta : SX, rad
        Out-of-plane angle.

    Returns
    -------
    SX (3x1)
        ``e = (cos theta cos psi, sin theta, cos theta sin psi)``.
    """
    return ca.vertcat(ca.cos(theta) * ca.cos(psi), ca.sin(theta), ca.cos(theta) * ca.sin(psi))


def rotation_matrix(psi: ca.SX, theta: ca.SX, phi: ca.SX | float = 0.0) -> ca.SX:
    """Rotation from the element frame to the world frame.

    The paper's ``R = Rz(psi) Ry(theta) Rx(phi)`` (eq. 3) expressed in our axes; its first column is
    :func:`axis_direction`.

    Parameters
    ----------
    psi, theta, phi : SX, rad
        Euler angles Z'Y'X' of the paper.

    Returns
    -------
    SX (3x3)
    """
    c, s = ca.cos, ca.sin
    rz = ca.vertcat(
        ca.horzcat(c(psi), -s(psi), 0), ca.horzcat(s(psi), c(psi), 0), ca.horzcat(0, 0, 1)
    )
    ry = ca.vertcat(
        ca.horzcat(c(theta), 0, s(theta)), ca.horzcat(0, 1, 0), ca.horzcat(-s(theta), 0, c(theta))
    )
    rx = ca.vertcat(
        ca.horzcat(1, 0, 0), ca.horzcat(0, c(phi), -s(phi)), ca.horzcat(0, s(phi), c(phi))
    )
    return _PAPER_TO_WORLD @ rz @ ry @ rx


def relative_twist(rotation_below: ca.SX, rotation_above: ca.SX) -> ca.SX:
    """Twist angle of one element frame relative to its neighbour about the element axis.

    The angle of the relative rotation ``R_{i-1}^T R_i`` (eq. 17) about the local x' axis; it is
    invariant under a common spin of both frames, so only relative twist stores energy.

    Returns
    -------
    SX, rad
    """
    rel = rotation_below.T @ rotation_above
    return ca.atan2(rel[2, 1] - rel[1, 2], rel[1, 1] + rel[2, 2])
