"""Random lowering scenes: the planned landing, the optimised and the closed-loop landing, the hold.

``cable-ocp bench --only lowering [--cases N --seed S]`` draws N lowerings that an installation
engineer would plan (:class:`LoweringRanges` states each range and why), lands each in open loop
(:func:`cable_ocp.lowering.plan.plan_landing`: the reference descent, the heave fed forward on the
approach, the landing line corrected on the full model, every constraint checked on the verified
run) and holds it above its target by the closed loop (:func:`cable_ocp.lowering.hold.hold`);
then lands it from its hover (:func:`cable_ocp.lowering.landing.land`) by :func:`cable_ocp.optimize`
(Gauss-Newton, default settings) and by :func:`cable_ocp.mpc` (the measured heave fed back).
It prints how many succeeded, how many raised (which must be none), the landing errors and
speeds, the hold's deviation and compensation ratio, the median wall time of a planned landing
and of ``optimize``, the closed loops' real-time factors, and DNV-RP-H103's slack criterion
(the least top tension over its static value, above 10 %) and dynamic amplification factor (the
largest over it) of every landing run (:func:`cable_ocp.lowering.checks.check_landing`).

A case is a dict of scene overrides of the bundled ``paper_flat`` (its water and its
hydrodynamics), with a flat seabed ``depth`` below the end's start (``seabed.clearance``).
"""

from __future__ import annotations

import math
import time
import traceback
from dataclasses import dataclass

import numpy as np

from cable_ocp.lowering.hold import hold
from cable_ocp.lowering.landing import land, landing_scene
from cable_ocp.lowering.plan import plan_landing
from cable_ocp.scene.axial_choice import axial_choice
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import load_scene

WATER, GRAVITY = 1025.0, 9.81
# A steel wire rope's breaking load per mm^2 of its diameter squared (1770 MPa grade, fill 0.45).
BREAKING_LOAD_PER_MM2 = 800.0  # N
SAFETY_FACTOR = 4.0  # the working limit, tension_max, is a quarter of the breaking load
CRUISE_SHARE = 0.6  # of the winch's line speed: the landing time this leaves the descent
ELEMENTS_AT_LANDING = 60  # the element length is the landing line over this (at least 10 m)
HOLD = 60.0  # s


@dataclass(frozen=True)
class LoweringRanges:
    """Where the random lowerings are drawn from (uniformly unless stated).

    Attributes
    ----------
    depth : (float, float), m
        200-2000 m of water below the load's start: shelf-edge to deep-water installations.
    payload_mass : (float, float), kg
        0.5-20 t: sensor frames and transponders to subsea modules and suction anchors.
    payload_density : (float, float), kg/m^3
        Of the payload's volume: steel frames with buoyancy, 3000-7850.
    drag_coefficient : (float, float)
        Of the payload's plan area (a frame's, 1.0-2.0).
    steel_density : (float, float), kg/m^3
        The wire rope (6000-7850, with lubricant and voids).
    surface_current : (float, float), m/s
        0-0.8 m/s at the surface, falling to 20-60 % at the seabed, in a random direction.
    sea_share : float
        Share in a JONSWAP sea state.
    significant_height : (float, float), m
        H_s 0.5-2.5 m: the sea states an installation with heave compensation is planned for.
    peak_period : (float, float), s
        7-12 s: swell and wind sea of those heights.
    drum_radius : (float, float), m
        r_D, 0.5-1.5 m: the drum sets the winch's angle, rate and acceleration limits.
    line_speed : (float, float), m/s
        The winch's top line speed: 1.0-2.0 m/s.
    line_acceleration : (float, float), m/s^2
        1.0-2.5 m/s^2.
    heave_margin : (float, float)
        In a sea state the winch is one sized for it, as an installation is planned: its line
        speed and acceleration at least this many times the peaks of the vessel's heave over
        the run (4 standard deviations of its speed and acceleration), beside what the descent
        asks (the drawn line speed and acceleration).
    height : (float, float), m
        The landing's target height above the seabed.
    """

    depth: tuple[float, float] = (200.0, 2000.0)
    payload_mass: tuple[float, float] = (500.0, 20000.0)
    payload_density: tuple[float, float] = (3000.0, 7850.0)
    drag_coefficient: tuple[float, float] = (1.0, 2.0)
    steel_density: tuple[float, float] = (6000.0, 7850.0)
    surface_current: tuple[float, float] = (0.0, 0.8)
    bottom_share: tuple[float, float] = (0.2, 0.6)
    sea_share: float = 0.6
    significant_height: tuple[float, float] = (0.5, 2.5)
    peak_period: tuple[float, float] = (7.0, 12.0)
    drum_radius: tuple[float, float] = (0.5, 1.5)
    line_speed: tuple[float, float] = (1.0, 2.0)
    line_acceleration: tuple[float, float] = (1.0, 2.5)
    height: tuple[float, float] = (3.0, 10.0)
    heave_margin: tuple[float, float] = (1.1, 1.5)


