"""Winch angle ``phi(t)`` and the top-element length it sets (CONVENTIONS.md §3, paper eq. 38, 41).

``l_n(t) = l_top + r_D (phi(t) - phi(0))`` with ``phi > 0`` paying out, ``l_top`` the top element
at ``phi = 0`` (Delta/2 on a uniform mesh; longer where the winch needs the reach, ``Scene.mesh``).
An angle history is a callable ``(t, left=None) -> (phi, phi', phi'')`` in rad, rad/s, rad/s^2;
where ``left`` is true a time on a breakpoint of a piecewise profile gives the limit from the left
(the end stage of an RK4 step, :func:`cable_ocp.drive.drive.stage_times`). The profiles here are
C2: they ignore it.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

import numpy as np

from cable_ocp.scene.rules import finite_array

WinchAngleFunction = Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]]
PROFILE_SAMPLES = 2001  # samples of a profile where its largest acceleration is looked for
SHORTEST_SETTLE = 0.1  # s, the least time constant of a winch brought to rest


def locked(t: np.ndarray, left=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A winch that does not turn: ``phi = 0``."""
    zeros = np.zeros(np.atleast_1d(t).shape)
    return zeros, zeros.copy(), zeros.copy()


def with_left(angle: WinchAngleFunction) -> WinchAngleFunction:
    """``angle`` if it takes ``left``; else the same history taken as smooth (both limits agree).

    A user's callable ``t -> (phi, phi', phi'')`` need not know about left limits.
    """
    try:
        takes_left = "left" in inspect.signature(angle).parameters
    except (TypeError, ValueError):
        takes_left = False
    return angle if takes_left else lambda t, left=None: angle(t)


def check_angle(angle: WinchAngleFunction) -> None:
    """Raise ValueError, naming the winch, unless ``angle`` gives an angle history at t = 0.

    An angle history returns ``(phi, phi', phi'')`` in rad, rad/s, rad/s^2, each an array
    like its ``t``, finite. A user's callable that returns a number, or NaN, is caught here,
    before it reaches the statics as an unpacking error or a failed equilibrium.
    """
    t = np.zeros(2)  # two times: a number returned for an array of them is caught too
    values = angle(t, None)
    wanted = (
        "a winch function must return (phi, phi', phi'') in rad, rad/s, rad/s^2, each an array "
        "like its t"
    )
    if isinstance(values, str | bytes) or not isinstance(values, tuple | list) or len(values) != 3:
        text = repr(values)
        text = text if len(text) <= 60 else text[:57] + "..."
        raise ValueError(f"winch: the function returned {type(values).__name__} {text}; {wanted}")
    for name, value in zip(("phi", "phi'", "phi''"), values, strict=True):
        finite_array(value, f"winch: the function's {name}", t.shape, "t",
                     lambda k: f" at t = {t[k]:g} s", wanted)  # fmt: skip


def coming_to_rest(angle, rate, acceleration, tau, settle: float):
    """The angle ``tau`` (s) past an end where it had ``angle``, ``rate``, ``acceleration``.

    A C2 continuation that comes to rest: the rate decays as ``(v + (a + v/c) tau) exp(-tau/c)``
    from the end's rate ``v`` and acceleration ``a``, ``c = settle`` (s), so the angle settles
    at ``angle + v c + (a + v/c) c^2``. (Holding the end's angle dropped the rate to zero at
    once, and the jump in the top element's speed opened the bonds.) Linear in the end's
    values, which may be arrays (or basis rows) broadcasting with ``tau``.

    Returns
    -------
    phi, phi', phi'' : arrays, rad, rad/s, rad/s^2
    """
    c = settle
    decay = np.exp(-tau / c)
    slope = acceleration + rate / c
    return (
        angle + rate * c * (1 - decay) + slope * c * (c - (tau + c) * decay),
        (rate + slope * tau) * decay,
        (slope - (rate + slope * tau) / c) * decay,
    )


def played_then_resting(angle: WinchAngleFunction, end: float) -> WinchAngleFunction:
    """``angle`` up to ``end`` (s), then :func:`coming_to_rest`, braked as the profile moved.

    The history of a profile replayed in its own time on a longer run. Its end's values are
    taken from the left (a piecewise profile continues its last piece), and the time constant is
    ``c = |phi'(end)| / max |phi''|``: the brake's deceleration peaks at ``1/e`` of the
    profile's largest acceleration (at least :data:`SHORTEST_SETTLE`).
    """
    times = np.linspace(0.0, end, PROFILE_SAMPLES)
    peak = float(np.abs(angle(times, None)[2]).max())
    last = [float(np.ravel(v)[0]) for v in angle(np.array([end]), np.array([True]))]
    settle = max(abs(last[1]) / peak if peak > 0 else 0.0, SHORTEST_SETTLE)

    def played(t, left=None):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        phi, rate, acceleration = (
            np.array(v, dtype=float) for v in angle(np.minimum(t, end), left)
        )
        beyond = t > end
        if beyond.any():
            rest = coming_to_rest(*last, t[beyond] - end, settle)
            phi[beyond], rate[beyond], acceleration[beyond] = rest
        return phi, rate, acceleration

    return played


# How a profile saved from a run of one duration is replayed on a scene of another (by choice).
RETIMES = {
    "hold": "played in its own time, then brought to rest and held (cut where the scene is "
    "shorter)",
    "stretch": "stretched in time over the scene's duration",
}


