"""Whether a scene's line can hang from its top in still water: the rules a scene is held to.

Every dynamic run starts from the hanging equilibrium, a chain whose bonds all pull. In still
water a rope of submerged weight ``w`` per metre (N/m, negative for a rope lighter than water),
``L`` long, with the net load ``P = (P_h, P_z)`` on its end (N: ``end.force`` plus the payload's
buoyancy less its weight, ``P_z`` up) hangs as a catenary whose force at ``s`` metres above the end
is ``(P_h, P_z - w s)``. So, in water:

1. A rope lighter than water (``w <= 0``) hangs only while the load at its end outweighs its
   buoyancy, ``-P_z > -w L``: otherwise its upper part floats up and pushes.
2. A rope denser than water with a buoyant end (``P_z > 0``) is refused where its end would lie
   above the sea surface: a floating load rises until its buoyancy is lost there, it cannot hang
   above it. The flexible line's end lies
   ``dz = (sqrt(P_h^2 + (w L - P_z)^2) - sqrt(P_h^2 + P_z^2)) / w`` below the top (for any ``P_h``;
   with the top at the surface that is ``P_z < w L / 2``). Below that limit a sideways pull
   (``end.force``'s horizontal part) makes a U-shaped catenary with every bond pulling, which is
   allowed.
3. Without a sideways pull the same buoyant end would fold the rope at zero tension ``P_z / w``
   above the end, a slack bight under the floating load: it can happen at sea, but it is not a
   hanging line, so it is refused too, with the least payload mass that hangs the line straight.

A payload heavier than the water it displaces on a rope denser than water always hangs. In air
nothing floats and the end may be pulled anywhere (the catenary scene pulls it up and sideways).
"""

from __future__ import annotations

import math

from cable_ocp.scene.rules import SceneError

# A buoyant end counts as one only above this share of the loads (a neutral payload's rounding).
NEUTRAL = 1e-9


def check_hanging(scene) -> None:
    """Raise :class:`SceneError` if the scene's line cannot hang in still water (module rules).

    Parameters
    ----------
    scene : Scene
        A scene whose sections are each valid.
    """
    environment, cable, end = scene.environment, scene.cable, scene.end
    if not environment.submerged:
        return
    g, water = environment.gravity, environment.water_density
    weight = (cable.density - water) * cable.cross_section_area * g  # w, N/m
    payload = end.payload
    payload_lift = -payload.weight_in(environment) if payload is not None else 0.0
    lift = payload_lift + end.force[2]  # P_z, N
    sideways = math.hypot(end.force[0], end.force[1])  # P_h, N
    length = cable.length
    if weight <= 0:
        _check_light_rope(scene, -weight * length / g, -lift / g)
        return
    scale = weight * length + abs(payload_lift) + abs(end.force[2]) + sideways
    if lift <= NEUTRAL * scale:
        return
    where = "end.payload" if payload is not None else "end.force"
    loads = _loads(scene, lift)
    top = scene.top.start[2]
    depth = _drop(weight, length, sideways, lift)
    if top - depth >= 0:
        least = _least_mass(scene, weight, sideways, lift, top)
        raise SceneError(
            where,
            f": the end would float: lifted by {lift:.4g} N ({loads}), on this rope "
            f"({weight:.4g} N/m submerged, {length:g} m) it would hang at z = "
            f"{top - depth:.4g} m, above the sea surface, where a load's buoyancy is lost "
            f"(rule: the end of a rope denser than water must hang below the surface). {least}",
        )
    if sideways == 0:
        mass = (water * payload.volume if payload is not None else 0.0) + end.force[2] / g
        raise SceneError(
            where,
            f": the end is lifted by {lift:.4g} N ({loads}) with no sideways pull (end.force[0], "
            f"end.force[1] = 0): a rope cannot push, so the line would fold {lift / weight:.4g} m "
            "above its end into a slack bight under the floating load, not hang from the top "
            "(rule: a buoyant end on a rope denser than water needs a sideways pull). Give "
            f"end.payload.mass >= {mass:.6g} kg (its displaced water plus end.force[2]/g), or "
            "end.force a horizontal part",
        )


def _loads(scene, lift: float) -> str:
    """The fields that make the end's lift, with their values."""
    payload, force = scene.end.payload, scene.end.force
    parts = []
    if payload is not None:
        parts.append(
            f"end.payload.volume = {payload.volume!r} m^3 with end.payload.mass = "
            f"{payload.mass!r} kg"
        )
    if force[2] != 0:
        parts.append(f"end.force[2] = {force[2]!r} N")
    return " and ".join(parts)


def _drop(weight: float, length: float, sideways: float, lift: float) -> float:
    """How far below the top the flexible line's end hangs (m; negative: above it)."""
    return (math.hypot(sideways, weight * length - lift) - math.hypot(sideways, lift)) / weight


def _least_mass(scene, weight: float, sideways: float, lift: float, top: float) -> str:
    """The advice: the payload mass that would put the end at the surface, or why none would."""
    from scipy.optimize import brentq

    g = scene.environment.gravity
    at_surface = lambda p: top - _drop(weight, scene.cable.length, sideways, p)  # noqa: E731
    if at_surface(0.0) >= 0:
        return (
            f"Even a neutral end hangs above the surface: top.start[2] = {top!r} m is too high "
            "for this line"
        )
    largest = brentq(at_surface, 0.0, lift)
    mass = scene.end.payload.mass if scene.end.payload is not None else 0.0
    return (
        f"The largest lift that keeps the end under water is {largest:.4g} N: give "
        f"end.payload.mass > {mass + (lift - largest) / g:.6g} kg, or a smaller volume"
    )


def _check_light_rope(scene, buoyancy: float, load: float) -> None:
    """Rule 1: a rope lighter than water (``buoyancy`` kg) needs ``load`` (kg) that outweighs it."""
    if load <= buoyancy:
        water = scene.environment.water_density
        raise SceneError(
            "cable.density",
            f" = {scene.cable.density!r} kg/m^3 is not denser than "
            f"environment.water_density = {water!r} kg/m^3: the rope's buoyancy "
            f"({buoyancy:.4g} kg) must be outweighed by the load at its end (end.payload mass "
            f"less its displaced water, less end.force[2]/g: {load:.4g} kg), or the rope "
            f"floats. Add a payload of more than {buoyancy - load:.4g} kg, or use a rope "
            "denser than water",
        )
