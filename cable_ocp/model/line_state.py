"""The state of a line across a change of its number of elements (CONVENTIONS.md §3).

**Split** (``n -> n + 1``, pay-out): the top element ``n``, of length ``l``, becomes element ``n``
of length ``Delta`` and a new top element ``n + 1`` of length ``l - Delta`` on the same axis,
turning at the same rates; its lower joint ``A_n + Delta e_n`` moves as that point of the old
rod did. Every material point keeps its position and velocity, so mass, momentum, angular
momentum, kinetic energy and the bonds (position and rate) are unchanged to rounding; the new
joint starts straight (no bending energy).

**Merge** (``n -> n - 1``, haul-in): the top element and the one below it (``Delta``), at an
angle ``alpha`` to each other, become one straight top element of ``Delta + l``. A straight rod
is longer than the chord of the kinked pair by ``s ~ Delta l alpha^2 / (2 (Delta + l))``: the new
element lies along that chord, from the top point down by ``Delta + l``, and the elements below
translate by the same small offset (``s`` along the chord) so that every bond holds exactly; their
velocities translate by the chord's axial rate mismatch, so that the bonds' rates hold too, and
the new element turns at the rate that carries its upper end with the top point. The rope's
length and mass are exact; its momentum changes by the lower chain's mass times that velocity
offset and by what a straight rod cannot carry of the kinked pair's motion (both reported by
:func:`momentum`).

**An elastic rope** (:mod:`cable_ocp.model.axial`) carries its strain ``s`` and rate across both:
the strain is uniform and the rest length of the line is unchanged, so is its elastic energy.
Every length above is then a rest length times ``1 + s``, and the stretching rate ``s'`` moves
each point along its element in proportion to its rest distance. The state's size says which
rope it is (:func:`_blocks`).
"""

from __future__ import annotations

import numpy as np

DOFS = 5  # 5-DOF elements: x, y, z, psi, theta


