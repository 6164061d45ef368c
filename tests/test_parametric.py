"""One parametric model per structure: numbers as the input p, compiled once for many scenes."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.drive.drive import Drive
from cable_ocp.model import parametric
from cable_ocp.model.cable import CableModel, cached_model, spec_from_scene
from cable_ocp.model.parameters import parameter_names, parameter_values, structure_of
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.statics import rest_inputs

SMALL = {"model.elements": 6, "numerics.duration": 2.0}


def test_structure_keeps_switches_and_drops_numbers(models_dir):
    scene = load_scene(models_dir / "hanging.toml")
    spec = spec_from_scene(scene)
    current = spec_from_scene(scene.updated({"environment.current": [0.5, -0.2, 0.0]}))
    stiffer = spec_from_scene(scene.updated({"hydrodynamics.drag_normal": 2.0}))
    no_drag = spec_from_scene(scene.updated({"hydrodynamics.drag": False}))
    assert structure_of(spec) == structure_of(current) == structure_of(stiffer)
    assert structure_of(no_drag) != structure_of(spec)
    names = parameter_names(spec)
    assert len(names) == len(set(names)) == parameter_values(spec).size
    # The current is a parameter even in still water; a switched-off term is no parameter.
    assert "element.hydro.current[0]" in names
    assert "element.hydro.drag_normal" not in parameter_names(no_drag)
    assert dict(zip(names, parameter_values(current), strict=True))[
        "element.hydro.current[0]"
    ] == pytest.approx(0.5)


def test_scenes_of_one_structure_share_the_symbolic_model(models_dir):
    # A model cached by an earlier test may hold a structure since evicted from the smaller
    # structure cache (16 against 32 models): start from empty caches.
    cached_model.cache_clear()
    parametric.parametric_model.cache_clear()
    scene = load_scene(models_dir / "hanging.toml")
    still = CableModel.from_scene(scene)
    flowing = CableModel.from_scene(scene.updated({"environment.current": [0.0, 1.0, 0.0]}))
    assert flowing.parametric is still.parametric
    rng = np.random.default_rng(5)
    u = rest_inputs(Drive.from_scene(scene))
    x = rng.normal(size=still.state_size) * 0.1
    x[3 : still.state_size // 2 : still.dofs] += np.pi / 2
    shared = np.array(still.parametric.rhs(x, u, flowing.parameters))
    bound = np.array(flowing.rhs(x, u))
    # The bound Function folds the numbers in: the same arithmetic, so equal to rounding.
    np.testing.assert_allclose(bound, shared, rtol=1e-13, atol=1e-12)
    # ... and the current does act: the accelerations differ from still water's.
    assert np.abs(bound - np.array(still.rhs(x, u))).max() > 1e-3


def test_a_sweep_over_currents_compiles_once(models_dir, tmp_path, monkeypatch):
    """Three currents and two drag coefficients: one set of libraries, written by the first run."""
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    # Forget what this process compiled, so that the first run here compiles into tmp_path.
    cached_model.cache_clear()
    parametric.parametric_model.cache_clear()
    scene = load_scene(models_dir / "hanging.toml", SMALL)
    first = simulate(scene, compiled=True)
    libraries = sorted(tmp_path.glob("*.so"))
    assert libraries, "the first run compiled nothing"
    ends = [first.end[-1]]
    for overrides in (
        {"environment.current": [0.0, 0.5, 0.0]},
        {"environment.current": [0.3, 1.0, 0.0]},
        {"hydrodynamics.drag_normal": 1.6},
    ):
        run = simulate(scene.updated(overrides), compiled=True)
        ends.append(run.end[-1])
    assert sorted(tmp_path.glob("*.so")) == libraries
    assert parametric.parametric_model.cache_info().misses == 1
    # The runs did see their own numbers: the end trails downstream in each current.
    assert ends[1][1] > ends[0][1] + 1.0 and ends[2][1] > ends[1][1]


def test_flat_functions_are_built_on_first_use(models_dir):
    """The compiled structured path (5 DOF, n = 60) eliminates no flat Function's subexpressions."""
    overrides = {"model.elements": 60, "numerics.duration": 1.0}
    scene = load_scene(models_dir / "hanging.toml", overrides)
    fresh = parametric.ParametricModel(structure_of(spec_from_scene(scene)))
    built = {"rhs", "kkt_parts", "outputs", "energy", "_graph"} & set(vars(fresh))
    assert not built, f"built up front: {built}"
    model = CableModel.from_scene(scene)
    simulate(scene, compiled=True)
    eliminated = {"rhs", "kkt_parts", "outputs", "energy"} & set(vars(model.parametric))
    assert not eliminated, f"built by a compiled simulation: {eliminated}"


def test_outputs_before_elimination_are_the_same_numbers(models_dir):
    """Common-subexpression elimination merges equal nodes: the outputs agree to the last bit."""
    scene = load_scene(models_dir / "hanging.toml", SMALL)
    model = parametric.ParametricModel(structure_of(spec_from_scene(scene)))
    values = parameter_values(spec_from_scene(scene))
    rng = np.random.default_rng(8)
    u = rest_inputs(Drive.from_scene(scene))
    x = rng.normal(size=model.state_size) * 0.1
    x[3 : model.state_size // 2 : model.dofs] += np.pi / 2
    plain = model.output_values(x, u, values)
    assert "outputs" not in vars(model)
    eliminated = model.outputs(x=x, u=u, p=values)
    assert "outputs" in vars(model)
    for name, value in eliminated.items():
        np.testing.assert_array_equal(np.array(plain[name]), np.array(value), err_msg=name)