def rope_diameter(load: float, depth: float, density: float) -> float:
    """The smallest wire (m, 20-80 mm, whole mm) whose working limit carries the lowering.

    ``load`` (N) is the payload's submerged weight; the rope's own over ``depth`` (m) is added.
    """
    for millimetres in range(20, 81):
        d = millimetres / 1000.0
        rope = (density - WATER) * GRAVITY * math.pi * d**2 / 4 * depth
        if BREAKING_LOAD_PER_MM2 * millimetres**2 / SAFETY_FACTOR >= 1.3 * (load + rope):
            return d
    return 0.08


def lowering_case(rng: np.random.Generator, ranges: LoweringRanges = LoweringRanges()) -> dict:
    """Scene overrides of ``paper_flat`` for one random lowering."""

    def uniform(bounds, digits=3):
        return float(np.round(rng.uniform(*bounds), digits))

    depth, mass = uniform(ranges.depth, 0), uniform(ranges.payload_mass, -1)
    volume = round(mass / uniform(ranges.payload_density, 0), 3)
    rope_density = uniform(ranges.steel_density, 0)
    load = (mass - WATER * volume) * GRAVITY
    diameter = rope_diameter(load, depth, rope_density)
    element = max(10.0, round(depth / ELEMENTS_AT_LANDING))
    start = max(20.0, 2 * element + 1.0)  # the line's shortest: 3/2 Delta + Delta/2
    radius = uniform(ranges.drum_radius, 2)
    speed, acceleration = uniform(ranges.line_speed, 2), uniform(ranges.line_acceleration, 2)
    height = uniform(ranges.height, 1)
    land_time = float(math.ceil((depth - height) / (CRUISE_SHARE * speed) / 10.0) * 10.0)
    surface = uniform(ranges.surface_current, 2)
    heading = rng.uniform(0.0, 2 * math.pi)
    bottom = surface * uniform(ranges.bottom_share, 2)
    case = {
        "top.motion": "fixed",
        "cable.length": start,
        "cable.diameter": diameter,
        "cable.density": rope_density,
        "end.payload": {"mass": mass, "volume": volume, "drag_area": round(mass / 1000.0, 2),
                        "drag": uniform(ranges.drag_coefficient, 2)},
        "environment.current_profile": [
            {"z": 0.0, "u": round(surface * math.cos(heading), 3),
             "v": round(surface * math.sin(heading), 3)},
            {"z": -depth, "u": round(bottom * math.cos(heading), 3),
             "v": round(bottom * math.sin(heading), 3)},
        ],
        "winch.drum_radius": radius,
        "winch.rate_max": round(speed / radius, 4),
        "winch.acceleration_max": round(acceleration / radius, 4),
        "winch.line": {"pay_out_max": depth + 50.0, "element_length": element},
        "seabed.clearance": depth,
        "lowering": {"land_time": land_time, "height": height,
                     "tension_min": round(0.2 * load), "tension_max": round(
                         BREAKING_LOAD_PER_MM2 * (1000 * diameter) ** 2 / SAFETY_FACTOR)},
        "numerics.duration": land_time + HOLD,
        "numerics.step": 0.05,
        "numerics.output_every": 10,
        "numerics.constraint_tolerance": 1e-4,
    }  # fmt: skip
    if rng.uniform() < ranges.sea_share:
        sea = {
            "significant_height": uniform(ranges.significant_height, 2),
            "peak_period": uniform(ranges.peak_period, 1),
            "seed": int(rng.integers(1000)),
        }
        case["top.heave"] = {"sea_state": sea}
        speed_peak, acceleration_peak = heave_peaks(sea, case["numerics.duration"])
        margin = uniform(ranges.heave_margin, 2)
        case["winch.rate_max"] = round(max(speed, margin * speed_peak) / radius, 4)
        case["winch.acceleration_max"] = round(
            max(acceleration, margin * acceleration_peak) / radius, 4
        )
    return case


