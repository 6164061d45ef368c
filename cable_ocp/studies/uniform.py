"""Scenes on the paper's uniform mesh for studies that keep the winch locked."""

from __future__ import annotations

from collections.abc import Sequence


def locked_uniform(scene, elements: Sequence[int], overrides: dict | None = None):
    """The scene (with ``overrides``) on the uniform mesh ``Delta = L / n`` for every n given.

    A locked winch needs none of the reach that the graded mesh keeps for it (``Scene.mesh``): the
    winch gets no haul-in (``winch.angle_min = 0``) and top-element bounds that admit ``L / 2n``
    for each ``n`` in ``elements``, so convergence in n is the paper's uniform refinement.
    """
    halves = [scene.cable.length / (2 * n) for n in elements]
    winch = {
        "winch.angle_min": 0.0,
        "winch.top_length_min": min(scene.winch.top_length_min, *halves),
    }
    if scene.winch.top_length_max is not None:
        winch["winch.top_length_max"] = max(scene.winch.top_length_max, *halves)
    return scene.updated({**(overrides or {}), **winch})