def check_retime(retime: str) -> None:
    """Raise ValueError unless ``retime`` is one of :data:`RETIMES`, naming them."""
    if retime not in RETIMES:
        raise ValueError(
            f"retime = {retime!r}: must be one of " + ", ".join(repr(name) for name in RETIMES)
        )


def replayed_duration(own: float | None, duration: float, retime: str | None, what: str) -> float:
    """The duration (s) to lay a saved profile over when it drives a scene of ``duration`` s.

    Parameters
    ----------
    own : float or None, s
        The duration the profile was made for (None when its file does not say: laid over the
        scene's, as before results kept their scene).
    duration : float, s
        The scene's ``numerics.duration``.
    retime : {None, "hold", "stretch"}
        None refuses another duration; ``"hold"`` keeps the profile's own time
        (:func:`played_then_resting` past its end), ``"stretch"`` lays it over the scene's.
    what : str
        How the user asks for a retimed profile, named in the refusal, e.g.
        ``"result.retimed('hold')"`` with ``{}`` for the choice.

    Raises
    ------
    ValueError
        An unknown ``retime``, or another duration with ``retime`` None, naming both durations
        and the choices.
    """
    if retime is not None:
        check_retime(retime)
    if own is None or retime == "stretch":
        return duration
    if retime is None and not np.isclose(own, duration, rtol=1e-9, atol=1e-9):
        choices = "; ".join(f"{what.format(repr(name))}: {text}" for name, text in RETIMES.items())
        raise ValueError(
            f"numerics.duration = {duration:g} s, but the winch profile was made for {own:g} s: "
            f"replayed as it is, it would be stretched in time {duration / own:.3g}x. Replay it "
            f"on a scene of {own:g} s, or choose how: {choices}"
        )
    return own


def knot_times(duration: float, knots: int) -> np.ndarray:
    """Equidistant knot times ``t_i = i T / p`` for ``i = 0..p`` (eq. 41), s."""
    return np.linspace(0.0, duration, knots + 1)


def spline_angle(duration: float, knot_values) -> WinchAngleFunction:
    """Cubic spline through ``phi(t_i)``, ``i = 1..p``, with ``phi(0) = 0`` (the paper's choice).

    The spline starts at rest (``phi'(0) = 0``, the winch is still in the initial equilibrium) and
    ends free (``phi''(T) = 0``).

    Parameters
    ----------
    duration : float, s
    knot_values : array (p,), rad
    """
    from scipy.interpolate import CubicSpline  # here: a locked winch runs without SciPy's import

    values = np.concatenate([[0.0], np.asarray(knot_values, dtype=float).ravel()])
    spline = CubicSpline(
        knot_times(duration, values.size - 1), values, bc_type=((1, 0.0), (2, 0.0))
    )
    rate, acceleration = spline.derivative(1), spline.derivative(2)

    def angle(t, left=None):
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), 0.0, duration)
        return spline(t), rate(t), acceleration(t)

    return angle


def tabulated_angle(time, angles) -> WinchAngleFunction:
    """Winch angle through a time series, interpolated by a C2 cubic spline (natural ends).

    Parameters
    ----------
    time : array (k,), s
        Strictly increasing, starting at 0, at least 4 samples.
    angles : array (k,), rad
        The first value must be 0 (``phi(0) = 0``, the initial configuration).
    """
    time = np.asarray(time, dtype=float).ravel()
    angles = np.asarray(angles, dtype=float).ravel()
    if time.size != angles.size or time.size < 4:
        raise ValueError(
            f"winch time series: need at least 4 pairs (t, phi); got {time.size} times and "
            f"{angles.size} angles"
        )
    if not (np.all(np.isfinite(time)) and np.all(np.isfinite(angles))):
        raise ValueError("winch time series: non-finite value (NaN or inf)")
    if np.any(np.diff(time) <= 0) or time[0] != 0.0:
        raise ValueError("winch time series: times must start at 0 s and increase strictly")
    if angles[0] != 0.0:
        raise ValueError(f"winch time series: phi(0) = {angles[0]} rad; it must be 0")
    from scipy.interpolate import CubicSpline

    spline = CubicSpline(time, angles, bc_type="natural")
    rate, acceleration = spline.derivative(1), spline.derivative(2)

    def angle(t, left=None):
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), 0.0, time[-1])
        return spline(t), rate(t), acceleration(t)

    return angle


def heave_payout(
    departure: np.ndarray, speed: np.ndarray, acceleration: np.ndarray, drum_radius: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Winch angle that pays out a vertical motion of the top (eq. 38): ``z / r_D`` and rates.

    Parameters
    ----------
    departure, speed, acceleration : arrays, m, m/s, m/s^2
        The top's height from its reference (the start in the open loop, the forecast in the
        closed loop) with its rates.
    drum_radius : float, m

    Returns
    -------
    phi, phi', phi'' : arrays, rad, rad/s, rad/s^2
    """
    return departure / drum_radius, speed / drum_radius, acceleration / drum_radius


def top_length(angle: tuple, nominal_length: float, drum_radius: float) -> np.ndarray:
    """Top-element length and its rates (3, len): m, m/s, m/s^2, from the winch's ``angle``.

    ``angle``: the angle, its rate and acceleration (rad, rad/s, rad/s^2), arrays alike;
    ``nominal_length`` (m) is the top element at ``phi = 0``.
    """
    phi, rate, acceleration = angle
    return np.vstack(
        [nominal_length + drum_radius * phi, drum_radius * rate, drum_radius * acceleration]
    )