def heave_peaks(sea: dict, duration: float) -> tuple[float, float]:
    """4 standard deviations of the heave's speed (m/s) and acceleration (m/s^2) over a run."""
    from cable_ocp.drive.sea_state import sea_state_motion
    from cable_ocp.scene.schema import SeaState

    _, velocity, acceleration = sea_state_motion(SeaState(**sea))(np.arange(0.0, duration, 0.25))
    return 4 * float(np.std(velocity[2])), 4 * float(np.std(acceleration[2]))


def lowering_cases(count: int, seed: int, ranges: LoweringRanges = LoweringRanges()) -> list:
    """``count`` random lowerings of ``seed``."""
    rng = np.random.default_rng([seed, 27])
    return [lowering_case(rng, ranges) for _ in range(count)]


def run_case(overrides: dict) -> dict:
    """Land and hold one case; a row of figures (never raises: an exception is a row too)."""
    row = {"overrides": overrides}
    try:
        scene = load_scene(scene_path("paper_flat"), overrides)
        axial = axial_choice(scene)
        row.update(elastic=axial.elastic, axial_period=axial.period)
        started = time.perf_counter()
        plan = plan_landing(scene)
        row.update(wall=time.perf_counter() - started, success=plan.success, status=plan.status,
                   runs=len(plan.landing_errors))  # fmt: skip
        if plan.report is not None:
            report = plan.report
            row.update(landing_error=report.landing_error, landing_speed=report.landing_speed,
                       peak_tension=report.peak_tension, least_tension=report.least_tension,
                       elements=int(plan.run.element_count.max()))  # fmt: skip
            row.update(dnv_figures("planned", report))
        held = hold(scene)
        row.update(hold_success=held.success, hold_status=held.status,
                   hold_deviation=held.deviation, ratio=held.compensation_ratio,
                   rtf=held.mpc.real_time_factor)  # fmt: skip
        landed = landing_scene(scene)
        optimised = land(landed)
        row.update(optimised=optimised.success, optimised_status=optimised.status,
                   optimise_wall=optimised.result.wall_time)  # fmt: skip
        looped = land(landed, closed_loop=True)
        row.update(looped=looped.success, looped_status=looped.status,
                   looped_ratio=looped.compensation_ratio,
                   looped_rtf=looped.result.real_time_factor)  # fmt: skip
        for name, result in (("optimised", optimised), ("looped", looped)):
            if result.report is not None:
                row[f"{name}_error"] = result.report.landing_error
                row.update(dnv_figures(name, result.report))
    except KeyboardInterrupt:
        raise
    except Exception as error:  # a raise is what the benchmark counts; its row says where
        row.update(success=False, raised=f"{type(error).__name__}: {error}",
                   trace=traceback.format_exc(limit=3))  # fmt: skip
    return row


LANDINGS = ("planned", "optimised", "looped")  # the landing runs of a case, as rows name them


def dnv_figures(name: str, report) -> dict:
    """A landing report's DNV-RP-H103 figures, keyed for a row.

    ``{name}_amplification`` (the dynamic amplification factor), ``{name}_static_share`` (the
    least top tension over static) and ``{name}_slack`` (whether the slack criterion held).
    """
    held = all(c.passed for c in report.checks if c.name.startswith("slack criterion"))
    return {
        f"{name}_amplification": report.dynamic_amplification,
        f"{name}_static_share": report.least_static_share,
        f"{name}_slack": held,
    }


