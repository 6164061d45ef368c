"""Optimal winch control: the optimiser works, respects its bounds and fails loudly."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import xarray as xr
from legacy_results import write_ocp_result

from cable_ocp.control.gauss_newton import GaussNewtonSettings
from cable_ocp.control.ipopt import IpoptSettings
from cable_ocp.control.nelder_mead import NelderMeadSettings
from cable_ocp.control.optimization import OcpResult, optimize
from cable_ocp.control.settings import GridSettings, ModelSettings, TranscriptionSettings
from cable_ocp.drive.bounds import angle_bounds
from cable_ocp.drive.controls import HermiteIntervals, KnotSpline
from cable_ocp.drive.winch import spline_angle
from cable_ocp.result_files.dataset import fields_equal
from cable_ocp.scene.schema import load_scene
from cable_ocp.simulation.run import simulate

# small_tow: 100 m cable, n = 4, 40 s; the same model for optimisation and verification.
SETTINGS = {"model": ModelSettings(4, 0.25), "grid": GridSettings(intervals=8)}


@pytest.fixture(scope="module")
def small(models_dir):
    return load_scene(models_dir / "small_tow.toml")


@pytest.fixture(scope="module")
def solved(small):
    return optimize(small, quiet=True, **SETTINGS), simulate(small)


def test_ipopt_beats_locked_winch(solved, small):
    """Omega of the optimised winch is far below the locked one (measured 2.2e-4 vs 0.58 m)."""
    result, locked = solved
    assert result.success, result.status
    assert locked.omega > 0.3
    assert result.omega < 0.02 * locked.omega
    # Omega is the verified one: it equals a fresh simulation of the scene with that winch.
    control = HermiteIntervals(40.0, SETTINGS["grid"].intervals)
    again = simulate(small, winch=control.angle_function(result.parameters))
    assert again.omega == pytest.approx(result.omega, rel=1e-12)


def test_winch_bounds_hold_along_the_trajectory(solved, small):
    result, _ = solved
    low, high = angle_bounds(small)
    phi = result.trajectory.winch_angle
    assert phi.min() >= low - 1e-9 and phi.max() <= high + 1e-9
    length = result.trajectory.top_length
    assert length.min() >= small.winch.top_length_min - 1e-9
    assert length.max() <= small.winch.top_length_max + 1e-9


def test_result_round_trip(solved, tmp_path):
    """Through netCDF, field by field; every variable of the file has units and a long name."""
    result, _ = solved
    assert result.save(tmp_path / "r") == tmp_path / "r" / "result.nc"
    back = OcpResult.load(tmp_path / "r")
    assert fields_equal(back, result)
    assert np.array_equal(back.parameters, result.parameters)
    assert back.trajectory.equals(result.trajectory)
    assert back.omega == result.omega and back.status == result.status
    with xr.open_dataset(tmp_path / "r" / "result.nc") as data:
        assert all(
            v.attrs.get("units") and v.attrs.get("long_name") for v in data.variables.values()
        )
        assert data["omega"].attrs["units"] == "m" and data["history"].attrs["units"] == "m"
        assert data["wall_time"].attrs["units"] == "s" and data.attrs["method"] == "shooting"
        assert data["trajectory_omega"] == data["omega"]  # the verified run's Omega
        assert data["tension"].dims == ("time", "element")


def test_a_result_of_format_1_still_loads(solved, tmp_path):
    result, _ = solved
    write_ocp_result(result, tmp_path / "r")
    # Format 1 kept no scene (neither the result's nor its trajectory's), no signed tensions
    # (its top tension is then the bond force's magnitude) and no bond residual: the rest is as
    # it was.
    trajectory = replace(
        result.trajectory,
        scene_record={},
        signed_tensions=np.zeros((0, 0)),
        bond_residual=float("nan"),
    )
    expected = replace(result, scene_record={}, trajectory=trajectory)
    assert fields_equal(OcpResult.load(tmp_path / "r"), expected)


def test_infeasible_bounds_fail_loudly(small):
    """A heave the rate-limited winch cannot compensate within its angle range: IPOPT says so."""
    scene = small.updated(
        {
            "top.heave.amplitude": 6.0,
            "top.heave.period": 10.0,
            "top.heave.compensation": True,
            "winch.rate_max": 0.1,
        }
    )
    result = optimize(scene, quiet=True, **SETTINGS)
    assert not result.success
    assert "Infeasible" in result.status


def test_nelder_mead_at_its_evaluation_limit_is_not_a_success(small):
    result = optimize(
        small,
        "nelder-mead",
        NelderMeadSettings(max_evaluations=20),
        model=ModelSettings(step=0.5),
        quiet=True,
    )
    assert not result.success
    assert result.evaluations <= 21
    assert "evaluations" in result.status.lower()


def test_gauss_newton_and_ipopt_find_the_same_winch(solved, small):
    """Two solvers of one transcription: the verified Omega agrees within 0.1 % (measured
    2.2322025e-4 m and 2.2322025e-4 m; 2 against 17 iterations)."""
    gauss_newton, _ = solved
    assert gauss_newton.solver == "gauss-newton"
    ipopt = optimize(small, "ipopt", quiet=True, **SETTINGS)
    assert gauss_newton.success and ipopt.success, (gauss_newton.status, ipopt.status)
    assert gauss_newton.omega == pytest.approx(ipopt.omega, rel=1e-3)
    assert gauss_newton.iterations < ipopt.iterations


@pytest.mark.slow
def test_single_and_multiple_shooting_find_the_same_winch(solved, small):
    """Two formulations of one NLP: the optimum's verified Omega agrees within 1e-5 m (measured
    2.218e-4 m both), and both hold the bounds."""
    single, _ = solved
    multiple = optimize(
        small, "ipopt", transcription=TranscriptionSettings("multiple"), quiet=True, **SETTINGS
    )
    assert single.success and multiple.success, (single.status, multiple.status)
    assert abs(single.omega - multiple.omega) < 1e-5


def test_single_shooting_reports_its_phases(solved):
    """Compile and verification times are part of the wall time (0 <= each <= wall)."""
    result, _ = solved
    assert 0.0 <= result.compile_time <= result.build_time <= result.wall_time
    assert 0.0 < result.verification_time <= result.wall_time


def test_unknown_shooting_is_rejected():
    with pytest.raises(ValueError, match="shooting = 'double'"):
        TranscriptionSettings(shooting="double")


def test_a_result_saved_without_the_phase_times_loads(solved, tmp_path):
    """Results written before compile_time/verification_time existed load with them 0."""
    import json

    result, _ = solved
    write_ocp_result(result, tmp_path / "r")
    path = tmp_path / "r" / "result.json"
    meta = json.loads(path.read_text())
    del meta["compile_time"], meta["verification_time"]
    path.write_text(json.dumps(meta))
    back = OcpResult.load(tmp_path / "r")
    assert back.compile_time == 0.0 and back.verification_time == 0.0
    assert back.omega == result.omega


def test_exact_hessian_needs_the_interpreted_model(small):
    with pytest.raises(ValueError, match="second derivatives"):
        optimize(small, "ipopt", IpoptSettings(hessian="exact"))


def test_spline_basis_matches_the_winch_spline():
    control = KnotSpline(210.0, 14)
    values = np.random.default_rng(3).normal(size=14)
    t = np.linspace(0.0, 210.0, 777)
    basis = control.basis(t)
    reference = spline_angle(210.0, values)(t)
    for b, r in zip(basis, reference, strict=True):
        assert np.allclose(b @ values, r, atol=1e-12)


def test_hermite_basis_interpolates_its_nodes():
    control = HermiteIntervals(100.0, 10)
    p = np.random.default_rng(4).normal(size=control.size)
    nodes = np.arange(1, 11) * 10.0
    b0, b1, _ = control.basis(nodes)
    assert np.allclose(b0 @ p, p[:10]) and np.allclose(b1 @ p, p[10:])
    start = control.basis(np.zeros(1))
    assert np.allclose(start[0] @ p, 0.0) and np.allclose(start[1] @ p, 0.0)


# Output modes: small_tow over 20 s at h = 0.5 s, two Hermite intervals (a solve takes about 1 s).
SHORT = {"numerics.duration": 20.0, "numerics.step": 0.5}
TINY = {"model": ModelSettings(4, 0.5), "grid": GridSettings(intervals=2)}  # the scene's model
# IPOPT's banner ("This program contains Ipopt") prints once per process at most, so the tests
# look for the log's header line.
BANNER = "This is Ipopt version"


@pytest.fixture(scope="module")
def short(small):
    return small.updated(SHORT)


def test_quiet_prints_nothing_at_all(short, capfd):
    optimize(short, quiet=True, **TINY)  # a first run may compile the model
    capfd.readouterr()
    result = optimize(short, quiet=True, **TINY)
    out, err = capfd.readouterr()
    assert result.success, result.status
    assert out == "" and err == ""


def test_default_prints_one_line_per_iteration_and_no_ipopt_log(short, capfd):
    result = optimize(short, **TINY)
    out, err = capfd.readouterr()
    assert BANNER not in out + err and "EXIT:" not in out + err
    lines = [line for line in err.splitlines() if line.startswith("gauss-newton iter")]
    assert len(lines) == result.evaluations  # iteration 0 is the starting point
    assert "Omega = " in lines[-1] and " m  violation = " in lines[-1]
    omega = float(lines[-1].split("Omega = ")[1].split()[0])
    assert omega == pytest.approx(result.omega_model, rel=1e-3)


def test_verbose_prints_the_ipopt_log(short, capfd):
    optimize(short, "ipopt", verbose=True, **TINY)
    out, err = capfd.readouterr()
    assert BANNER in out and "EXIT:" in out
    assert "ipopt iter" not in err


def test_quiet_and_verbose_together_are_rejected(short):
    for solver in ("gauss-newton", "ipopt", "nelder-mead"):
        with pytest.raises(ValueError, match="quiet.*verbose"):
            optimize(short, solver, quiet=True, verbose=True)


def test_the_result_names_the_solver_that_ran_and_keeps_it_in_its_files(short, tmp_path):
    """``solver`` chooses, and the result, its summary and its file say which one ran: the
    default without the argument, the settings' owner without a name."""
    by_default = optimize(short, quiet=True, **TINY)
    assert by_default.solver == "gauss-newton"
    ipopt = optimize(short, settings=IpoptSettings(), quiet=True, **TINY)
    assert ipopt.solver == "ipopt" and ipopt.success, ipopt.status
    assert ipopt.summary()["solver"] == "ipopt"
    ipopt.save(tmp_path / "run")
    assert OcpResult.load(tmp_path / "run").solver == "ipopt"
    simplex = optimize(short, "nelder-mead", NelderMeadSettings(max_evaluations=5), quiet=True)
    assert simplex.solver == "nelder-mead"


