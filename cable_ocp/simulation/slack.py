"""Slack and compression of a run's rope: where and when a bond stops pulling.

A rope pulls and never pushes, but the rfe model's bonds carry any force: a run that drives the
rope faster than it can follow (a drum paying out faster than the load sinks, a load driven
through the water) shows bonds in compression. The **signed tension** of bond ``j`` (at the upper
end of element ``j - 1``; bond ``n + 1`` is the top) is its bond force along that element's axis,
positive pulling (:func:`signed_tensions`); the model's ``tensions`` are the force's norm, which
has no sign.

Each bond's signed tension is held against its **static tension** (:func:`static_tensions`):
the submerged weight that hangs below it (the rope below, the payload, the end force's downward
part), DNV-RP-H103's ``F_static`` of the hoisting system at that line out. Three levels
(:func:`slack_report`):

- **slack**: below :data:`SLACK_FRACTION` of static, DNV-RP-H103 §5's slack criterion (a
  reported note: snap loads follow when the rope tightens again);
- **compression**: below zero (a note: where a real rope would go slack);
- **pushing**: below ``-compression_tolerance`` (:func:`compression_tolerance`): the run is no
  picture of a rope, and it fails.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from cable_ocp.model.cable import spec_from_scene
from cable_ocp.model.layout import INPUTS
from cable_ocp.simulation.drum_range import drum_failure, rate_findings
from cable_ocp.simulation.seabed import seabed_findings

# DNV-RP-H103 §5 (deepwater lowering): the minimum tension must stay above 10 % of the static.
SLACK_FRACTION = 0.1
# A run fails when a bond pushes with more than this share of the rope's largest static top
# tension (see compression_tolerance).
COMPRESSION_SHARE = 0.01


def signed_tensions(joints: np.ndarray, forces: np.ndarray) -> np.ndarray:
    """Bond forces along the element axes, as tensions: positive pulls, negative pushes (N).

    Parameters
    ----------
    joints : array (..., 3, n+2), m
        ``A_0 .. A_{n+1}``; the axis of element ``i`` is ``A_{i+1} - A_i``.
    forces : array (..., 3, n+1), N
        The bond forces ``lambda_j`` of bonds ``1 .. n+1`` (``model.outputs``'s ``bond_forces``).

    Returns
    -------
    array (..., n+1), N
        ``-lambda_j . e_{j-1}`` (the bond pulls element ``j - 1`` up along its axis).
    """
    axes = np.diff(joints, axis=-1)
    axes = axes / np.linalg.norm(axes, axis=-2, keepdims=True)
    return -np.sum(forces * axes, axis=-2)


def static_tensions(spec, joints: np.ndarray, end_force_z: np.ndarray) -> np.ndarray:
    """The submerged weight hanging below each bond (k, n+1), N.

    ``w_s s_j + (m_p - rho_w V_p) g - F_z``: the rope's submerged weight per metre ``w_s`` over
    the length ``s_j`` below bond ``j`` (the elements' lengths from the joints), the payload's
    submerged weight, and the downward part of the end force.

    Parameters
    ----------
    spec : ModelSpec
        The rope, the payload, gravity and water (:func:`cable_ocp.model.cable.spec_from_scene`).
    joints : array (k, 3, n+2), m
        NaN after a sample's top joint (a line run's padded joints) gives NaN there.
    end_force_z : array (k,), N
    """
    lengths = np.linalg.norm(np.diff(joints, axis=-1), axis=-2)
    payload = spec.payload
    weight = (payload.mass - spec.water_density * payload.volume) * spec.gravity
    below = np.cumsum(lengths, axis=-1)
    return spec.element.submerged_weight_per_length * below + (weight - end_force_z)[:, None]


def compression_tolerance(static: np.ndarray) -> float:
    """How hard a bond may push before the run fails (N).

    :data:`COMPRESSION_SHARE` of the largest static top tension of the run.

    A stated choice: any push is outside a rope's physics, but a bond near zero tension (the
    free end of a rope without a load) may carry the small corrective forces of the bonds'
    Baumgarte stabilisation with either sign, and a run should fail on the rope, not on them.
    One per cent of the rope's whole hanging weight is a force that moves the run (the paper's
    rope, 62 kN, fails from 0.62 kN of push) and far from both sides measured: the least bond
    tension of the bundled scenes' runs is +1.8 to +3.3 kN (paper_hill, survey, small_tow,
    end_force; the hanging rope under a 3 m, 6 s heave +1.2 kN), a load paid out faster than it
    sinks pushes with 34 to 91 kN (tests/test_slack.py).
    """
    return COMPRESSION_SHARE * float(np.nanmax(np.abs(top_values(static))))


def _top_index(values: np.ndarray) -> np.ndarray:
    """Index of the last finite value of each row (the top bond of a padded line run)."""
    return values.shape[1] - 1 - np.argmax(np.isfinite(values[:, ::-1]), axis=1)


def top_values(values: np.ndarray) -> np.ndarray:
    """The top bond's value of each sample (k,) of per-bond values (k, m) padded with NaN."""
    return values[np.arange(values.shape[0]), _top_index(values)]


