"""The hold after a landing: the closed loop keeps the load in a band above its target.

Once landed, the line out stays near the landing line, so the hold is a scene of fixed ``n``:
:func:`hold_scene` makes it from a ``[lowering]`` scene (the line at the landing as
``cable.length``, the line's own ``n``, the drum free to haul in or pay out
:data:`HOLD_RANGE` about it, the seabed's clearance ``delta`` set to ``lowering.height``, the
hold's duration), and :func:`hold` runs the closed loop (:func:`cable_ocp.mpc`, the measured heave
fed back) on it. The line is trimmed until the hanging end starts at the target height (the
vessel's heave at the hold's start moves it), so that the closed loop starts on its target and
is judged only on what the sea does. Reported: the largest deviation from the target height
against ``lowering.hold_band``, and the compensation ratio ``1 - std(z_E) / std(z_top)`` in %,
the load's vertical motion against the vessel's at the winch (CONVENTIONS.md §5, lowering).

The hold's vessel must hold station (``top.motion = "fixed"``, heave allowed): a tow's profile
starts again at the hold scene's t = 0. The sea state is the scene's, from its own start (the
same spectrum and seed, so the same sea in distribution, not the same waves as at the landing).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.control.closed_loop.result import MpcResult
from cable_ocp.control.closed_loop.settings import MpcSettings
from cable_ocp.control.keywords import refuse_unknown
from cable_ocp.drive.drive import Drive
from cable_ocp.lowering.arguments import real_number
from cable_ocp.lowering.checks import Check, drum_checks, sampled_line
from cable_ocp.lowering.descent import landing_line, line_range, seabed_reference
from cable_ocp.lowering.files import WithParts, check_recomputed
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.given import scene_given
from cable_ocp.scene.schema import Scene, scene_from_dict
from cable_ocp.simulation.seabed import clearance
from cable_ocp.simulation.statics import starting_state

HOLD_RANGE = 10.0  # m of line the drum may haul in or pay out about the landing line
LINE_TOLERANCE = 1e-3  # m: the hold's start is trimmed to the target height within this
TRIM_ITERATIONS = 8
CALM = 1e-6  # m: a vessel heaving less (std) has no compensation ratio (NaN)


@dataclass(frozen=True)
class HoldResult(WithParts):
    """A closed-loop hold above the target.

    Attributes
    ----------
    mpc : MpcResult
        The closed loop's result on the hold scene (its ``trajectory`` the plant's run).
    scene : Scene
        The hold scene.
    deviation : float, m
        The largest ``|z_E - z_sb - lowering.height|`` over the hold.
    band : float, m
        ``lowering.hold_band``.
    compensation_ratio : float, %
        ``100 (1 - std(z_E) / std(z_top))``: the share of the vessel's heave kept off the load
        (NaN in a calm, where the vessel does not heave).
    heave_std, load_std : float, m
        The standard deviations of the top's and the end's heights over the hold.
    peak_rate : float, rad/s
        The drum's largest rate, from the plant's inputs at its output times (heave payout
        included).
    peak_acceleration : float, rad/s^2
        The drum's largest acceleration, likewise.
    drum : tuple of Check
        Those peaks against the winch's limits (:func:`~.checks.drum_checks`).
    """

    PARTS = ("mpc",)
    WHAT = "hold"
    # CF units of the fields kept as variables (a percentage is no SI symbol of a docstring).
    UNITS = MappingProxyType({
        "deviation": "m", "band": "m", "compensation_ratio": "percent", "heave_std": "m",
        "load_std": "m", "peak_rate": "rad s-1", "peak_acceleration": "rad s-2",
    })  # fmt: skip

    mpc: MpcResult
    scene: Scene
    deviation: float
    band: float
    compensation_ratio: float
    heave_std: float
    load_std: float
    peak_rate: float
    peak_acceleration: float
    drum: tuple[Check, ...]

    def check_file(self) -> None:
        """Check a hold read from a file against the closed loop's run it holds.

        Its scene is the one the closed loop ran on, its band a band, and its figures what
        that run gives (:func:`_measured`, as :func:`hold` made them).

        Raises
        ------
        ValueError
            Naming the field (a forged file).
        """
        if self.scene.to_dict() != self.mpc.scene_record:
            raise ValueError("scene_record: not the scene its closed loop ran on (mpc)")
        if not (np.isfinite(self.band) and self.band > 0):
            raise ValueError(f"band = {self.band!r} m: expected a hold band > 0")
        for name, value in _measured(self.scene, self.mpc).items():
            check_recomputed(name, getattr(self, name), value)

    def winch_profile(self, scene=None, retime: str | None = None):
        """The drum's angle the closed loop applied, to replay the hold on its scene.

        ``MpcResult.winch_profile`` on ``scene`` (default: the hold scene).
        """
        return self.mpc.winch_profile(scene if scene is not None else self.scene, retime)

    @property
    def drum_excess(self) -> str:
        """The winch limits the drum went beyond, as text ('' when it kept within them)."""
        return "; ".join(str(check) for check in self.drum if not check.passed)

    @property
    def success(self) -> bool:
        """Whether the closed loop succeeded, kept the load in the band and the drum in limits."""
        return bool(self.mpc.success) and self.deviation <= self.band and not self.drum_excess

    @property
    def status(self) -> str:
        """What happened, in one line."""
        if not self.mpc.success:
            return f"the closed loop failed: {self.mpc.status}"
        verdict = "within" if self.deviation <= self.band else "outside"
        text = (
            f"held {verdict} the band: largest deviation {self.deviation:.3g} m against "
            f"+/- {self.band:g} m, compensation ratio {self.compensation_ratio:.1f} % (load "
            f"{self.load_std:.3g} m against heave {self.heave_std:.3g} m, standard deviations)"
        )
        return f"{text}; beyond the winch: {self.drum_excess}" if self.drum_excess else text


def hold_scene(scene, line_out: float | None = None, duration: float | None = None) -> Scene:
    """The fixed-``n`` scene of a ``[lowering]`` scene's line held at its landing.

    Parameters
    ----------
    scene : Scene, str or path-like
        With ``[lowering]`` and ``[winch.line]``, its vessel holding station (a path or a
        bundled name is loaded).
    line_out : float, optional, m
        The line out to start from (default: :func:`~.descent.landing_line`); trimmed until the
        hanging end starts within :data:`LINE_TOLERANCE` of the target height.
    duration : float, optional, s
        The hold (default: ``numerics.duration - lowering.land_time``).

    Raises
    ------
    TypeError
        A scene, ``line_out`` or ``duration`` of the wrong type.
    ValueError
        A scene without ``[lowering]`` or ``[winch.line]``, a moving vessel, no hold time, a
        ``line_out`` beyond what the drum holds (:func:`~.descent.line_range`) or a ``duration``
        that is not positive: each before any statics.
    """
    scene = scene_given(scene, "hold")
    hold_time = held_on_station(scene, "a hold", duration is None)
    if duration is not None:
        duration = real_number("duration", duration, "s")
        if not duration > 0:
            raise ValueError(f"duration = {duration!r} s is out of range: must be > 0")
    duration = hold_time if duration is None else duration
    if line_out is not None:
        line_out = real_number("line_out", line_out, "m")
        least, most = line_range(scene)
        if not least <= line_out <= most:
            raise ValueError(
                f"line_out = {line_out!r} m is out of range: must be within [{least:g}, "
                f"{most:g}] m, the line the drum holds (cable.length - winch.line.haul_in_max "
                "to cable.length + winch.line.pay_out_max)"
            )
    length = landing_line(scene) if line_out is None else line_out
    return trimmed_line(scene, scene.lowering.height, length, duration, HOLD_RANGE)


def held_on_station(scene, what: str, needs_hold: bool = True) -> float:
    """The hold's duration (s) of a ``[lowering]`` scene whose vessel holds station.

    Raises
    ------
    ValueError
        Naming ``what`` needs it: a scene without ``[lowering]`` or ``[winch.line]``, a moving
        vessel, or (``needs_hold``) no time after ``lowering.land_time``.
    """
    if scene.lowering is None or scene.winch.line is None:
        raise ValueError(f"{what} needs a scene with [lowering] and [winch.line]")
    if scene.top.motion != "fixed":
        raise ValueError(
            f"top.motion = {scene.top.motion!r}: {what} needs the vessel holding station "
            "(top.motion = 'fixed'; heave allowed)"
        )
    duration = scene.numerics.duration - scene.lowering.land_time
    if needs_hold and not duration > 0:
        raise ValueError(
            f"numerics.duration = {scene.numerics.duration!r} s leaves no hold after "
            f"lowering.land_time = {scene.lowering.land_time!r} s: numerics.duration must be "
            "longer (hold() also takes a hold duration)"
        )
    return duration


def trimmed_line(
    scene, height: float, line_out: float, duration: float, pay_out: float,
    lowering: dict | None = None,
) -> Scene:  # fmt: skip
    """A ``[winch.line]`` scene's line as a fixed-``n`` scene whose end starts ``height`` up.

    The line (first ``line_out``, m) is trimmed until its hanging end starts within
    :data:`LINE_TOLERANCE` of ``height`` (m) above the seabed under it; the drum may haul in
    :data:`HOLD_RANGE` and pay out ``pay_out`` (m) about it, over ``duration`` (s). The seabed
    stays where it is: a grid's clearance ``delta`` is ``lowering.height`` (the target), and a
    relative seabed, which lies ``delta`` below the start, is placed by ``delta = height``.
    ``lowering`` (a table, or None) is the new scene's ``[lowering]``.

    Raises
    ------
    ValueError
        The trimming does not converge (naming ``lowering.height``).
    """
    reference = seabed_reference(scene)
    length = line_out
    for _ in range(TRIM_ITERATIONS):
        held = _fixed_line(scene, length, duration, pay_out, lowering, height)
        miss = _start_height(held, scene, reference) - height
        if abs(miss) < LINE_TOLERANCE:
            return held
        length += miss  # too high by miss: pay out as much (the end falls by what is paid out)
    raise ValueError(
        f"lowering.height = {scene.lowering.height!r} m: the held line's start stays {miss:+.3g} m "
        f"off {height:.6g} m after {TRIM_ITERATIONS} trims (line out {length:.6g} m)"
    )


def _fixed_line(
    scene, length: float, duration: float, pay_out: float, lowering, height: float
) -> Scene:
    """The scene's line as a fixed-``n`` scene of ``length`` (m) over ``duration`` (s)."""
    data = scene.to_dict()
    line = data["winch"].pop("line")
    data.pop("lowering")
    if lowering is not None:
        data["lowering"] = lowering
    mesh = scene.winch.line.mesh
    radius = scene.winch.drum_radius
    data["cable"]["length"] = length
    data["model"]["elements"] = mesh.starting_elements(length)
    data["winch"].update(angle_min=-HOLD_RANGE / radius, angle_max=pay_out / radius)
    data["winch"]["top_length_min"] = line.get("top_length_min", mesh.element_length / 2)
    seabed = data["seabed"]
    seabed["clearance"] = scene.lowering.height if scene.seabed.absolute else height
    if seabed.get("minimum_clearance") is not None:
        seabed["minimum_clearance"] = min(seabed["minimum_clearance"], scene.lowering.height)
    data["numerics"]["duration"] = duration
    data["name"] = f"{scene.name}_{'landing' if lowering is not None else 'hold'}"
    return scene_from_dict(data, base_dir=None)