def test_a_solver_that_does_not_fit_its_settings_is_refused_before_any_work(short):
    with pytest.raises(ValueError, match="solver = 'gradient-descent': must be one of 'gauss-n"):
        optimize(short, "gradient-descent")
    with pytest.raises(ValueError, match="NelderMeadSettings given for solver 'ipopt'"):
        optimize(short, "ipopt", NelderMeadSettings())
    with pytest.raises(ValueError, match="IpoptSettings given for solver 'nelder-mead'"):
        optimize(short, "nelder-mead", IpoptSettings())
    with pytest.raises(ValueError, match="Nelder-Mead searches the spline through winch.knots"):
        optimize(short, "nelder-mead", grid=GridSettings(intervals=2))
    with pytest.raises(ValueError, match="Nelder-Mead takes no shooting"):
        optimize(short, "nelder-mead", transcription=TranscriptionSettings("multiple"))
    with pytest.raises(ValueError, match="Gauss-Newton takes 'single' shooting"):
        optimize(short, transcription=TranscriptionSettings("multiple"))


def test_nelder_mead_quiet_prints_nothing(short, capfd):
    optimize(short, "nelder-mead", NelderMeadSettings(max_evaluations=5), quiet=True)
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_failed_result_saves_nan_as_null_and_loads_back(short, tmp_path):
    result = optimize(
        short, settings=GaussNewtonSettings(max_iter=1), grid=GridSettings(intervals=2), quiet=True
    )
    # A failed solve is still simulated on the scene's model (where it got to), never a success.
    assert not result.success and result.trajectory is not None
    result = replace(result, trajectory=None, omega=float("nan"), history=[1.0, float("nan")])
    result.save(tmp_path / "netcdf")
    back = OcpResult.load(tmp_path / "netcdf")
    assert fields_equal(back, result) and back.trajectory is None
    empty = replace(result, parameters=np.zeros(0), control="hermite(0)", history=[],
                    refinements=[])  # fmt: skip
    empty.save(tmp_path / "empty")
    assert fields_equal(OcpResult.load(tmp_path / "empty"), empty)
    write_ocp_result(result, tmp_path / "r")
    text = (tmp_path / "r" / "result.json").read_text()
    assert "NaN" not in text and '"omega": null' in text
    back = OcpResult.load(tmp_path / "r")
    assert np.isnan(back.omega) and back.history[0] == 1.0 and np.isnan(back.history[1])
    assert back.trajectory is None and back.status == result.status


