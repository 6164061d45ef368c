"""Random scenes drawn from the whole scene space: any rope, payload, tow, sea, seabed and winch.

The robustness benchmark's first family (:mod:`cable_ocp.studies.robustness`; the variants of
``paper_hill`` are its second). Each field an offshore user sets is drawn from a range that such
a user meets (:class:`SpaceRanges` states each range and why); the numbers the user leaves to the
toolkit (the optimiser's and the controller's models) are left unset, so that the benchmark
checks the defaults derived from the scene (:mod:`cable_ocp.control.defaults`).

Three fields depend on the scene drawn, as a user would set them after a first look:

- ``numerics.constraint_tolerance``: paper_hill's 0.1 mm, or its share of the segment length
  on longer segments (:data:`BOND_SHARE`);
- ``numerics.step`` of the scene's own model: the largest of :data:`STEP_LADDER` within a
  quarter of the model's RK4 limit along its locked run (a user reads the limit off
  ``cable-ocp study stability``; the benchmark takes it from
  :func:`cable_ocp.control.defaults.run_limit`);
- the hills and the grid, placed along the end's path in the locked run (a survey line follows
  the seabed feature it inspects), the grid covering that path with a margin.

A case is a dict of scene overrides of ``paper_hill`` plus :data:`PLACED`: what is placed after
the locked run (hills as fractions of the path, the grid's relief).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.control.defaults import run_limit
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import seabed_height
from cable_ocp.studies.random_site import write_site

PLACED = "placed"  # key of a case's overrides: the hills and grid placed along the locked path
# Steps (s) a user would give the scene's model: each divides 1 s, so any whole-second duration.
STEP_LADDER = (0.1, 0.05, 0.025, 0.02, 0.01, 0.005, 0.0025, 0.002, 0.001)
# Of the full model's RK4 limit along the locked run: at 0.5, heaving plants (the winch paying
# out the heave) left 1.4e-4 m in their bonds at h = 0.1 s; at 0.05 s they held.
STEP_SHARE = 0.25
GRID_MARGIN = 80.0  # m around the locked path
# The bond tolerance a user gives: paper_hill's 0.1 mm (a moving winch needs more than the
# schema's 1e-6 m, as paper_hill says), or its share of the segment length on longer segments.
BOND_TOLERANCE, BOND_SHARE = 1e-4, 1e-4 / 20.0


@dataclass(frozen=True)
class SpaceRanges:
    """Where the whole-space scenes are drawn from (uniformly unless stated).

    Attributes
    ----------
    diameter : (float, float), m
        20-80 mm: instrument tows and umbilicals to lift wires.
    steel_density, synthetic_density : (float, float), kg/m^3
        Steel wire 6000-7850 (with lubricant and voids); synthetic and umbilical 1500-3000.
    synthetic_share : float
        Share of synthetic ropes.
    buoyant_share : float
        Share of near-neutral ropes (HMPE, 950-1000 kg/m^3), always with a payload that sinks
        them (deep lowering's ropes).
    length : (float, float), m
        150-600 m of line out.
    payload_share : float
        Share with a payload at the end.
    payload_mass : (float, float), kg
        0.2-5 t: towfish, frames, depressors.
    payload_density : (float, float), kg/m^3
        Of the payload's volume (steel frames with buoyancy: 2500-7800).
    payload_drag_area : (float, float), m^2
        Its drag coefficient times its area across the flow, 0.2-3 m^2.
    surge_speed : (float, float), m/s
        Tows up to 1.8 m/s (3.5 kn).
    sway_speed : (float, float), m/s
        Amplitude of the vessel's lateral speed, up to 0.4 m/s.
    ramp_time : (float, float), s
        Time over which the tow reaches its surge speed, 10-40 s.
    duration : (int, int), s
        Whole seconds, 60-600: multiples of nothing in particular.
    elements : (int, int)
        n, 5 to 30.
    current_share : float
        Share with a sheared current profile.
    surface_current : (float, float), m/s
        Its speed at the surface, up to 0.8 m/s; it falls to 10-60 % at the cable's depth.
    heave_share, sea_share : float
        Shares with a sinusoidal heave and with a JONSWAP sea state (with an RAO table).
    heave_amplitude : (float, float), m
        Of the sinusoidal heave, 0.3-1 m.
    heave_period : (float, float), s
        Of the sinusoidal heave, 7-12 s.
    significant_height : (float, float), m
        Hs 1-4 m: workable to marginal sea states for a tow.
    peak_period : (float, float), s
        T_p of the sea state, 6-12 s.
    drum_radius : (float, float), m
        0.3-1.5 m.
    haul_in, pay_out : (float, float), m
        The winch's reach in line each way (its angle range follows from the drum).
    rate_share : float
        Share with rate and acceleration limits.
    line_speed : (float, float), m/s
        The winch's top line speed ``r_D phi'_max``.
    line_acceleration : (float, float), m/s^2
        The winch's top line acceleration ``r_D phi''_max``.
    clearance : (float, float), m
        The end's initial height above the seabed, delta.
    hills : (int, int)
        How many Gaussian hills are placed along the locked run's path (0-3).
    hill_height : (float, float), m
        Each hill's height k.
    hill_width : (float, float), m
        Each hill's widths along x and y, drawn separately.
    grid_share : float
        Share on a random bathymetry grid.
    grid_slope : (float, float)
        Its slope along the tow, 10-20 %, rising or falling.
    """

    diameter: tuple[float, float] = (0.02, 0.08)
    steel_density: tuple[float, float] = (6000.0, 7850.0)
    synthetic_density: tuple[float, float] = (1500.0, 3000.0)
    synthetic_share: float = 0.4
    buoyant_share: float = 0.1
    length: tuple[float, float] = (150.0, 600.0)
    payload_share: float = 0.5
    payload_mass: tuple[float, float] = (200.0, 5000.0)
    payload_density: tuple[float, float] = (2500.0, 7800.0)
    payload_drag_area: tuple[float, float] = (0.2, 3.0)
    surge_speed: tuple[float, float] = (0.3, 1.8)
    sway_speed: tuple[float, float] = (0.0, 0.4)
    ramp_time: tuple[float, float] = (10.0, 40.0)
    duration: tuple[int, int] = (60, 600)
    elements: tuple[int, int] = (5, 30)
    current_share: float = 0.5
    surface_current: tuple[float, float] = (0.1, 0.8)
    heave_share: float = 0.25
    sea_share: float = 0.3
    heave_amplitude: tuple[float, float] = (0.3, 1.0)
    heave_period: tuple[float, float] = (7.0, 12.0)
    significant_height: tuple[float, float] = (1.0, 4.0)
    peak_period: tuple[float, float] = (6.0, 12.0)
    drum_radius: tuple[float, float] = (0.3, 1.5)
    haul_in: tuple[float, float] = (5.0, 25.0)
    pay_out: tuple[float, float] = (5.0, 25.0)
    rate_share: float = 0.5
    line_speed: tuple[float, float] = (0.5, 2.0)
    line_acceleration: tuple[float, float] = (0.2, 1.0)
    clearance: tuple[float, float] = (3.0, 12.0)
    hills: tuple[int, int] = (0, 3)
    hill_height: tuple[float, float] = (2.0, 12.0)
    hill_width: tuple[float, float] = (15.0, 40.0)
    grid_share: float = 0.3
    grid_slope: tuple[float, float] = (0.1, 0.2)


def rounded_uniform(rng: np.random.Generator, digits: int) -> Callable[..., float]:
    """The draws of a random case: ``uniform(bounds, digits=digits)`` from ``rng``, rounded.

    Parameters
    ----------
    rng : numpy.random.Generator
        The stream every draw of the case comes from, in order.
    digits : int
        Decimals kept when a draw names none (a scene file's readable figures).
    """

    def uniform(bounds: tuple[float, float], places: int = digits) -> float:
        return round(float(rng.uniform(*bounds)), places)

    return uniform


def space_case(rng: np.random.Generator, ranges: SpaceRanges = SpaceRanges()) -> dict:
    """Scene overrides of ``paper_hill`` for one whole-space case (see the module docstring).

    Every number is drawn whether used or not, so that each case takes as many draws.
    """
    uniform = rounded_uniform(rng, 3)
    kind = rng.uniform()
    diameter = uniform(ranges.diameter, 3)
    steel, synthetic = uniform(ranges.steel_density, 0), uniform(ranges.synthetic_density, 0)
    buoyant = uniform((950.0, 1000.0), 0)
    length = uniform(ranges.length, 0)
    payload = {
        "mass": uniform(ranges.payload_mass, 0),
        "density": uniform(ranges.payload_density, 0),
        "drag_area": uniform(ranges.payload_drag_area, 2),
    }
    has_payload = rng.uniform() < ranges.payload_share
    if kind < ranges.buoyant_share:
        density, modulus, has_payload = buoyant, 2e10, True
        payload["mass"] = max(payload["mass"], 1000.0)
    elif kind < ranges.buoyant_share + ranges.synthetic_share:
        density, modulus = synthetic, 3e10
    else:
        density, modulus = steel, 1e11
    radius = uniform(ranges.drum_radius, 2)
    haul_in, pay_out = uniform(ranges.haul_in, 1), uniform(ranges.pay_out, 1)
    line_speed, line_acceleration = uniform(ranges.line_speed, 2), uniform(ranges.line_acceleration)
    overrides = {
        "cable.diameter": diameter,
        "cable.density": density,
        "cable.length": length,
        "cable.youngs_modulus": modulus,
        "cable.shear_modulus": modulus / 2.6,
        "model.elements": int(rng.integers(ranges.elements[0], ranges.elements[1] + 1)),
        "numerics.duration": float(rng.integers(ranges.duration[0], ranges.duration[1] + 1)),
        "top.tow.surge_speed": uniform(ranges.surge_speed, 2),
        "top.tow.sway_speed": uniform(ranges.sway_speed, 2),
        "top.tow.ramp_time": uniform(ranges.ramp_time, 0),
        "seabed.clearance": uniform(ranges.clearance, 1),
        "winch.drum_radius": radius,
        "winch.angle_min": -round(haul_in / radius, 2),
        "winch.angle_max": round(pay_out / radius, 2),
    }
    overrides["top.tow.sway_period"] = overrides["numerics.duration"]
    if has_payload:
        overrides["end.payload"] = {
            "mass": payload["mass"],
            "volume": round(payload["mass"] / payload["density"], 3),
            "drag_area": payload["drag_area"],
        }
    if rng.uniform() < ranges.rate_share:
        overrides["winch.rate_max"] = round(line_speed / radius, 3)
        overrides["winch.acceleration_max"] = round(line_acceleration / radius, 3)
    surface = uniform(ranges.surface_current, 2)
    heading, share = uniform((0.0, 2 * math.pi)), uniform((0.1, 0.6), 2)
    if rng.uniform() < ranges.current_share:
        u, v = surface * math.cos(heading), surface * math.sin(heading)
        overrides["environment.current_profile"] = [
            {"z": 0.0, "u": round(u, 3), "v": round(v, 3)},
            {"z": -round(length / 3), "u": round(u * (1 + share) / 2, 3),
             "v": round(v * (1 + share) / 2, 3)},
            {"z": -round(length), "u": round(u * share, 3), "v": round(v * share, 3)},
        ]  # fmt: skip
    heave = {
        "amplitude": uniform(ranges.heave_amplitude, 2),
        "period": uniform(ranges.heave_period, 1),
    }
    sea = {
        "significant_height": uniform(ranges.significant_height, 2),
        "peak_period": uniform(ranges.peak_period, 1),
        "seed": int(rng.integers(2**31)),
        "winch_offset": [round(float(v), 1) for v in rng.uniform(-20.0, 20.0, 3)],
        "rao": _rao(rng),
    }
    waves = {}
    if rng.uniform() < ranges.heave_share:
        waves.update(heave)
    if rng.uniform() < ranges.sea_share:
        waves["sea_state"] = sea
    if waves:
        overrides["top.heave"] = waves
    hills = [
        {
            "along": uniform((0.2, 0.9), 2),
            "across": uniform((-20.0, 20.0), 0),
            "height": uniform(ranges.hill_height, 1),
            "width_x": uniform(ranges.hill_width, 0),
            "width_y": uniform(ranges.hill_width, 0),
        }
        for _ in range(int(rng.integers(ranges.hills[0], ranges.hills[1] + 1)))
    ]
    relief = {
        "slope": uniform(ranges.grid_slope, 3) * (1 if rng.uniform() < 0.5 else -1),
        "ridge_height": uniform((1.0, 6.0), 1),
        "ridge_angle": uniform((-0.6, 0.6)),
        "ridge_width": uniform((10.0, 25.0), 0),
        "ridge_along": uniform((0.3, 0.8), 2),
        "waves": uniform((0.0, 0.5)),
        "wavelength": uniform((20.0, 40.0), 0),
        "roughness": uniform((0.05, 0.3)),
        "seed": int(rng.integers(2**31)),
    }
    placed = {"hills": hills}
    if rng.uniform() < ranges.grid_share:
        placed["grid"] = relief
    overrides[PLACED] = placed
    return overrides


def _rao(rng: np.random.Generator) -> list[dict]:
    """A vessel's RAO table: heave near 1 m/m at long waves falling off, small roll and pitch."""
    frequencies = (0.3, 0.6, 0.9, 1.3, 2.0)
    heave = np.sort(rng.uniform(0.05, 1.0, len(frequencies)))[::-1]
    return [
        {
            "frequency": w,
            "heave": round(float(h), 3),
            "heave_phase": round(float(rng.uniform(-0.3, 0.3)), 2),
            "roll": round(float(rng.uniform(0.0, 0.03)), 4),
            "pitch": round(float(rng.uniform(0.0, 0.015)), 4),
        }
        for w, h in zip(frequencies, heave, strict=True)
    ]


def space_cases(count: int, seed: int, ranges: SpaceRanges = SpaceRanges()) -> list[dict]:
    """``count`` whole-space cases drawn with the seed ``seed``."""
    rng = np.random.default_rng([seed, 23])
    return [space_case(rng, ranges) for _ in range(count)]


def scene_step(scene) -> float:
    """The scene's own step as a careful user sets it (module docstring), s."""
    limit, _ = run_limit(scene, scene.model.elements, scene.numerics.duration)
    fitting = [h for h in STEP_LADDER if h <= STEP_SHARE * limit]
    return fitting[0] if fitting else STEP_LADDER[-1]


def space_scene(overrides: dict, folder: Path):
    """The scene of a whole-space case, its step set and its hills and grid placed.

    The grid (if any) is written into ``folder``. Raises what loading or the locked run raise.
    """
    placed = overrides.get(PLACED, {})
    given = {k: v for k, v in overrides.items() if k != PLACED}
    given["seabed.hills"] = []
    given.setdefault("numerics.step", 0.001)  # any valid step: the user's is set below
    scene = load_scene(scene_path("paper_hill"), given)
    tolerance = max(BOND_TOLERANCE, float(f"{BOND_SHARE * scene.segment_length:.2g}"))
    scene = scene.updated(
        {"numerics.step": scene_step(scene), "numerics.constraint_tolerance": tolerance}
    )
    locked = simulate(scene, compiled=True)
    path, start = locked.end[:, :2], locked.end[0]
    hills = []
    for hill in placed.get("hills", []):
        k = min(int(hill["along"] * (len(path) - 1)), len(path) - 1)
        hills.append(
            {
                "height": hill["height"],
                "x0": round(float(path[k, 0]), 1),
                "y0": round(float(path[k, 1] + hill["across"]), 1),
                "width_x": hill["width_x"],
                "width_y": hill["width_y"],
            }
        )
    scene = scene.updated({"seabed.hills": hills})
    relief = placed.get("grid")
    if relief is None:
        return scene
    hill = float(seabed_height(scene.seabed.hills, start[0], start[1]))
    base = float(start[2]) - scene.seabed.clearance - hill
    along = relief["ridge_along"]
    ridge_x = float(start[0] + along * (path[-1, 0] - start[0]))
    site = {**relief, "ridge_x": ridge_x}
    x_range = (float(path[:, 0].min()) - GRID_MARGIN, float(path[:, 0].max()) + GRID_MARGIN)
    y_range = (float(path[:, 1].min()) - GRID_MARGIN, float(path[:, 1].max()) + GRID_MARGIN)
    file = write_site(folder / "site.nc", site, base, x_range, y_range, float(start[0]))
    return scene.updated({"seabed.grid": {"file": str(file)}})
