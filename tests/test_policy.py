"""The learned policy's object (issue 42): its three forms agree, its fit is reproducible, its
file is refused when damaged or of another family."""

from __future__ import annotations

import shutil
import subprocess

import netCDF4
import numpy as np
import pytest

from cable_ocp.drive.controls import HermiteIntervals
from cable_ocp.policy.action import label, ramp
from cable_ocp.policy.network import Network
from cable_ocp.policy.observation import FEATURES
from cable_ocp.policy.policy import Policy, load_policy

FAMILY = {"name": "made_up", "fingerprint": "0123456789abcdef"}


def _data(seed: int = 3, count: int = 400):
    """Observations of the policy's width and a smooth made-up drum rate (rad/s)."""
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(count, len(FEATURES))) * np.linspace(0.5, 50.0, len(FEATURES))
    y = 0.8 * np.tanh(x[:, 1]) - 0.02 * x[:, 5] + 0.1 * np.sin(x[:, 2])
    return x, y


@pytest.fixture(scope="module")
def policy() -> Policy:
    x, y = _data()
    network, _ = Network.fit(x, y, (12, 12), 1.5, seed=7, iterations=200)
    return Policy(network, FAMILY, x, y, np.zeros(y.size, dtype=np.int64), 7)


def test_the_same_seed_gives_the_same_network_bit_for_bit():
    x, y = _data()
    first, _ = Network.fit(x, y, (8, 8), 1.5, seed=11, iterations=100)
    again, _ = Network.fit(x, y, (8, 8), 1.5, seed=11, iterations=100)
    other, _ = Network.fit(x, y, (8, 8), 1.5, seed=12, iterations=100)
    for a, b in zip((*first.weights, *first.biases), (*again.weights, *again.biases), strict=True):
        assert a.tobytes() == b.tobytes()
    assert not np.array_equal(first.weights[0], other.weights[0])


def test_the_fit_learns_and_the_action_is_clipped_to_the_rate_limit(policy):
    x, y = _data(seed=4)  # observations the fit never saw
    error = np.mean((policy(x) - y) ** 2) / np.var(y)
    assert error < 0.05
    far = x[:1].copy()
    far[0, 1] = 1e3  # drives the made-up rate towards 0.8 rad/s and beyond, by extrapolation
    network = policy.network
    assert np.all(np.abs(policy(np.vstack([far, x]))) <= network.rate_limit)


def test_casadi_and_numpy_agree(policy):
    x, _ = _data(seed=5, count=1000)
    function = policy.function()
    rates = np.array(function.map(x.shape[0])(x.T)).ravel()
    assert np.max(np.abs(rates - policy(x))) < 1e-12


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler")
def test_compiled_c_matches_the_casadi_function(policy, tmp_path):
    """1000 observations through the exported C, compiled with -Wall -Werror, against CasADi."""
    c_file, h_file = policy.to_c(tmp_path / "winch_policy")
    assert h_file.read_text().count("#include") == 0
    assert c_file.read_text().count("#include") == 2  # math.h and its header, nothing else
    x, _ = _data(seed=6, count=1000)
    x[::97, 4] = 1e6  # far outside the data: the clip acts
    np.savetxt(tmp_path / "observations.txt", x, fmt="%.17g")
    main = tmp_path / "main.c"
    main.write_text(
        "#include <stdio.h>\n"
        f'#include "{h_file.name}"\n'
        "int main(void) {\n"
        f"    double o[{len(FEATURES)}]; int i;\n"
        "    while (1) {\n"
        f"        for (i = 0; i < {len(FEATURES)}; ++i)\n"
        '            if (scanf("%lf", &o[i]) != 1) return 0;\n'
        '        printf("%.17g\\n", cable_ocp_policy(o));\n'
        "    }\n"
        "}\n"
    )
    binary = tmp_path / "policy"
    subprocess.run(
        ["cc", "-O2", "-std=c99", "-Wall", "-Werror", str(c_file), str(main), "-o", str(binary),
         "-lm"],
        check=True, cwd=tmp_path,
    )  # fmt: skip
    with open(tmp_path / "observations.txt") as given:
        out = subprocess.run([str(binary)], stdin=given, capture_output=True, check=True)
    rates = np.array(out.stdout.split(), dtype=float)
    expected = np.array(policy.function().map(x.shape[0])(x.T)).ravel()
    assert rates.shape == (1000,)
    assert np.max(np.abs(rates - expected)) <= 1e-12
    assert np.any(np.abs(expected) == policy.network.rate_limit)


def test_a_saved_policy_loads_the_same(policy, tmp_path):
    path = policy.save(tmp_path / "policy.nc")
    again = load_policy(path)
    assert again.digest == policy.digest and again.family == FAMILY
    np.testing.assert_array_equal(again.observations, policy.observations)
    x, _ = _data(seed=8)
    assert np.array_equal(again(x), policy(x))


def test_a_damaged_policy_file_is_refused(policy, tmp_path):
    path = policy.save(tmp_path / "policy.nc")
    with netCDF4.Dataset(path, "a") as stored:
        stored["weight_1"][0, 0] = stored["weight_1"][0, 0] + 1e-9  # one number changed
    with pytest.raises(ValueError, match="network does not hash to the digest.*damaged"):
        load_policy(path)
    truncated = tmp_path / "truncated.nc"
    truncated.write_bytes(policy.save(tmp_path / "whole.nc").read_bytes()[:3000])
    with pytest.raises(ValueError, match="truncated.nc"):
        load_policy(truncated)


def test_a_policy_of_another_family_is_refused(policy, tmp_path):

    path = policy.save(tmp_path / "policy.nc")
    with pytest.raises(ValueError, match="learned for the family 'made_up'.*not for 'hill_tow'"):
        load_policy(path, family="hill_tow")


def test_a_file_of_another_kind_is_refused(tmp_path):
    import xarray as xr

    from cable_ocp.result_files import netcdf

    path = netcdf.write(xr.Dataset(attrs=netcdf.file_attributes("MpcResult")), tmp_path / "mpc.nc")
    with pytest.raises(ValueError, match="holds a MpcResult, not a Policy"):
        load_policy(path)


def test_an_action_made_into_a_plan_is_read_back():
    control = HermiteIntervals(20.0, 4, free_start=True)
    for angle, rate, action in ((1.0, 0.3, -0.5), (-3.0, 0.0, 0.7), (0.0, -0.2, -0.2)):
        plan = ramp(control, angle, rate, action, 1.0)
        start = control.evaluate(plan, np.array([0.0]))
        assert start[0][0] == pytest.approx(angle) and start[1][0] == pytest.approx(rate)
        assert label(control, plan, 1.0) == pytest.approx(action, abs=1e-12)
