"""Static equilibria against analytic references: the catenary (paper §4.1), the hanging cable."""

from __future__ import annotations

import numpy as np
import pytest

from cable_ocp.catenary import catenary_shape, relative_errors
from cable_ocp.drive import Drive
from cable_ocp.layout import INPUTS
from cable_ocp.model import CableModel
from cable_ocp.scene import load_scene
from cable_ocp.statics import equilibrium, rest_inputs


class CatenaryCase:
    """The catenary scene at one n: the equilibrium beside the analytic catenary (eq. 34)."""

    def __init__(self, models_dir, elements: int):
        scene = load_scene(models_dir / "catenary.toml", {"model.elements": elements})
        self.scene, self.n = scene, elements
        self.model = CableModel.from_scene(scene)
        drive = Drive.from_scene(scene)
        self.x = equilibrium(self.model, drive)
        self.u = rest_inputs(drive)
        out = self.model.outputs(self.x, self.u)
        self.joints = np.array(out[0])  # 3 x (n+2): A_0 (free end) .. A_n, A_{n+1} = top
        self.tensions = np.array(out[5]).ravel()  # |lambda_1| .. |lambda_{n+1}|, at A_1 .. A_{n+1}
        cable = scene.cable
        self.length = cable.length
        self.area = cable.cross_section_area
        self.weight = cable.density * self.area * scene.environment.gravity  # w = rho A g
        self.horizontal, _, self.vertical = scene.end.force
        lengths = np.array(
            [float(v) for v in self.model.element_lengths(self.u[INPUTS.top_length])]
        )
        # Unstretched arc length from the pinned top: s(A_j) = L - sum_{k<j} l_k, j = 0..n+1.
        self.arc = self.length - np.concatenate([[0.0], np.cumsum(lengths)])

    def analytic(self, axial_stiffness: float):
        return catenary_shape(
            self.arc, self.length, self.weight, self.horizontal, self.vertical, axial_stiffness
        )

    def errors(self, axial_stiffness: float) -> tuple[float, float]:
        """Eq. 35-36: max relative errors (%) in x and z over A_0..A_{n-1}.

        The top (s = 0, where x = z = 0) and the joint Delta/2 below it are left out, as the paper's
        i = 1..n leaves out s_0.
        """
        x, z, _ = self.analytic(axial_stiffness)
        n = self.n
        eps_x = 100 * relative_errors(self.joints[0, :n], x[:n]).max()
        eps_z = 100 * relative_errors(self.joints[2, :n], z[:n]).max()
        return float(eps_x), float(eps_z)


@pytest.fixture(scope="module")
def catenary_case(models_dir):
    cache = {}

    def get(elements: int) -> CatenaryCase:
        if elements not in cache:
            cache[elements] = CatenaryCase(models_dir, elements)
        return cache[elements]

    return get


def test_catenary_scene_is_the_papers(catenary_case):
    case = catenary_case(15)
    assert case.n == 15
    assert case.area == pytest.approx(0.07**2 / 4, rel=1e-15)
    assert (case.horizontal, case.vertical) == (20000.0, 50000.0)
    assert not case.scene.environment.submerged
    np.testing.assert_array_equal(case.joints[:, -1], 0.0)  # top pinned at the origin
    assert case.arc[-1] == pytest.approx(0.0, abs=1e-9)
    assert case.arc[0] == case.length


def test_catenary_elastic_error_n15(catenary_case, validation):
    """eps_x, eps_z <= 0.1 % against the elastic catenary, EA = E A (paper: < 0.5 %).

    Measured 0.042 % and 0.032 %.
    """
    case = catenary_case(15)
    axial = case.scene.cable.youngs_modulus * case.area
    eps_x, eps_z = case.errors(axial)
    validation("catenary statics, n = 15 (paper 4.1)", "analytic", "elastic catenary eq. 34",
               "eps_x, eps_z", f"{eps_x:.3f} %, {eps_z:.3f} %",
               "<= 0.1 % (paper: < 0.5 %)")  # fmt: skip
    assert eps_x <= 0.1, eps_x
    assert eps_z <= 0.1, eps_z


def test_catenary_inextensible_error_converges_second_order(catenary_case, validation):
    """max(eps_x, eps_z) against the inextensible catenary falls strictly with n = 5, 15, 30, 60.

    Measured 0.061, 0.0077, 0.0020, 0.00052 %: second order, so each doubling of n must cut the
    error by more than 3 (15 -> 30 and 30 -> 60).
    """
    ns = (5, 15, 30, 60)
    error = {n: max(catenary_case(n).errors(np.inf)) for n in ns}
    validation("catenary convergence in n", "analytic", "inextensible catenary",
               "max(eps_x, eps_z) at n = 5, 15, 30, 60",
               ", ".join(f"{error[n]:.2g}" for n in ns) + " %",
               "falls; ratio > 3 per doubling; < 0.01 % at n = 15")  # fmt: skip
    for coarse, fine in zip(ns, ns[1:], strict=False):
        assert error[fine] < error[coarse], error
    assert error[15] / error[30] > 3, error
    assert error[30] / error[60] > 3, error
    assert error[15] < 0.01, error  # % (measured 0.0077 %)