def _line(k: int, row: dict) -> str:
    o = row["overrides"]
    payload = o["end.payload"]["mass"] / 1000
    sea = o.get("top.heave", {}).get("sea_state")
    head = (
        f"case {k:3d}: depth {o['seabed.clearance']:.0f} m, payload {payload:.1f} t, "
        f"d {1000 * o['cable.diameter']:.0f} mm, "
        + (f"Hs {sea['significant_height']:.1f} m" if sea else "calm")
    )
    if row.get("elastic"):
        head += f", elastic (T0 {row['axial_period']:.2g} s)"
    if "raised" in row:
        return f"{head}: RAISED {row['raised']}"
    land = "ok" if row["success"] else "FAILED " + row["status"]
    text = f"{head}: landing {land}"
    if "landing_error" in row:
        text += (f" (error {row['landing_error']:+.3g} m, speed {row['landing_speed']:+.2g} m/s, "
                 f"n -> {row['elements']}, {row['runs']} run(s), {row['wall']:.1f} s)")  # fmt: skip
    if "hold_success" in row:
        verdict = "ok" if row["hold_success"] else "FAILED"
        ratio = f"ratio {row['ratio']:.1f} %" if np.isfinite(row["ratio"]) else "no heave"
        text += f"; hold {verdict} {row['hold_deviation']:.3g} m, {ratio}, RTF {row['rtf']:.0f}"
    if "optimised" in row:
        text += (f"; from the hover: optimize {'ok' if row['optimised'] else 'FAILED'} "
                 f"({row['optimise_wall']:.1f} s), mpc {'ok' if row['looped'] else 'FAILED'} "
                 f"(RTF {row['looped_rtf']:.0f})")  # fmt: skip
        for name in ("optimised", "looped"):
            if not row[name]:
                text += f"\n    {name}: {row[name + '_status']}"
    dnv = [
        f"{name} DAF {row[name + '_amplification']:.3g}, min {row[name + '_static_share']:.0%}"
        f"{'' if row[name + '_slack'] else ' SLACK'}"
        for name in LANDINGS
        if name + "_amplification" in row
    ]
    if dnv:
        text += "\n    DNV-RP-H103: " + "; ".join(dnv) + " of static"
    return text


def summary(rows: list[dict]) -> dict:
    """The benchmark's figures."""
    landed = [r for r in rows if r.get("success")]
    holds = [r for r in rows if "hold_success" in r]
    return {
        "cases": len(rows),
        "raised": sum("raised" in r for r in rows),
        "landed": len(landed),
        "held": sum(r["hold_success"] for r in holds),
        "both": sum(r.get("success", False) and r.get("hold_success", False) for r in rows),
        "wall_median": float(np.median([r["wall"] for r in rows if "wall" in r] or [np.nan])),
        "error_max": float(max((abs(r["landing_error"]) for r in landed), default=np.nan)),
        "ratio_median": float(
            np.median([r["ratio"] for r in holds if np.isfinite(r["ratio"])] or [np.nan])
        ),  # fmt: skip
        "rtf_min": float(min((r["rtf"] for r in holds), default=np.nan)),
        "rtf_median": float(np.median([r["rtf"] for r in holds] or [np.nan])),
        **_hover_summary([r for r in rows if "looped" in r]),
        **_dnv_summary(rows),
        **_elastic_summary(rows),
    }


def _elastic_summary(rows: list[dict]) -> dict:
    """The cases whose rope ``model.axial = "auto"`` made elastic, and how many fully succeeded.

    A case succeeds when it raised nothing, its planned landing landed, the closed loop held it,
    and it landed from the hover both by ``optimize`` and by the closed loop.
    """
    elastic = [r for r in rows if r.get("elastic")]
    done = [
        r
        for r in elastic
        if "raised" not in r
        and r.get("success")
        and r.get("hold_success")
        and r.get("optimised")
        and r.get("looped")
    ]
    return {
        "elastic": len(elastic),
        "elastic_succeeded": len(done),
        "elastic_periods": [round(r["axial_period"], 2) for r in elastic],
    }