@pytest.mark.parametrize("name", ["result.json", "result.npz", "trajectory.npz", "trajectory.json"])
def test_load_names_a_truncated_file(solved, tmp_path, name):
    result, _ = solved
    write_ocp_result(result, tmp_path / "r")
    path = tmp_path / "r" / name
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(ValueError, match=name.replace(".", r"\.")):
        OcpResult.load(tmp_path / "r")


def test_load_names_a_missing_file(solved, tmp_path):
    result, _ = solved
    write_ocp_result(result, tmp_path / "r")
    (tmp_path / "r" / "result.npz").unlink()
    with pytest.raises(ValueError, match=r"result\.npz"):
        OcpResult.load(tmp_path / "r")
    with pytest.raises(ValueError, match=r"nothing/result\.nc: no such file"):
        OcpResult.load(tmp_path / "nothing")


def test_load_names_a_truncated_netcdf_file(solved, tmp_path):
    result, _ = solved
    path = result.save(tmp_path / "r")
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(ValueError, match=r"result\.nc: not a readable"):
        OcpResult.load(tmp_path / "r")


def test_intervals_that_do_not_divide_the_steps_are_refused_before_any_model(
    models_dir, monkeypatch
):
    from cable_ocp.control.problem import WinchProblem

    def forbidden(*args, **kwargs):
        pytest.fail("the intervals must be checked before the problem is built")

    monkeypatch.setattr(WinchProblem, "from_scene", forbidden)
    scene = load_scene(models_dir / "small_tow.toml")  # 40 s at h = 0.5 s: 80 steps
    with pytest.raises(ValueError, match=r"intervals = 42 must divide the 80 RK4 steps"):
        optimize(scene, model=ModelSettings(step=0.5), grid=GridSettings(intervals=42), quiet=True)