@dataclass(frozen=True)
class SlackEvent:
    """Where and when a run's rope crossed one level.

    Attributes
    ----------
    what : str
        ``top tension below 10 % of static``, ``bond in compression``, ...
    first : float, s
        The first sample below the level.
    duration : float, s
        How long it stayed below (samples below times the output interval).
    worst : float, N
        The least signed tension below the level.
    time : float, s
        When the worst was reached.
    bond : int
        Which bond (1 .. n+1, the last the top).
    """

    what: str
    first: float
    duration: float
    worst: float
    time: float
    bond: int

    def __str__(self) -> str:
        return (
            f"{self.what} from t = {self.first:g} s for {self.duration:.3g} s, least "
            f"{self.worst:.4g} N at t = {self.time:g} s (bond {self.bond})"
        )


@dataclass(frozen=True)
class SlackReport:
    """The slack and compression of a run (:func:`slack_report`).

    Attributes
    ----------
    least_top_tension, peak_top_tension : float, N
        Of the signed top tension.
    least_bond_tension : float, N
        The least signed tension of any bond at any sample (negative: a bond pushes).
    least_static_share : float
        The least signed tension over the static one, of any bond where the static is positive.
    compression_tolerance : float, N
        The push beyond which the run fails.
    events : tuple of SlackEvent
        The levels crossed, for the top bond and for any bond.
    signed : bool
        Whether the run kept signed tensions (a file written before them holds only norms:
        nothing could then be said of compression).
    """

    least_top_tension: float
    peak_top_tension: float
    least_bond_tension: float
    least_static_share: float
    compression_tolerance: float
    events: tuple[SlackEvent, ...]
    signed: bool = True

    @property
    def pushing(self) -> bool:
        """Whether a bond pushed beyond :attr:`compression_tolerance` (never when unsigned)."""
        return self.signed and self.least_bond_tension < -self.compression_tolerance

    @property
    def reason(self) -> str:
        """Why the run fails (empty when it does not)."""
        if not self.pushing:
            return ""
        worst = next(e for e in self.events if e.what.startswith("rope pushes"))
        return f"{worst}: a rope cannot push; the run does not show this rope"

    @property
    def notes(self) -> list[str]:
        """One line per level crossed; the unsigned run's warning."""
        unknown = (
            []
            if self.signed
            else ["the run holds no signed tensions (written before them): compression unknown"]
        )
        return unknown + [str(event) for event in self.events]


