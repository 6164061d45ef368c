"""Validation cases that compare the model with independent references (CONVENTIONS.md §8)."""

from __future__ import annotations

import numbers
from dataclasses import dataclass, fields

import numpy as np

from cable_ocp.drive.drive import Drive
from cable_ocp.model.cable import CableModel
from cable_ocp.model.layout import INPUTS
from cable_ocp.scene.schema import ModelOptions
from cable_ocp.simulation.statics import equilibrium
from cable_ocp.studies.catenary import catenary_shape, relative_errors

MAX_ELEMENTS = next(
    f.metadata["spec"].le for f in fields(ModelOptions) if f.name == "elements"
)  # the scene's bound on model.elements


@dataclass(frozen=True)
class CatenaryCheck:
    """The statics check of the paper's §4.1 for one number of elements.

    Attributes
    ----------
    elements : int
        Number of elements n of the model.
    max_error_x, max_error_z : float
        ``eps_x^max``, ``eps_z^max`` (eq. 35-36) against the elastic catenary, as fractions.
    max_error_inextensible : float
        ``max(eps_x, eps_z)`` against the inextensible catenary, as a fraction.
    top_tension_error : float
        Relative error of the top tension against eq. 34c.
    tension_error : float
        Largest relative error of the bond tensions ``|lambda_1| .. |lambda_{n+1}|`` against
        ``T(s)`` of eq. 34c at their joints ``A_1 .. A_{n+1}`` (the top included).
    joints : array (2, n+2), m
        x and z of the model's joints.
    arc_length : array (n+2,), m
        Arc length of each joint from the pinned top.
    """

    elements: int
    max_error_x: float
    max_error_z: float
    max_error_inextensible: float
    top_tension_error: float
    tension_error: float
    joints: np.ndarray
    arc_length: np.ndarray


def catenary_check(scene, elements: int | None = None) -> CatenaryCheck:
    """Equilibrium of the catenary scene against the analytic catenary (eq. 34-36).

    The top is pinned at the origin and the end carries ``(H, 0, V)``; joints ``A_0 .. A_{n-1}``
    are compared (the paper's ``i = 1..n``, which leaves out the joint next to the pin).

    Parameters
    ----------
    scene : Scene
        The catenary scene (or one like it: pinned top, end force, no water).
    elements : int, optional
        Number of elements n, 1 to 1000 (None: the scene's ``model.elements``).

    Raises
    ------
    ValueError
        If ``elements`` is not an integer from 1 to 1000.
    """
    if elements is not None and (
        isinstance(elements, bool) or not isinstance(elements, numbers.Integral)
        or not 1 <= elements <= MAX_ELEMENTS
    ):  # fmt: skip
        raise ValueError(f"elements = {elements!r}: must be an integer from 1 to {MAX_ELEMENTS}")
    model = CableModel.from_scene(scene, elements)
    drive = Drive.from_scene(scene, elements=model.spec.elements)
    state = equilibrium(model, drive).state
    u = drive.inputs(np.zeros(1))[:, 0]
    outputs = model.output_values(state, u)
    joints = outputs["joints"] - u[INPUTS.top, None]
    lengths = np.array(model.element_lengths(model.spec.top_length))
    length = scene.cable.length
    arc = length - np.concatenate([[0.0], np.cumsum(lengths)])
    force_x, force_y, force_z = u[INPUTS.end_force]
    horizontal, vertical = float(np.hypot(force_x, force_y)), float(force_z)
    weight = scene.cable.mass_per_length * scene.environment.gravity
    stiffness = scene.cable.youngs_modulus * scene.cable.cross_section_area
    compared = slice(0, model.element_count - 1)
    x_el, z_el, tension = catenary_shape(arc, length, weight, horizontal, vertical, stiffness)
    x_in, z_in, _ = catenary_shape(arc, length, weight, horizontal, vertical)
    planar_x = np.hypot(joints[0], joints[1])
    errors = {
        "x": relative_errors(planar_x[compared], x_el[compared]).max(),
        "z": relative_errors(joints[2][compared], z_el[compared]).max(),
        "inextensible": max(
            relative_errors(planar_x[compared], x_in[compared]).max(),
            relative_errors(joints[2][compared], z_in[compared]).max(),
        ),
    }
    tensions = outputs["tensions"].ravel()  # at A_1 .. A_{n+1}
    top_tension = float(tensions[-1])
    return CatenaryCheck(
        elements=model.spec.elements,
        max_error_x=float(errors["x"]),
        max_error_z=float(errors["z"]),
        max_error_inextensible=float(errors["inextensible"]),
        top_tension_error=abs(top_tension / tension[-1] - 1),
        tension_error=float(relative_errors(tensions, tension[1:]).max()),
        joints=np.vstack([planar_x, joints[2]]),
        arc_length=arc,
    )