def _start_height(held: Scene, scene, reference: float) -> float:
    """The held line's hanging end above the (lowering scene's) seabed, m."""
    model = CableModel.from_scene(held)
    end = starting_state(model, Drive.from_scene(held), compiled=True)[:3]
    return float(clearance(scene.seabed, end, reference))


def vessel_heights(run) -> np.ndarray:
    """The top's prescribed heights over a run (k,), m: the vessel's, from the run's inputs.

    Not the model's top joint, which carries the bonds' residual (1e-6 m): in a calm that alone
    made a compensation ratio of -457000 %.
    """
    return run.inputs[:, INPUTS.top][:, 2]


def compensation_ratio(top_heights, end_heights) -> tuple[float, float, float]:
    """The share of the vessel's heave kept off the load, ``100 (1 - std z_E / std z_top)`` (%).

    Parameters
    ----------
    top_heights, end_heights : arrays (k,), m
        The top's and the end's heights over the same samples.

    Returns
    -------
    ratio : float, %
        NaN in a calm (the top's standard deviation below :data:`CALM`).
    heave_std, load_std : float, m
        The two standard deviations.
    """
    heave_std, load_std = float(np.std(top_heights)), float(np.std(end_heights))
    ratio = 100.0 * (1.0 - load_std / heave_std) if heave_std > CALM else float("nan")
    return ratio, heave_std, load_std