def slack_report(time: np.ndarray, signed: np.ndarray, static: np.ndarray) -> SlackReport:
    """Where and when the top tension, and each bond's, goes below the levels of the module.

    Parameters
    ----------
    time : array (k,), s
    signed : array (k, m), N
        Signed tensions of bonds ``1 .. m`` (NaN past a sample's top bond).
    static : array (k, m), N
        Their static tensions (:func:`static_tensions`).
    """
    top_index = _top_index(signed)
    rows = np.arange(time.size)
    top, top_static = signed[rows, top_index], static[rows, top_index]
    tolerance = compression_tolerance(static)
    interval = float(np.median(np.diff(time))) if time.size > 1 else 0.0
    events = []
    for what, values, levels, bonds in (
        ("top tension", top[:, None], top_static[:, None], top_index[:, None] + 1),
        ("bond", signed, static, np.broadcast_to(np.arange(1, signed.shape[1] + 1), signed.shape)),
    ):
        for name, level in (
            (f"{what} below {SLACK_FRACTION:.0%} of static", SLACK_FRACTION * levels),
            (f"{what} in compression", np.zeros_like(levels)),
            (f"rope pushes beyond {tolerance:.3g} N", np.full_like(levels, -tolerance)),
        ):
            if what == "top tension" and name.startswith("rope pushes"):
                continue  # the bonds' event covers the top's
            event = _event(name, time, values, level, bonds, interval)
            if event is not None:
                events.append(event)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(static > 0, signed / static, np.nan)
    return SlackReport(
        least_top_tension=float(np.nanmin(top)),
        peak_top_tension=float(np.nanmax(top)),
        least_bond_tension=float(np.nanmin(signed)),
        least_static_share=float(np.nanmin(share)) if np.isfinite(share).any() else float("nan"),
        compression_tolerance=tolerance,
        events=tuple(events),
    )


def _event(name, time, values, level, bonds, interval) -> SlackEvent | None:
    """The crossing of ``level`` by ``values`` (k, m) over ``time``, or None if never."""
    with np.errstate(invalid="ignore"):
        below = values < level
    samples = below.any(axis=1)
    if not samples.any():
        return None
    masked = np.where(below, values, np.inf)
    k, b = np.unravel_index(int(np.argmin(masked)), masked.shape)
    return SlackEvent(
        what=name,
        first=float(time[int(np.argmax(samples))]),
        duration=float(np.count_nonzero(samples) * interval),
        worst=float(values[k, b]),
        time=float(time[k]),
        bond=int(bonds[k, b]),
    )


def run_static(run, spec) -> np.ndarray:
    """Static tensions of a run's bonds over its samples (k, largest n + 1), N.

    ``run`` is a Trajectory or a LineTrajectory (its joints padded with NaN past each top).
    """
    force = run.joined(lambda s: s.inputs[:, INPUTS.end_force][:, 2])
    return static_tensions(spec, run.padded(lambda s: s.joints), force)