def axis(psi: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``e(psi, theta) = (cos theta cos psi, sin theta, cos theta sin psi)`` (CONVENTIONS.md §3)."""
    return np.array([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])


def axis_derivatives(psi: float, theta: float) -> tuple[np.ndarray, np.ndarray]:
    """``de/dpsi`` (length ``cos theta``) and ``de/dtheta`` (unit), orthogonal to each other."""
    d_psi = np.array([-np.cos(theta) * np.sin(psi), 0.0, np.cos(theta) * np.cos(psi)])
    d_theta = np.array([-np.sin(theta) * np.cos(psi), np.cos(theta), -np.sin(theta) * np.sin(psi)])
    return d_psi, d_theta


def axis_rate(psi: float, theta: float, psi_rate: float, theta_rate: float) -> np.ndarray:
    """``e'`` (1/s) of an element turning at ``psi'``, ``theta'`` (rad/s)."""
    d_psi, d_theta = axis_derivatives(psi, theta)
    return d_psi * psi_rate + d_theta * theta_rate


def _blocks(state: np.ndarray, elements: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Coordinates and rates per element (n+1, 5), and the strain with its rate (0 or 2,)."""
    size = DOFS * (elements + 1)
    axial = (len(state) - 2 * size) // 2
    if axial not in (0, 1) or len(state) != 2 * (size + axial):
        raise ValueError(
            f"a state of {len(state)} entries is not one of n = {elements} elements of 5 DOF "
            f"({2 * size}, or {2 * size + 2} with the strain)"
        )
    q = state[:size].reshape(-1, DOFS).copy()
    qd = state[size + axial : 2 * size + axial].reshape(-1, DOFS).copy()
    strain = np.array([state[size], state[-1]])[: 2 * axial]
    return q, qd, strain


def _joined(q: np.ndarray, qd: np.ndarray, strain: np.ndarray) -> np.ndarray:
    """The state of :func:`_blocks`' parts."""
    return np.concatenate([q.ravel(), strain[:1], qd.ravel(), strain[1:]])


def _stretch(strain: np.ndarray) -> tuple[float, float]:
    """``1 + s`` and ``s'`` (1/s) of the parts' strain (1 and 0 for a rigid rope)."""
    return (1.0 + strain[0], strain[1]) if strain.size else (1.0, 0.0)


def split(state: np.ndarray, elements: int, element_length: float) -> np.ndarray:
    """The state of ``n + 1`` elements from that of ``n = elements`` (see the module docstring).

    Parameters
    ----------
    state : array (2 * 5 (n + 1),), or (2 * (5 (n + 1) + 1),) with the strain
    elements : int
        ``n`` before the split.
    element_length : float, m
        ``Delta``, the element split off below the top.
    """
    q, qd, strain = _blocks(state, elements)
    stretch, strain_rate = _stretch(strain)
    top, rate = q[-1].copy(), qd[-1].copy()
    e = axis(top[3], top[4])
    top[:3] = q[-1, :3] + stretch * element_length * e
    turning = axis_rate(*q[-1, 3:5], *qd[-1, 3:5])
    rate[:3] = qd[-1, :3] + element_length * (stretch * turning + strain_rate * e)
    return _joined(np.vstack([q, top]), np.vstack([qd, rate]), strain)


def merge(
    state: np.ndarray,
    elements: int,
    element_length: float,
    top_length: float,
    top_point: np.ndarray,
    top_velocity: np.ndarray,
    top_length_rate: float,
) -> np.ndarray:
    """The state of ``n - 1`` elements from that of ``n = elements`` (see the module docstring).

    Parameters
    ----------
    state : array (2 * 5 (n + 1),), or (2 * (5 (n + 1) + 1),) with the strain
    elements : int
        ``n`` before the merge (>= 3).
    element_length : float, m
        ``Delta`` of the element merged into the top one.
    top_length : float, m
        ``l_n``, the top element's length before the merge.
    top_point, top_velocity : array (3,), m, m/s
        The top point ``A_{n+1}`` and its velocity at the merge.
    top_length_rate : float, m/s
        ``l_n'``, the drum's pay-out rate (the same before and after).
    """
    q, qd, strain = _blocks(state, elements)
    stretch, strain_rate = _stretch(strain)
    below = q[-2, :3]  # A_{n-1}, the lower joint of the merged element
    rest = element_length + top_length
    length = stretch * rest
    chord = top_point - below
    e = chord / np.linalg.norm(chord)
    offset = top_point - length * e - below  # s along the chord: the straight rod's excess
    q[:-1, :3] += offset
    psi = np.arctan2(e[2], e[0])
    psi += 2 * np.pi * np.round((q[-2, 3] - psi) / (2 * np.pi))  # the branch of the old angle
    theta = np.arcsin(np.clip(e[1], -1.0, 1.0))
    relative = top_velocity - qd[-2, :3] - (stretch * top_length_rate + strain_rate * rest) * e
    slip = float(relative @ e)  # the chord's axial rate mismatch
    qd[:-1, :3] += slip * e
    turning = (relative - slip * e) / length
    d_psi, d_theta = axis_derivatives(psi, theta)
    q[-2, 3:5] = psi, theta
    qd[-2, 3:5] = turning @ d_psi / np.cos(theta) ** 2, turning @ d_theta
    return _joined(q[:-1], qd[:-1], strain)


def momentum(
    state: np.ndarray, lengths: np.ndarray, mass_per_length: float
) -> tuple[np.ndarray, float]:
    """Linear momentum of the rope (3,), kg m/s, and its mass (kg), payload excluded.

    Each rigid element's centre moves at ``A_i' + l_i e_i' / 2``.
    """
    elements = len(lengths) - 1
    q, qd, _ = _blocks(state, elements)
    total = np.zeros(3)
    for i, length in enumerate(lengths):
        centre = qd[i, :3] + 0.5 * length * axis_rate(*q[i, 3:5], *qd[i, 3:5])
        total += mass_per_length * length * centre
    return total, mass_per_length * float(np.sum(lengths))