def test_a_result_keeps_its_resolved_settings_and_solves_again_from_its_file(short, tmp_path):
    """The file holds the scene and the settings, every number as derived: the same problem
    solved again from them gives the same profile (to 1e-12 rad) and Omega (to 1e-12 m)."""
    from cable_ocp.control.solvers import ocp_settings_from_record

    first = optimize(short, "ipopt", IpoptSettings(max_iter=50), quiet=True)
    assert first.settings["grid"]["intervals"] is not None  # derived, then kept
    first.save(tmp_path / "run")
    kept = OcpResult.load(tmp_path / "run")
    settings = ocp_settings_from_record(kept.settings)
    assert settings.solver == "ipopt" and settings.solver_settings.max_iter == 50
    again = optimize(kept.scene, settings=settings, quiet=True)
    np.testing.assert_allclose(again.parameters, first.parameters, rtol=0, atol=1e-12)
    assert again.omega == pytest.approx(first.omega, rel=0, abs=1e-12)
    with pytest.raises(ValueError, match="not a record of OcpSettings"):
        ocp_settings_from_record({"solver": "ipopt"})
    retired = {**kept.settings, "grid": {**kept.settings["grid"], "adaptive_start": 4,
                                         "adaptive_rounds": 4}}  # fmt: skip
    assert ocp_settings_from_record(retired) == settings  # a file of the first adaptive rule


def test_a_correction_that_does_not_lower_its_model_is_not_run_on_the_full_model():
    """The share a solve lowered its model's Omega^2 by, from either unit of history: a solve
    below UNMOVED is not verified (its run could lower Omega by about half that share)."""
    from types import SimpleNamespace

    from cable_ocp.control.optimization import UNMOVED, _model_gain

    def outcome(history):
        return SimpleNamespace(history=history)

    assert _model_gain(outcome([4.0, 1.0, 2.0]), "m2") == pytest.approx(0.75)
    assert _model_gain(outcome([2.0, 1.0]), "m") == pytest.approx(0.75)  # Omega: 4 -> 1 m^2
    assert _model_gain(outcome([9.0]), "m2") == 0.0  # not one step taken
    assert _model_gain(outcome([0.0, 0.0]), "m2") == 1.0  # nothing to hold: not "unmoved"
    assert _model_gain(outcome([1.0, 1.0 - UNMOVED / 2]), "m2") < UNMOVED
