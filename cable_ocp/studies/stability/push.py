"""The pushed scene of the step-limit and drift runs.

The ``end_force`` scene starts from a static equilibrium, so without a push a run would only
amplify rounding noise; its push is moved to ``t = 0`` (:data:`PUSH`), and ramped up over 1 s
for the Baumgarte drift (:data:`SHARP_PUSH`).
"""

from __future__ import annotations

from cable_ocp.studies.uniform import locked_uniform

# The end_force scene's push (10 kN along x ramped over 15 s, 5 kN sine along y) from t = 0.
PUSH = {"end.force_start": 0.0}
# The same push ramped up over 1 s: a violent start, for the Baumgarte drift.
SHARP_PUSH = {**PUSH, "end.force_ramp": 1.0}


def pushed_scene(scene, elements: int, torsion: bool, push: dict = PUSH):
    """The scene with ``elements``, ``torsion`` and a push (scene overrides, :data:`PUSH`).

    The winch is locked, on the uniform mesh of this ``n``.
    """
    return locked_uniform(
        scene, [elements], {**push, "model.elements": elements, "model.torsion": torsion}
    )