def hold(
    scene, line_out: float | None = None, duration: float | None = None, quiet: bool = True,
    **settings,
) -> HoldResult:  # fmt: skip
    """Hold a landed load above its target by the closed loop, in the scene's sea state.

    Parameters
    ----------
    scene : Scene, str or path-like
        With ``[lowering]`` and ``[winch.line]`` (see :func:`hold_scene`); a scene file's path
        or a bundled scene's name too.
    line_out, duration
        As for :func:`hold_scene`.
    quiet : bool
        No progress bar.
    **settings
        Fields of :class:`~cable_ocp.control.closed_loop.settings.MpcSettings`; another keyword
        is refused before any work (TypeError naming the allowed ones).

    Returns
    -------
    HoldResult
        Never raises for a closed loop that fails: ``success`` and ``status`` say so.
    """
    own = MpcSettings.__dataclass_fields__
    unknown = {name: value for name, value in settings.items() if name not in own}
    refuse_unknown("hold", unknown, ("scene", "line_out", "duration", "quiet", *own))
    scene = scene_given(scene, "hold")
    held = hold_scene(scene, line_out, duration)
    result = mpc(held, quiet=quiet, **settings)
    return HoldResult(result, held, band=scene.lowering.hold_band, **_measured(held, result))


def _measured(held: Scene, result: MpcResult) -> dict:
    """A hold's figures from its closed loop's run (:class:`HoldResult`'s fields, by name)."""
    run = result.trajectory
    ratio, heave_std, load_std = compensation_ratio(vessel_heights(run), run.end[:, 2])
    line = sampled_line(run)
    rate, acceleration = (float(np.abs(v).max()) / held.winch.drum_radius for v in line)
    return {
        "deviation": float(np.max(np.abs(run.clearance_error))),
        "compensation_ratio": ratio, "heave_std": heave_std, "load_std": load_std,
        "peak_rate": rate, "peak_acceleration": acceleration,
        "drum": tuple(drum_checks(held.winch, run.time, *line)),
    }  # fmt: skip
