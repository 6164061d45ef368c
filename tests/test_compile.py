"""Compiled mode: the C step equals the interpreted one, and a second build hits the cache."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp import compile as compile_module
from cable_ocp.integrate import rk4_step
from cable_ocp.model import CableModel
from cable_ocp.scene import load_scene


@pytest.fixture(scope="module")
def tiny_step(models_dir):
    scene = load_scene(models_dir / "small_tow.toml", {"model.elements": 2})
    model = CableModel.from_scene(scene)
    return model, rk4_step(model, 0.05)


def test_compiled_step_matches_and_is_cached(tiny_step, tmp_path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_CACHE", str(tmp_path))
    model, step = tiny_step
    description = f"{model.spec!r}|step=0.05"
    fast, first = compile_module.compiled(step, description, derivatives=True)
    assert not first.cache_hit and first.compile_time > 0
    again, second = compile_module.compiled(step, description, derivatives=True)
    assert second.cache_hit and second.compile_time == 0.0
    assert second.library == first.library
    rng = np.random.default_rng(0)
    x = rng.normal(size=model.state_size) * 0.1
    u = rng.normal(size=(15, 3))
    u[9] = 25.0
    reference = np.array(step(x, u))
    for f in (fast, again):
        assert np.allclose(np.array(f(x, u)), reference, rtol=1e-12, atol=1e-12)
    # The compiled first derivatives agree with the interpreted ones.
    import casadi as ca

    xs = ca.MX.sym("x", model.state_size)
    jac = [ca.Function("j", [xs], [ca.jacobian(f(xs, u), xs)]) for f in (step, fast)]
    assert np.allclose(np.array(jac[0](x)), np.array(jac[1](x)), rtol=1e-10, atol=1e-10)
    # Another description is another library.
    _, other = compile_module.compiled(step, description + "|other", derivatives=False)
    assert not other.cache_hit and other.library != first.library


def test_without_a_compiler_falls_back_to_interpreted(tiny_step, monkeypatch):
    monkeypatch.setattr(compile_module, "find_compiler", lambda: None)
    _, step = tiny_step
    with pytest.warns(RuntimeWarning, match="no C compiler"):
        function, report = compile_module.compiled(step, "x")
    assert function is step and not report.cache_hit


SECOND_PROCESS = """
from cable_ocp.compile import compiled
from cable_ocp.integrate import rk4_step
from cable_ocp.model import CableModel
from cable_ocp.scene import load_scene
scene = load_scene({scene!r}, {{"model.elements": 2, "hydrodynamics.drag_normal": {drag}}})
model = CableModel.from_scene(scene)
print(compiled(rk4_step(model, 0.05), "step", derivatives=False)[1].cache_hit)
"""


def test_a_second_process_loads_from_the_cache_and_a_changed_model_compiles(models_dir, tmp_path):
    """The key hashes the expression graph: the same model rebuilt elsewhere hits the cache."""
    import os
    import subprocess
    import sys

    def hit(drag: float) -> bool:
        code = SECOND_PROCESS.format(scene=str(models_dir / "small_tow.toml"), drag=drag)
        env = {**os.environ, "CABLE_OCP_CACHE": str(tmp_path)}
        out = subprocess.run(
            [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
        )
        return out.stdout.strip() == "True"

    assert not hit(1.0)  # first build compiles
    assert hit(1.0)  # a new process, the same model: loaded from the cache
    assert not hit(1.2)  # other physics, other code: compiled anew
