"""The Euler-angle singularity: states with an element along +-y, rejected by the model."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import equilibrium


@dataclass(frozen=True)
class SingularCase:
    """What was tried with a singular state, and what the toolkit answered.

    Attributes
    ----------
    tried : str
        The scene, its ``n`` and the singular angle it started from.
    rejected : bool
        Whether the toolkit refused the run (it must).
    message : str
        Its error, type first, or that the run went ahead.
    """

    tried: str
    rejected: bool
    message: str


def singular_states(scene, element: int = 2) -> tuple[SingularCase, ...]:
    """Simulate from the scene's equilibrium with ``theta_element = +-pi/2`` (along +-y).

    Returns
    -------
    tuple of SingularCase
        One per sign; ``rejected`` is False if the run went ahead (it must not).
    """
    model = CableModel.from_scene(scene)
    x0 = equilibrium(model, Drive.from_scene(scene)).state
    cases = []
    for sign, name in ((1, "+"), (-1, "-")):
        x = x0.copy()
        x[model.state_names.index(f"theta_{element}")] = sign * np.pi / 2
        tried = (
            f"simulate {scene.name} (n = {model.spec.elements}) from its equilibrium with "
            f"theta_{element} = {name}pi/2 (element {element} along {name}y)"
        )
        try:
            simulate(scene, model=model, initial_state=x)
        except (ValueError, SimulationError) as error:
            cases.append(SingularCase(tried, True, f"{type(error).__name__}: {error}"))
        else:
            cases.append(SingularCase(tried, False, "no error: the run went ahead"))
    return tuple(cases)