@dataclass(frozen=True)
class PhysicsCheck:
    """Whether a run shows what its scene can hold: the rope pulling, the end, the drum.

    Attributes
    ----------
    slack : SlackReport
        The signed tensions against the static ones (:func:`slack_report`).
    seabed_failure : str or None
        Where the end went under an absolute seabed
        (:func:`~cable_ocp.simulation.seabed.seabed_findings`).
    seabed_notes : tuple of str
        The end under a relative seabed, or nearer than ``seabed.minimum_clearance``.
    end_under_seabed : bool
        Whether the end went under the seabed, absolute or relative.
    drum_failure : str or None
        Where the drum turned beyond ``[winch.angle_min, winch.angle_max]``
        (:func:`~cable_ocp.simulation.drum_range.drum_failure`).
    rate_failure : str or None
        Where the drum turned faster than ``winch.rate_max``
        (:func:`~cable_ocp.simulation.drum_range.rate_findings`).
    acceleration_note : str or None
        Where it accelerated harder than ``winch.acceleration_max`` (a note).
    """

    slack: SlackReport
    seabed_failure: str | None = None
    seabed_notes: tuple[str, ...] = ()
    end_under_seabed: bool = False
    drum_failure: str | None = None
    rate_failure: str | None = None
    acceleration_note: str | None = None

    @property
    def success(self) -> bool:
        """No bond pushed, the end stayed above an absolute seabed, the drum within its limits."""
        return not self.failures

    @property
    def failures(self) -> list[str]:
        """Why the run fails, one line per cause (empty when it succeeds)."""
        causes = (self.slack.reason, self.seabed_failure, self.drum_failure, self.rate_failure)
        return [text for text in causes if text]

    @property
    def notes(self) -> list[str]:
        """Slack crossings, seabed notes and the drum's acceleration, one line each."""
        drum = [self.acceleration_note] if self.acceleration_note else []
        return [*self.slack.notes, *self.seabed_notes, *drum]

    @property
    def status(self) -> str:
        """One line: the failures, else ``physics checked`` with the least bond tension."""
        if self.failures:
            return "; ".join(self.failures)
        seabed = (
            "the end under the relative seabed (a note)"
            if self.end_under_seabed
            else "the end above the seabed"
        )
        return (
            f"physics checked: least bond tension {self.slack.least_bond_tension:.4g} N "
            f"(fails below -{self.slack.compression_tolerance:.3g} N), {seabed}, the drum "
            "within its range"
        )

    def summary(self) -> dict:
        """The check's figures (json-ready), with ``"units"``."""
        slack = self.slack
        figures = {
            "success": self.success,
            "status": self.status,
            "notes": self.notes,
            "top_tension_min": slack.least_top_tension,
            "top_tension_max": slack.peak_top_tension,
            "least_bond_tension": slack.least_bond_tension,
            "least_static_share": slack.least_static_share,
            "compression_tolerance": slack.compression_tolerance,
        }
        units = {name: "N" for name in figures if "tension" in name}
        units["least_static_share"] = "1"
        return {**figures, "units": units}


def check_physics(run) -> PhysicsCheck:
    """The slack, the seabed and the drum limits of a run (Trajectory or LineTrajectory).

    A run that kept no signed tensions (a file written before them) is checked on the norms,
    and its report says that compression is unknown.

    Raises
    ------
    ValueError
        The run holds no scene (a file written before scenes were kept).
    """
    scene = run.scene
    kept = bool(run.joined(lambda s: np.full(s.time.size, s.kept_signs)).all())
    tensions = run.padded(lambda s: s.signed_tensions if kept else s.tensions)
    report = slack_report(run.time, tensions, run_static(run, spec_from_scene(scene)))
    failure, notes, under = seabed_findings(scene.seabed, run.time, run.end)
    rate, acceleration = rate_findings(scene, run.time, run.joined(lambda s: s.inputs))
    return PhysicsCheck(
        report if kept else replace(report, signed=False),
        seabed_failure=failure,
        seabed_notes=tuple(notes),
        end_under_seabed=under,
        drum_failure=drum_failure(scene.winch, run.time, run.winch_angle),
        rate_failure=rate,
        acceleration_note=acceleration,
    )


class PhysicsChecked:
    """A run's physics check as its properties: ``physics``, ``success`` and ``status``.

    Mixed into both trajectory kinds (a fixed-n :class:`~cable_ocp.simulation.trajectory.Trajectory`
    and a :class:`~cable_ocp.simulation.line_trajectory.LineTrajectory`).
    """

    @cached_property
    def physics(self) -> PhysicsCheck:
        """The run's slack, compression, seabed and drum range (:func:`check_physics`).

        Raises ValueError if the run holds no scene.
        """
        return check_physics(self)

    @property
    def success(self) -> bool:
        """Whether the run passed its physics check (:attr:`physics`)."""
        return self.physics.success

    @property
    def status(self) -> str:
        """The physics check's one line: why the run fails, or that it passed."""
        return self.physics.status