def _dnv_summary(rows: list[dict]) -> dict:
    """DNV-RP-H103's figures over every landing run of the rows.

    The runs checked, those whose slack criterion failed, the largest dynamic amplification
    and the least share of static.
    """
    runs = [(r[f"{n}_amplification"], r[f"{n}_static_share"], r[f"{n}_slack"])
            for r in rows for n in LANDINGS if f"{n}_amplification" in r]  # fmt: skip
    return {
        "dnv_runs": len(runs),
        "slack_failures": sum(not held for *_, held in runs),
        "amplification_max": float(np.nanmax([a for a, *_ in runs] or [np.nan])),
        "static_share_min": float(np.nanmin([s for _, s, _ in runs] or [np.nan])),
    }


def _hover_summary(rows: list[dict]) -> dict:
    """The landings from the hover: successes, optimize's median wall time, the loop's speed."""
    return {
        "optimised": sum(r["optimised"] for r in rows),
        "looped": sum(r["looped"] for r in rows),
        "optimise_wall_median": float(np.median([r["optimise_wall"] for r in rows] or [np.nan])),
        "looped_rtf_min": float(min((r["looped_rtf"] for r in rows), default=np.nan)),
        "looped_rtf_median": float(np.median([r["looped_rtf"] for r in rows] or [np.nan])),
        "looped_ratio_median": float(
            np.median(
                [r["looped_ratio"] for r in rows if np.isfinite(r["looped_ratio"])] or [np.nan]
            )  # fmt: skip
        ),
    }


def report(cases: int = 10, seed: int = 0, quiet: bool = False) -> tuple[list[dict], dict]:
    """Run and print the lowering benchmark; returns its rows and :func:`summary`."""
    rows = []
    for k, overrides in enumerate(lowering_cases(cases, seed)):
        rows.append(run_case(overrides))
        if not quiet:
            print(_line(k, rows[-1]), flush=True)
    figures = summary(rows)
    if not quiet:
        n = figures["cases"]
        print(
            f"lowering: {n} random lowerings (seed {seed}): planned landing and closed-loop hold; "
            "optimised and closed-loop landing from the hover\n"
            f"  landed             {figures['landed']}/{n} (every check on the verified run)\n"
            f"  held               {figures['held']}/{n} (within the band, closed loop)\n"
            f"  raised             {figures['raised']}\n"
            f"  landing error      at most {figures['error_max']:.3g} m (landed cases)\n"
            f"  landing wall       median {figures['wall_median']:.1f} s per case\n"
            f"  compensation       median {figures['ratio_median']:.1f} % (in a sea state)\n"
            f"  hold real time     min {figures['rtf_min']:.0f}x, median "
            f"{figures['rtf_median']:.0f}x faster than real time\n"
            f"  from the hover:    optimize landed {figures['optimised']}/{n}, mpc landed and "
            f"held {figures['looped']}/{n}\n"
            f"  optimize wall      median {figures['optimise_wall_median']:.2f} s per case "
            "(Gauss-Newton, verified on the scene's own model)\n"
            f"  mpc real time      min {figures['looped_rtf_min']:.0f}x, median "
            f"{figures['looped_rtf_median']:.0f}x faster than real time; compensation median "
            f"{figures['looped_ratio_median']:.1f} % (in a sea state)\n"
            f"  DNV-RP-H103        slack criterion failed in {figures['slack_failures']} of "
            f"{figures['dnv_runs']} landing runs (least top tension "
            f"{figures['static_share_min']:.0%} of static); dynamic amplification at most "
            f"{figures['amplification_max']:.3g}\n"
            f"  elastic rope       {figures['elastic']}/{n} cases deep and heavy enough for "
            f"model.axial = auto to choose it (T0 {figures['elastic_periods']} s); "
            f"{figures['elastic_succeeded']}/{figures['elastic']} of them succeeded in every "
            "landing and the hold",
            flush=True,
        )
    return rows, figures
