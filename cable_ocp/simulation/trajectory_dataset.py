"""A :class:`~cable_ocp.simulation.trajectory.Trajectory` as a labelled ``xarray.Dataset``.

The state and input vectors are split into named quantities by their layout (CONVENTIONS.md §3):
``position`` and ``velocity`` of each element's lower end ``A_i`` over (time, element,
component), its ``euler_angle`` and ``euler_angle_rate`` over (time, element, angle) with the angles
``psi``, ``theta`` (and ``phi`` with torsion); the inputs as ``top_position``, ``top_velocity``,
``top_acceleration``, ``top_length`` (and its rate and acceleration) and ``end_force``. The joints
``A_0`` (the end E) .. ``A_{n+1}`` (the top) are ``joint_position`` over (time, joint,
component); bond tensions are ``tension`` over (time, element), element i's bond at its upper end
``A_{i+1}``. An elastic rope's axial strain and its rate (:mod:`cable_ocp.model.axial`) are
``axial_strain`` and ``axial_strain_rate`` over time. Every variable has CF ``units`` and
``long_name``; :func:`from_dataset` puts the vectors back together exactly.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from cable_ocp.model.layout import INPUT_SIZE, INPUTS
from cable_ocp.result_files.dataset import COMPONENT, to_dataset
from cable_ocp.result_files.dataset import from_dataset as labelled_fields
from cable_ocp.result_files.units import DIMENSIONLESS, describe
from cable_ocp.scene.records import check_field

KIND = "Trajectory"
ANGLES = ("psi", "theta", "phi")  # the Euler angles of an element, in state order
# Inputs by name (the layout of cable_ocp.model.layout.INPUTS): (index, dims, units, long name).
INPUT_VARIABLES = {
    "top_position": (INPUTS.top, "m", "position of the top point A_{n+1}"),
    "top_velocity": (INPUTS.top_velocity, "m s-1", "velocity of the top point"),
    "top_acceleration": (INPUTS.top_acceleration, "m s-2", "acceleration of the top point"),
    "top_length": (INPUTS.top_length, "m", "length of the top element, set by the winch"),
    "top_length_rate": (INPUTS.top_length_rate, "m s-1", "rate of the top element's length"),
    "top_length_acceleration": (
        INPUTS.top_length_acceleration, "m s-2", "acceleration of the top element's length"
    ),
    "end_force": (INPUTS.end_force, "N", "external force at the end E"),
}  # fmt: skip
STATE_VARIABLES = {  # (derivative?, coordinates, units, long name)
    "position": (False, "component", "m", "position of the lower end A_i of element i"),
    "velocity": (True, "component", "m s-1", "velocity of the lower end A_i of element i"),
    "euler_angle": (False, "angle", "rad", "Euler angles of element i (psi in the x-z plane, theta "
              "out of it, phi the twist)"),
    "euler_angle_rate": (True, "angle", "rad s-1", "rates of the Euler angles of element i"),
}  # fmt: skip
# Fields kept as the named variables above, not as they are.
SPLIT = ("states", "inputs", "joints", "tensions", "state_names")


STRAIN_VARIABLES = {  # an elastic rope's: (units, long name)
    "axial_strain": (DIMENSIONLESS, "uniform axial strain of the line (elastic rope)"),
    "axial_strain_rate": ("s-1", "rate of the line's axial strain"),
}


def state_names(elements: int, dofs: int, axial: int = 0) -> list[str]:
    """Names of the state entries, ``x_0 .. theta_n`` then ``d_x_0 ..`` (CONVENTIONS.md §3).

    ``axial`` (1 for an elastic rope) adds ``strain`` after the coordinates (and ``d_strain``).
    """
    coords = [*COMPONENT, *ANGLES][:dofs]
    names = [f"{c}_{i}" for i in range(elements) for c in coords] + ["strain"] * axial
    return names + [f"d_{name}" for name in names]


def to_xarray(trajectory) -> xr.Dataset:
    """The trajectory as a Dataset (see the module docstring).

    Raises
    ------
    ValueError
        If ``state_names`` are not the model's layout (the states cannot then be named).
    """
    time, states = trajectory.time, trajectory.states
    elements = trajectory.tensions.shape[1]
    dofs = states.shape[1] // (2 * elements)
    axial = (states.shape[1] - 2 * elements * dofs) // 2
    if trajectory.state_names != state_names(elements, dofs, axial):
        raise ValueError(
            f"state_names {trajectory.state_names[:3]}...: not the layout of {elements} elements "
            f"with {dofs} DOF (x_0, y_0, ..., d_x_0, ...), so the states cannot be labelled"
        )
    half = states.shape[1] // 2
    rigid = np.concatenate([states[:, : half - axial], states[:, half : 2 * half - axial]], 1)
    blocks = rigid.reshape(time.size, 2, elements, dofs)
    angles = ANGLES[: dofs - 3]
    variables = {}
    for name, (rate, coordinate, units, long_name) in STATE_VARIABLES.items():
        part = slice(0, 3) if coordinate == "component" else slice(3, dofs)
        variables[name] = (("time", "element", coordinate), blocks[:, int(rate), :, part],
                           units, long_name)  # fmt: skip
    for name, (index, units, long_name) in INPUT_VARIABLES.items():
        dims = ("time", "component") if isinstance(index, slice) else ("time",)
        variables[name] = (dims, trajectory.inputs[:, index], units, long_name)
    for k, (name, (units, long_name)) in enumerate(STRAIN_VARIABLES.items()):
        if axial:
            variables[name] = (("time",), states[:, (k + 1) * half - 1], units, long_name)
    joints = trajectory.joints.transpose(0, 2, 1)
    joint_name = "position of joint A_j (A_0 the end E, A_{n+1} the top)"
    variables["joint_position"] = (("time", "joint", "component"), joints, "m", joint_name)
    tension_name = "bond force at the upper end A_{i+1} of element i"
    variables["tension"] = (("time", "element"), trajectory.tensions, "N", tension_name)
    dataset = to_dataset(
        trajectory,
        KIND,
        {"time": ("time",), "winch_angle": ("time",), "clearance_error": ("time",)},
        skip=SPLIT,
    )
    for name, (dims, data, units, long_name) in variables.items():
        dataset[name] = describe(xr.Variable(dims, data), units, long_name)
    labels = {
        "element": (np.arange(elements), "element i (0 carries the end E, n hangs from the top)"),
        "joint": (np.arange(elements + 1), "joint A_j (0 the end E, n+1 the top)"),
        "component": (list(COMPONENT), "component in the world frame (z up)"),
        "angle": (list(angles), "Euler angle (CONVENTIONS.md §3)"),
    }
    for dim, (values, long_name) in labels.items():
        dataset.coords[dim] = describe(xr.Variable(dim, values), DIMENSIONLESS, long_name)
    dataset["time"].attrs.update(units="s", long_name="time", standard_name="time")
    return dataset


def _dims(name: str) -> tuple[str, ...]:
    """The dimensions a state, input, joint or tension variable lies over (in any order)."""
    if name in STATE_VARIABLES:
        return ("time", "element", STATE_VARIABLES[name][1])
    if name in INPUT_VARIABLES:
        return ("time", "component") if isinstance(INPUT_VARIABLES[name][0], slice) else ("time",)
    return {"joint_position": ("time", "joint", "component"), "tension": ("time", "element")}[name]


def _check_dims(dataset: xr.Dataset) -> None:
    """ValueError naming the variable unless each lies over its dimensions, of fitting sizes."""
    for name in (*STATE_VARIABLES, *INPUT_VARIABLES, "joint_position", "tension"):
        if set(dataset[name].dims) != set(_dims(name)):
            raise ValueError(f"{name} over {dataset[name].dims}: expected {_dims(name)}")
    sizes = dataset.sizes
    if sizes["component"] != len(COMPONENT):
        raise ValueError(f"component of size {sizes['component']}: expected {len(COMPONENT)}")
    if sizes["angle"] not in (2, 3) or sizes["joint"] != sizes["element"] + 1:
        raise ValueError(
            f"angle of size {sizes['angle']} (expected 2 or 3) and joint of size "
            f"{sizes['joint']} (expected element + 1 = {sizes['element'] + 1})"
        )


def from_dataset(dataset: xr.Dataset, cls: type) -> dict:
    """The fields of a trajectory of class ``cls`` (``Trajectory``) from its Dataset.

    The fields stored as they are (``time``, ``omega``, ``scene_name``, ...) are read and
    checked against their types by :func:`cable_ocp.result_files.dataset.from_dataset`; the state,
    input, joint and tension variables must be arrays of numbers.

    Raises
    ------
    ValueError, KeyError
        A variable is missing or does not fit.
    """
    values = labelled_fields(cls, dataset, skip=SPLIT)
    for name in (*STATE_VARIABLES, *INPUT_VARIABLES, "joint_position", "tension"):
        if name not in dataset.variables:
            raise ValueError(f"missing field(s) {name}")
        check_field(name, dataset[name].values, np.ndarray)
    time = values["time"]
    _check_dims(dataset)
    elements, angles = dataset.sizes["element"], dataset.sizes["angle"]
    dofs = 3 + angles
    blocks = np.empty((time.size, 2, elements, dofs))
    for name, (rate, coordinate, _, _) in STATE_VARIABLES.items():
        part = slice(0, 3) if coordinate == "component" else slice(3, dofs)
        blocks[:, int(rate), :, part] = dataset[name].transpose("time", "element", coordinate)
    inputs = np.empty((time.size, INPUT_SIZE))
    for name, (index, _, _) in INPUT_VARIABLES.items():
        inputs[:, index] = dataset[name].values
    joints = dataset["joint_position"].transpose("time", "joint", "component").values
    states = blocks.reshape(time.size, 2, -1)
    axial = int("axial_strain" in dataset.variables)
    if axial:
        strain = [dataset[name].values.reshape(time.size, 1) for name in STRAIN_VARIABLES]
        states = np.concatenate([states[:, 0], strain[0], states[:, 1], strain[1]], 1)
    return {
        **values,
        "states": states.reshape(time.size, -1),
        "inputs": inputs,
        "joints": joints.transpose(0, 2, 1),
        "tensions": dataset["tension"].transpose("time", "element").values,
        "state_names": state_names(elements, dofs, axial),
    }