def test_catenary_tensions(catenary_case):
    """Top tension |lambda_{n+1}| = T(0) = hypot(H, V - w L) (eq. 34c, s = 0 at the pin), 1e-9 rel.

    A rigid chain in equilibrium carries exactly the end load less the weight below each joint, so
    every bond force equals T(s) at its joint A_1..A_{n+1} (same tolerance).
    """
    case = catenary_case(15)
    top = np.hypot(case.horizontal, case.vertical - case.weight * case.length)
    assert case.tensions[-1] == pytest.approx(top, rel=1e-9)
    _, _, tension = case.analytic(np.inf)
    np.testing.assert_allclose(case.tensions, tension[1:], rtol=1e-9)


# ----------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def hanging_case(models_dir):
    """``torsion -> (scene, model, equilibrium state, rest inputs)`` for hanging.toml, cached."""
    cache = {}

    def get(torsion: bool):
        if torsion not in cache:
            scene = load_scene(models_dir / "hanging.toml", {"model.torsion": torsion})
            model = CableModel.from_scene(scene)
            drive = Drive.from_scene(scene)
            cache[torsion] = scene, model, equilibrium(model, drive), rest_inputs(drive)
        return cache[torsion]

    return get


TORSION = pytest.mark.parametrize("torsion", [False, True], ids=["5dof", "6dof"])


@TORSION
def test_hanging_top_tension_is_submerged_weight(hanging_case, torsion, validation):
    """Top tension = (rho - rho_w) A g L to 1e-6 relative; each bond carries the weight below it."""
    scene, model, x, u = hanging_case(torsion)
    cable, env = scene.cable, scene.environment
    per_length = (cable.density - env.water_density) * cable.cross_section_area * env.gravity
    tensions = model.output_values(x, u)["tensions"].ravel()
    validation(f"hanging in water, top tension, {model.dofs} DOF", "analytic",
               "submerged weight (rho - rho_w) A g L", "relative error",
               f"{abs(tensions[-1] / (per_length * cable.length) - 1):.1e}", "<= 1e-6")  # fmt: skip
    assert tensions[-1] == pytest.approx(per_length * cable.length, rel=1e-6)
    lengths = np.array([float(v) for v in model.element_lengths(u[INPUTS.top_length])])
    np.testing.assert_allclose(tensions, per_length * np.cumsum(lengths), rtol=1e-6)


@TORSION
def test_hanging_elements_are_vertical(hanging_case, torsion):
    """Every element hangs straight down: |e_x|, |e_y| < 1e-12, joints on the z axis (1e-9 m)."""
    _, model, x, u = hanging_case(torsion)
    q, qd = model.coordinates(x)
    psi = np.array([qi[3] for qi in q])
    theta = np.array([qi[4] for qi in q])
    e = np.stack([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])
    assert np.abs(e[:2]).max() < 1e-12
    np.testing.assert_allclose(e[2], 1.0, atol=1e-12)
    np.testing.assert_array_equal(np.concatenate(qd), 0.0)
    out = model.outputs(x, u)
    joints = np.array(out[0])
    assert np.abs(joints[:2]).max() < 1e-9  # m
    assert joints[2, 0] == pytest.approx(-model.spec.cable_length, abs=1e-9)
    assert np.abs(np.array(out[2])).max() < 1e-12  # bonds hold (m)


def test_hanging_torsion_variant_same_equilibrium(hanging_case):
    """The 6-DOF model finds the 5-DOF equilibrium: same positions and angles (1e-9), no twist."""
    _, model6, x6, _ = hanging_case(True)
    _, model5, x5, _ = hanging_case(False)
    assert model6.dofs == 6 and model5.dofs == 5
    q6, _ = model6.coordinates(x6)
    q5, _ = model5.coordinates(x5)
    np.testing.assert_allclose(np.stack(q6)[:, :5], np.stack(q5), rtol=0, atol=1e-9)
    assert np.abs(x6[model6.twist_angle_index()]).max() < 1e-9


def test_compiled_equilibrium_matches_the_symbolic_one(models_dir, validation):
    """Newton on the compiled structured rhs (FD Jacobian) vs CasADi's Newton on the SX rhs."""
    scene = load_scene(models_dir / "hanging.toml", {"environment.current": [0.4, -0.2, 0.05]})
    model = CableModel.from_scene(scene)
    drive = Drive.from_scene(scene)
    compiled = equilibrium(model, drive, compiled=True)
    symbolic = equilibrium(model, drive)
    difference = float(np.abs(compiled - symbolic).max())
    validation("hanging in a current, n = 10, compiled statics", "second formulation",
               "CasADi Newton on the symbolic equations", "max state difference",
               f"{difference:.1e} m", "<= 1e-7 m")  # fmt: skip
    assert difference <= 1e-7
