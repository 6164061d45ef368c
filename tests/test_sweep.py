"""Sweeps: sweep-file validation and expansion, Dask runs, failed cases, resume, foreign folders.

Tiny cases (hanging / small_tow, n = 5, 10-20 s): the Dask cluster runs in-process threads
(``processes=False``) except in the command-line test, which starts worker processes.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

import numpy as np
import pytest

import cable_ocp as co
from cable_ocp.cli.sweep import add_sweep_command
from cable_ocp.sweep import load_sweep, open_sweep, run_sweep
from cable_ocp.sweep.store import case_path

MODELS = Path(__file__).resolve().parent.parent / "models"

HEADER = f"""
scene = "{MODELS / "hanging.toml"}"
task = "simulate"
[set]
"numerics.duration" = 10.0
"numerics.step" = 0.1
"model.elements" = 5
"top.motion" = "tow"
"top.tow.ramp_time" = 5.0
"""
GRID = (
    HEADER
    + """
[grid]
"top.tow.surge_speed" = [0.5, 1.0]
"environment.current" = [[0.0, 0.0, 0.0], [0.3, 0.1, 0.0]]
"""
)


def write(tmp_path: Path, text: str, name: str = "sweep.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def sample_text(n=6, seed=3, design="latin-hypercube", extra="") -> str:
    return HEADER + (
        f'[sample]\nn = {n}\nseed = {seed}\ndesign = "{design}"\n[sample.ranges]\n'
        '"top.tow.surge_speed" = [0.4, 1.2]\n'
        '"environment.current" = [[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]\n' + extra
    )


# --- the sweep file ---------------------------------------------------------------------------


def test_grid_expands_to_the_full_factorial(tmp_path):
    spec = load_sweep(write(tmp_path, GRID))
    assert spec.swept == ("top.tow.surge_speed", "environment.current")
    assert [c.overrides for c in spec.cases] == [
        {"top.tow.surge_speed": s, "environment.current": c}
        for s in (0.5, 1.0)
        for c in ([0.0, 0.0, 0.0], [0.3, 0.1, 0.0])
    ]
    scene = spec.cases[3].scene
    assert scene.top.tow.surge_speed == 1.0 and scene.environment.current == (0.3, 0.1, 0.0)
    assert scene.numerics.duration == 10.0 and scene.model.elements == 5  # [set] applied
    assert len({c.fingerprint for c in spec.cases}) == 4


def test_latin_hypercube_sample_is_stratified_and_reproducible(tmp_path):
    spec = load_sweep(write(tmp_path, sample_text(n=6, seed=3, extra='"model.elements" = [5, 8]')))
    speeds = np.array([c.overrides["top.tow.surge_speed"] for c in spec.cases])
    current = np.array([c.overrides["environment.current"] for c in spec.cases])
    elements = [c.overrides["model.elements"] for c in spec.cases]
    assert len(spec.cases) == 6 and spec.design == "latin-hypercube"
    # One sample in each sixth of each range: the Latin hypercube property.
    assert sorted(np.floor((speeds - 0.4) / 0.8 * 6).astype(int)) == list(range(6))
    assert sorted(np.floor(current[:, 0] / 0.5 * 6).astype(int)) == list(range(6))
    assert np.all(current[:, 1:] == 0.0)  # low == high: the component stays fixed
    assert all(isinstance(e, int) and 5 <= e <= 8 for e in elements)  # integer field rounded
    assert [c.scene.model.elements for c in spec.cases] == elements
    again = load_sweep(write(tmp_path, sample_text(n=6, seed=3, extra='"model.elements" = [5, 8]')))
    assert [c.overrides for c in again.cases] == [c.overrides for c in spec.cases]
    other = load_sweep(write(tmp_path, sample_text(n=6, seed=4, extra='"model.elements" = [5, 8]')))
    assert [c.overrides for c in other.cases] != [c.overrides for c in spec.cases]


def test_uniform_sample_stays_in_range(tmp_path):
    spec = load_sweep(write(tmp_path, sample_text(n=20, seed=0, design="uniform")))
    speeds = np.array([c.overrides["top.tow.surge_speed"] for c in spec.cases])
    assert len(speeds) == 20 and speeds.min() >= 0.4 and speeds.max() <= 1.2
    assert np.unique(speeds).size == 20


@pytest.mark.parametrize(
    "body, message",
    [
        ('[grid]\n"top.tow.ramp_time" = [2.0, -1.0]',
         "grid.top.tow.ramp_time[1] = -1.0 (case 1): top.tow.ramp_time = -1.0 is out of range: "
         "must be > 0"),
        ('[grid]\n"top.surge_sped" = [1.0]', "grid.top.surge_sped[0] = 1.0 (case 0): top.surge_sped"
         ": unknown key"),
        ('[grid]\n"environment.current" = [[0, 0, 0], [1, 0]]',
         "grid.environment.current[1] = [1, 0] (case 1): environment.current: expected 3 numbers"),
        ('[grid]\n"top.tow.surge_speed" = []',
         "grid.top.tow.surge_speed: expected a non-empty list"),
        ('[sample]\nn = 0\n[sample.ranges]\n"top.tow.surge_speed" = [1, 2]',
         "sample.n = 0: must be an integer in [1, 100000]"),
        ('[sample]\nn = 3\n[sample.ranges]\n"top.tow.surge_speed" = [2, 1]',
         "sample.ranges.top.tow.surge_speed = [2, 1]: low must be <= high"),
        ('[sample]\nn = 3\n[sample.ranges]\n"top.tow.ramp_time" = [-2.0, -1.0]',
         "sample.ranges.top.tow.ramp_time: drawn value"),
        ('[sample]\nn = 3\ndesign = "sobol"\n[sample.ranges]\n"top.tow.surge_speed" = [1, 2]',
         "sample.design = 'sobol': must be one of latin-hypercube, uniform"),
        ('[grid]\n"top.tow.surge_speed" = [1.0]\n[sample]\nn = 2', "sample: give either [grid] or"),
        ('[optimizer]\nelements = 3', "optimizer: only allowed with task = 'optimize'"),
        ('[grid]\n"top.tow.surge_speed" = [1.0, nan]',
         "grid.top.tow.surge_speed[1] = nan: must be finite"),
        ('[grid]\n"top.tow.surge_speed" = [1.0, inf]',
         "grid.top.tow.surge_speed[1] = inf: must be finite"),
        ('[grid]\n"top.tow" = [{surge_speed = 1.0}]',
         "grid.top.tow[0] = {'surge_speed': 1.0}: a swept value must be a number, a string"),
        ('[grid]\n"seabed.hills" = [[{position = 1.0}]]', "grid.seabed.hills[0] = [{'position'"),
        ('[grid]\n"top.tow.surge_speed" = [1.0, "fast"]',
         "grid.top.tow.surge_speed: values of one key must be of one kind, got number, string"),
        ('[grid]\n"top.tow.ramp_time" = [-1.0, 2.0, -1.0]',
         "grid.top.tow.ramp_time[0] = -1.0 (case 0): top.tow.ramp_time = -1.0"),
    ],
)  # fmt: skip
def test_bad_sweep_file_names_the_key(tmp_path, body, message):
    with pytest.raises(ValueError) as error:
        load_sweep(write(tmp_path, HEADER + body + "\n"))
    assert message in str(error.value)


@pytest.mark.parametrize(
    "text, message",
    [
        ('scene = "hanging"\ncolour = 1', "colour: unknown key; allowed keys: scene"),
        ('scene = "nowhere.toml"', "scene = 'nowhere.toml': file not found"),
        ('scene = "hanging"\ntask = "solve"', "task = 'solve': must be one of simulate, optimize"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nsteps = 1',
         "optimizer: steps: unknown setting for solver 'gauss-newton'; allowed: solver, elements"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nmax_iter = 0',
         "optimizer: GaussNewtonSettings.max_iter = 0: must be >= 1"),
        ('scene = "small_tow"\ntask = "optimize"\n[optimizer]\nstep = 0.25\nintervals = 7',
         "optimizer.intervals = 7 (case 0): must divide the 160 RK4 steps"),
        ('scene = "hanging"\n[set]\n"model.elements" = 0',
         "set.model.elements: model.elements = 0 is out of range: must be >= 1"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nstep = "abc"',
         "optimizer: ModelSettings.step = 'abc' s: must be a number"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nelements = 2.5',
         "optimizer: ModelSettings.elements = 2.5: must be an integer"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nmax_iter = true',
         "optimizer: GaussNewtonSettings.max_iter = True: must be an integer"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\ncompiled = 1',
         "optimizer: TranscriptionSettings.compiled = 1: must be true or false"),
        ('scene = "hanging"\ntask = "optimize"\nmethod = "nelder-mead"\n[optimizer]\nxatol = nan',
         "optimizer: NelderMeadSettings.xatol = nan rad: must be finite"),
        ('scene = "hanging"\ntask = "optimize"\nmethod = "nelder-mead"\n[optimizer]\nintervals = 4',
         "optimizer: intervals: unknown setting for solver 'nelder-mead'"),
        ('scene = "hanging"\ntask = "optimize"\n[optimizer]\nsolver = "ipopt"\nhessian = "exact"',
         "optimizer: IpoptSettings.hessian = 'exact' needs second derivatives"),
        # A named method and a solver that does not run on it (the registry says which do).
        ('scene = "hanging"\ntask = "optimize"\nmethod = "nelder-mead"\n[optimizer]\n'
         'solver = "ipopt"',
         "optimizer.solver: solver = 'ipopt' with method = 'nelder-mead': that method is run by "
         "'nelder-mead'"),
        ('scene = "hanging"\ntask = "optimize"\nmethod = "shooting"\n[optimizer]\n'
         'solver = "nelder-mead"',
         "that method is run by 'gauss-newton' or 'ipopt'"),
        ('scene = "hanging"\ntask = "optimize"\nmethod = "simplex"',
         "method: method = 'simplex': must be one of 'shooting', 'nelder-mead'"),
    ],
)  # fmt: skip
def test_bad_sweep_header_names_the_key(tmp_path, text, message):
    with pytest.raises(ValueError) as error:
        load_sweep(write(tmp_path, text + "\n"))
    assert message in str(error.value)


# --- running ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def grid_run(tmp_path_factory):
    """The 4-case grid run on 2 in-process workers, and its spec."""
    folder = tmp_path_factory.mktemp("grid")
    spec = load_sweep(write(folder, GRID))
    report = run_sweep(spec, folder / "out", workers=2, quiet=True, processes=False)
    return spec, report, folder / "out"


def test_sweep_dataset_matches_a_direct_simulation(grid_run):
    spec, report, out = grid_run
    ds = open_sweep(out)
    assert sorted(report.ran) == [0, 1, 2, 3] and report.skipped == []
    assert dict(ds.sizes) == {"case": 4, "time": 101}
    np.testing.assert_array_equal(ds["top.tow.surge_speed"], [0.5, 0.5, 1.0, 1.0])
    np.testing.assert_array_equal(ds["environment.current[0]"], [0.0, 0.3, 0.0, 0.3])
    np.testing.assert_array_equal(ds["environment.current[1]"], [0.0, 0.1, 0.0, 0.1])
    reasons = [str(reason) for reason in ds["reason"].values]
    assert list(ds["status"].values) == ["ok"] * 4 and bool(ds["success"].all()), reasons
    assert reasons == [""] * 4
    # Case 3 recomputed here, independently of the sweep machinery.
    scene = co.load_scene(
        MODELS / "hanging.toml",
        {"numerics.duration": 10.0, "numerics.step": 0.1, "model.elements": 5,
         "top.motion": "tow", "top.tow.ramp_time": 5.0, "top.tow.surge_speed": 1.0,
         "environment.current": [0.3, 0.1, 0.0]},
    )  # fmt: skip
    direct = co.simulate(scene)
    case = ds.sel(case=3)
    np.testing.assert_allclose(case["time"], direct.time, atol=1e-9)
    assert case["omega"].item() == pytest.approx(direct.omega, rel=1e-12)
    np.testing.assert_allclose(case["end_x"], direct.end[:, 0], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(case["end_z"], direct.end[:, 2], rtol=1e-12, atol=1e-9)
    assert direct.end[-1, 0] > 1.0  # the tow moved the end: the comparison is not trivial
    # The other cases differ from case 3 (each case ran its own scene).
    assert len(set(np.round(ds["omega"].values, 9))) == 4


def test_load_result_reads_a_sweep_as_open_sweep_does(grid_run):
    """The sweep's dataset is in the result family: its folder or its file, by its kind."""
    import cable_ocp as co
    from cable_ocp.result_files import SWEEP_KIND, netcdf

    out = grid_run[2]
    assert netcdf.kind_of(out / "sweep.nc") == SWEEP_KIND
    for path in (out, out / "sweep.nc"):
        assert co.load_result(path).identical(open_sweep(out))


def test_open_sweep_indexes_the_swept_keys(grid_run):
    ds = open_sweep(grid_run[2], index=True)
    picked = ds.sel({"top.tow.surge_speed": 1.0, "environment.current[0]": 0.3})
    assert picked["omega"].values.ravel()[0] == pytest.approx(
        open_sweep(grid_run[2])["omega"].values[3], rel=0
    )


def test_resume_recomputes_only_the_missing_case(grid_run, tmp_path):
    spec, _, out = grid_run
    case_path(out, 2).unlink()
    stamps = {k: os.stat(case_path(out, k)).st_mtime_ns for k in (0, 1, 3)}
    before = open_sweep(out)
    report = run_sweep(spec, out, workers=1, quiet=True, processes=False)
    assert report.ran == [2] and report.skipped == [0, 1, 3]
    assert {k: os.stat(case_path(out, k)).st_mtime_ns for k in (0, 1, 3)} == stamps
    after = open_sweep(out)
    np.testing.assert_allclose(after["omega"], before["omega"], rtol=1e-12)
    again = run_sweep(spec, out, workers=1, quiet=True, processes=False)
    assert again.ran == [] and again.skipped == [0, 1, 2, 3]


def test_a_foreign_folder_is_refused(grid_run, tmp_path):
    spec, _, out = grid_run
    other = GRID.replace("[0.5, 1.0]", "[0.5, 0.9]")
    with pytest.raises(ValueError, match="belongs to another sweep"):
        run_sweep(load_sweep(write(tmp_path, other)), out, quiet=True, processes=False)
    changed = GRID.replace('"numerics.step" = 0.1', '"numerics.step" = 0.05')
    with pytest.raises(ValueError, match="another scene file content"):
        run_sweep(load_sweep(write(tmp_path, changed)), out, quiet=True, processes=False)
    stray = tmp_path / "stray"
    stray.mkdir()
    (stray / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="not empty and holds no sweep of cable-ocp"):
        run_sweep(spec, stray, quiet=True, processes=False)
    assert not (stray / "sweep.json").exists()


def test_command_records_a_failed_case_and_exits_3(tmp_path, capsys):
    # h = 2 s blows the tow up (SimulationError); h = 0.1 s is fine. Worker processes this time.
    text = HEADER + '[grid]\n"numerics.step" = [0.1, 2.0]\n'
    parser = argparse.ArgumentParser()
    add_sweep_command(parser.add_subparsers())
    argv = ["sweep", str(write(tmp_path, text)), "--out", str(tmp_path / "out"), "--workers", "1"]
    args = parser.parse_args([*argv, "--quiet"])
    assert args.run(args) == 3
    ds = open_sweep(tmp_path / "out")
    assert list(ds["status"].values) == ["ok", "failed"]
    assert list(ds["success"].values) == [True, False]
    assert ds["reason"].values[0] == ""
    assert ds["reason"].values[1].startswith("SimulationError: bond residual")
    assert np.isnan(ds["omega"].values[1]) and np.isfinite(ds["omega"].values[0])
    assert dict(ds.sizes) == {"case": 2, "time": 101}  # the failed case has no time series
    assert np.isnan(ds["end_x"].values[1]).all()
    printed = capsys.readouterr().out
    assert "| 1 | 2 | failed | nan |" in printed and "SimulationError: bond residual" in printed
    assert "ok 1, failed 1, not run 0" in printed


def test_optimize_sweep_and_durations_padded_with_nan(tmp_path):
    text = (
        f'scene = "{MODELS / "small_tow.toml"}"\ntask = "optimize"\n'
        "[optimizer]\nstep = 0.25\nintervals = 4\nmax_iter = 30\n"
        '[grid]\n"numerics.duration" = [8.0, 10.0]\n'
    )
    spec = load_sweep(write(tmp_path, text))
    report = run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    ds = report.dataset
    assert dict(ds.sizes) == {"case": 2, "time": 41}
    for name in ("omega_model", "iterations", "evaluations", "solver_status"):
        assert name in ds
    assert (ds["iterations"] > 0).all()
    assert np.isnan(ds["winch_angle"].values[0, 33:]).all()  # 8 s case padded after t = 8 s
    assert np.isfinite(ds["winch_angle"].values[1]).all()
    assert np.abs(ds["winch_angle"].values[1]).max() > 0.01  # the winch moved
    locked = co.simulate(spec.cases[1].scene)
    assert ds["omega"].values[1] < locked.omega  # the optimised winch beats the locked one


def test_existing_scheduler_is_used_and_left_running(tmp_path):
    from dask.distributed import Client, LocalCluster

    text = HEADER + '[grid]\n"top.tow.surge_speed" = [0.5, 1.0]\n'
    with LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster:
        report = run_sweep(
            load_sweep(write(tmp_path, text)),
            tmp_path / "out",
            scheduler=cluster.scheduler_address,
            quiet=True,
        )
        assert report.workers == 1 and sorted(report.ran) == [0, 1] and report.all_ok
        with Client(cluster.scheduler_address) as client:  # still up after the sweep
            assert len(client.scheduler_info()["workers"]) == 1


def test_retry_failed_reruns_only_the_failed_case(tmp_path):
    spec = load_sweep(write(tmp_path, HEADER + '[grid]\n"numerics.step" = [0.1, 2.0]\n'))
    first = run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    assert list(first.dataset["status"].values) == ["ok", "failed"] and not first.all_ok
    plain = run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    assert plain.ran == [] and plain.skipped == [0, 1]  # a failed case counts as finished
    retried = run_sweep(
        spec, tmp_path / "out", workers=1, quiet=True, processes=False, retry_failed=True
    )
    assert retried.ran == [1] and retried.skipped == [0]
    assert retried.dataset["reason"].values[1].startswith("SimulationError")


def test_ctrl_c_keeps_the_finished_cases_and_a_rerun_completes(tmp_path, monkeypatch):
    import cable_ocp.sweep.runner as runner

    spec = load_sweep(write(tmp_path, GRID))
    real_write, calls = runner.write_case, []

    def write_then_interrupt(folder, case, record):
        calls.append(case.index)
        if len(calls) == 2:
            raise KeyboardInterrupt  # Ctrl-C while the second case is being saved
        return real_write(folder, case, record)

    monkeypatch.setattr(runner, "write_case", write_then_interrupt)
    report = run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    assert report.interrupted and not report.all_ok
    statuses = list(open_sweep(tmp_path / "out")["status"].values)
    assert statuses.count("ok") == 1 and statuses.count("not run") == 3
    monkeypatch.setattr(runner, "write_case", real_write)
    rerun = run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    assert len(rerun.ran) == 3 and len(rerun.skipped) == 1 and rerun.all_ok


def test_a_lost_task_is_recorded_and_retried(tmp_path, monkeypatch):
    """A case whose task dies (its worker lost) is saved as failed with the reason, the other
    cases are saved as they finish, and ``retry_failed`` runs only that case again."""
    from cable_ocp.sweep import execute

    real = execute.run_case

    def dies_at_the_fast_tow(scene, *args, **kwargs):
        if scene.top.tow_profile.surge_speed == 1.0:
            raise RuntimeError("worker tcp://127.0.0.1:1 died")
        return real(scene, *args, **kwargs)

    text = HEADER + '[grid]\n"top.tow.surge_speed" = [0.5, 1.0]\n'
    spec = load_sweep(write(tmp_path, text))
    out = tmp_path / "out"
    monkeypatch.setattr(execute, "run_case", dies_at_the_fast_tow)
    report = run_sweep(spec, out, workers=1, quiet=True, processes=False)
    ds = report.dataset
    assert list(ds["status"].values) == ["ok", "failed"]
    assert ds["reason"].values[1] == "task lost: RuntimeError: worker tcp://127.0.0.1:1 died"
    monkeypatch.setattr(execute, "run_case", real)
    again = run_sweep(spec, out, workers=1, quiet=True, processes=False, retry_failed=True)
    assert again.ran == [1] and again.skipped == [0]
    assert list(again.dataset["status"].values) == ["ok", "ok"]


# --- issue 17: the sweep file, the folder, the defaults -----------------------------------------

TWO = HEADER + '[grid]\n"top.tow.surge_speed" = [0.5, 1.0]\n'


def sweep_cli(args, capsys) -> tuple[int, str, str]:
    """``cable-ocp sweep ...`` in-process: (exit code, stdout, stderr)."""
    from cable_ocp import cli

    code = cli.main(["sweep", *map(str, args)])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_exit_2(code, out, err, fragment):
    assert code == 2, err
    assert err.count("\n") == 1 and err.startswith("cable-ocp sweep: error: "), err
    assert fragment in err and "Traceback" not in out + err


def test_binary_sweep_file_is_named(tmp_path, capsys):
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff")
    code, out, err = sweep_cli([path, "--out", tmp_path / "out"], capsys)
    assert_one_line_exit_2(code, out, err, f"sweep file {path}: not a text file")
    assert not (tmp_path / "out").exists()


def test_bundled_example_sweeps_load_by_name():
    from cable_ocp.scene.bundled import models_dir
    from cable_ocp.sweep.spec import bundled_sweeps

    assert set(bundled_sweeps()) >= {"tow_speeds", "ocp_sample"}
    spec = load_sweep("tow_speeds")
    assert spec.path == models_dir() / "sweeps" / "tow_speeds.toml"
    assert spec.scene_path == models_dir() / "small_tow.toml" and len(spec.cases) == 6
    with pytest.raises(ValueError, match="not found .nor a bundled example: ocp_sample"):
        load_sweep("no_such_sweep")


def test_sweep_defaults_are_the_registrys(tmp_path, monkeypatch):
    """No [optimizer]: optimize()'s settings (the registry's), not the scene's full model."""
    from cable_ocp.control.settings import ModelSettings
    from cable_ocp.control.solvers import ocp_settings

    base = f'scene = "{MODELS / "small_tow.toml"}"\ntask = "optimize"\n'  # 21 s: 42 steps of 0.5 s
    duration = '[set]\n"numerics.duration" = 21.0\n'
    for method, solver in (("ipopt", "gauss-newton"), ("shooting", "gauss-newton"),
                           ("nelder-mead", "nelder-mead")):  # fmt: skip
        spec = load_sweep(write(tmp_path, base + f'method = "{method}"\n' + duration))
        assert spec.settings == ocp_settings(solver)
        assert spec.settings.elements is None  # derived from each case's scene, as optimize()
        options = f'method = "{method}"\n[optimizer]\nelements = 4\n' + duration
        spec = load_sweep(write(tmp_path, base + options))
        assert spec.settings == ocp_settings(solver, model=ModelSettings(elements=4))
    spec = load_sweep(write(tmp_path, base + '[optimizer]\nsolver = "ipopt"\n' + duration))
    assert spec.settings == ocp_settings("ipopt")


@pytest.mark.parametrize("content", ["[1, 2]", "copied"])
def test_a_user_folder_with_a_sweep_json_is_refused_and_untouched(tmp_path, capsys, content):
    sweep = write(tmp_path, TWO)
    folder = tmp_path / "mine"
    folder.mkdir()
    if content == "copied":  # a copy of a real manifest, beside the user's own sweep.toml
        run_sweep(load_sweep(sweep), tmp_path / "real", workers=1, quiet=True, processes=False)
        (folder / "sweep.json").write_bytes((tmp_path / "real" / "sweep.json").read_bytes())
    else:
        (folder / "sweep.json").write_text(content)
    (folder / "sweep.toml").write_text("# my notes\n")
    before = {p.name: p.read_bytes() for p in folder.iterdir()}
    code, out, err = sweep_cli([sweep, "--out", folder, "--workers", "1", "--quiet"], capsys)
    assert_one_line_exit_2(code, out, err, "holds no sweep of cable-ocp (no .cable_ocp-results")
    assert {p.name: p.read_bytes() for p in folder.iterdir()} == before


def test_another_commands_results_folder_is_refused(tmp_path):
    folder = tmp_path / "res"
    folder.mkdir()
    (folder / ".cable_ocp-results").write_text("")
    (folder / "summary.json").write_text("{}")
    with pytest.raises(ValueError, match="holds the results of another cable-ocp command"):
        run_sweep(load_sweep(write(tmp_path, TWO)), folder, quiet=True, processes=False)
    assert sorted(p.name for p in folder.iterdir()) == [".cable_ocp-results", "summary.json"]


@pytest.fixture
def two_done(tmp_path):
    """A finished 2-case sweep: (spec, folder)."""
    spec = load_sweep(write(tmp_path, TWO))
    run_sweep(spec, tmp_path / "out", workers=1, quiet=True, processes=False)
    return spec, tmp_path / "out"


@pytest.mark.parametrize("damage", ["empty", "truncated"])
def test_a_damaged_case_file_is_named_and_retry_failed_recomputes_it(two_done, damage):
    spec, out = two_done
    path = case_path(out, 1)
    good = open_sweep(out)["omega"].values[1]
    path.write_bytes(b"" if damage == "empty" else path.read_bytes()[:500])
    with pytest.raises(ValueError) as error:
        run_sweep(spec, out, workers=1, quiet=True, processes=False)
    message = str(error.value)
    assert message.startswith(f"{path}: damaged case file (") and "--retry-failed" in message
    assert ("empty file" in message) == (damage == "empty")
    report = run_sweep(spec, out, workers=1, quiet=True, processes=False, retry_failed=True)
    assert report.ran == [1] and report.skipped == [0] and report.all_ok
    assert report.dataset["omega"].values[1] == good


def test_a_damaged_manifest_is_named_and_deleting_it_recovers(two_done):
    spec, out = two_done
    stamps = {k: os.stat(case_path(out, k)).st_mtime_ns for k in (0, 1)}
    for damage in ("", '{"cases": [1, 2]}', "[" * 100_000):
        (out / "sweep.json").write_text(damage)
        with pytest.raises(ValueError) as error:
            run_sweep(spec, out, quiet=True, processes=False)
        assert str(error.value).startswith(f"{out / 'sweep.json'}: damaged sweep manifest (")
        assert "delete it and rerun the same command" in str(error.value)
    (out / "sweep.json").unlink()
    report = run_sweep(spec, out, quiet=True, processes=False)
    assert report.ran == [] and report.skipped == [0, 1] and report.all_ok
    assert {k: os.stat(case_path(out, k)).st_mtime_ns for k in (0, 1)} == stamps


def test_leftover_scratch_files_are_removed_by_the_next_run(two_done):
    spec, out = two_done
    left = [out / "cases" / ".case_00001.nc.0badc0de.tmp", out / "cases" / ".case_00000.nc.x1y2",
            out / ".sweep.nc.deadbeef.tmp", out / ".sweep.json.01234567.tmp"]  # fmt: skip
    for path in left:
        path.write_bytes(b"partial")
    keep = out / "cases" / "notes.txt"  # not a scratch file of ours: kept
    keep.write_text("mine")
    run_sweep(spec, out, quiet=True, processes=False)
    assert not any(path.exists() for path in left) and keep.exists()


def test_results_files_have_the_folders_permissions(tmp_path):
    import stat

    folder = tmp_path / "out"
    folder.mkdir(mode=0o750)
    folder.chmod(0o750)
    run_sweep(load_sweep(write(tmp_path, TWO)), folder, workers=1, quiet=True, processes=False)
    files = [p for p in folder.rglob("*") if p.is_file()]
    assert {p.name for p in files} >= {"sweep.nc", "sweep.json", "sweep.toml", "case_00000.nc"}
    for path in files:
        assert stat.S_IMODE(path.stat().st_mode) == 0o640, path


def test_workers_are_bounded_and_not_given_with_a_scheduler(tmp_path, capsys):
    from cable_ocp.sweep.runner import usable_cores

    sweep = write(tmp_path, TWO)
    too_many = usable_cores() + 1
    for extra, message in [
        (["--workers", too_many], f"--workers {too_many}: must be 1 to {usable_cores()}"),
        (["--workers", 0], "--workers 0: must be 1 to"),
        (["--workers", 1, "--scheduler", "tcp://127.0.0.1:1"], "give one of the two"),
        (["--engine-timeout", "inf"], "--engine-timeout inf: must be finite and > 0"),
    ]:
        code, out, err = sweep_cli([sweep, "--out", tmp_path / "out", *extra], capsys)
        assert_one_line_exit_2(code, out, err, message)
    assert not (tmp_path / "out").exists()


def test_a_second_sweep_into_a_busy_folder_is_refused(tmp_path, capsys):
    from cable_ocp.sweep.store import folder_lock

    spec = load_sweep(write(tmp_path, TWO))
    out = tmp_path / "out"
    with folder_lock(out, "cable-ocp sweep first.toml"):  # as if another process ran it
        code, _, err = sweep_cli([spec.path, "--out", out, "--workers", "1", "--quiet"], capsys)
        assert code == 2 and f"--out {out} is in use by another sweep (pid {os.getpid()}" in err
        assert "first.toml" in err and not (out / "cases").exists()
    report = run_sweep(spec, out, workers=1, quiet=True, processes=False)  # free again
    assert sorted(report.ran) == [0, 1]


def test_claiming_a_folder_in_parallel_never_reads_half_a_manifest(tmp_path):
    import threading

    from cable_ocp.sweep.store import check_folder, claim_folder

    spec = load_sweep(write(tmp_path, GRID))
    out = tmp_path / "out"
    claim_folder(out, spec)
    errors: list[BaseException] = []

    def race():
        try:
            for _ in range(150):
                claim_folder(out, spec)
                check_folder(out, spec)
        except BaseException as error:  # noqa: BLE001 - collected for the assert
            errors.append(error)

    threads = [threading.Thread(target=race) for _ in range(4)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert errors == []
    assert not list(out.glob(".*.tmp"))


def test_a_sweep_folder_of_an_older_version_is_refused_with_how_to_resume(two_done, capsys):
    spec, out = two_done
    (out / ".cable_ocp-results").unlink()  # as cable_ocp 0.1 left its sweep folders
    code, output, err = sweep_cli([spec.path, "--out", out, "--workers", "1", "--quiet"], capsys)
    assert_one_line_exit_2(code, output, err, f"add an empty file {out / '.cable_ocp-results'}")
    (out / ".cable_ocp-results").write_text("")
    report = run_sweep(spec, out, quiet=True, processes=False)
    assert report.ran == [] and report.skipped == [0, 1]


# --- paths, implausible inputs and memory, before any case runs (issue 24) --------------------


def test_a_sweeps_relative_grid_paths_resolve_against_the_sweep_file(tmp_path):
    """In [set] and in [grid], as the scene path does; not against the base scene's folder."""
    folder = tmp_path / "study"
    folder.mkdir()
    for name in ("mine.nc", "other.nc"):
        (folder / name).write_bytes((MODELS / "data" / "survey_grid.nc").read_bytes())
    set_path = write(folder, f'scene = "{MODELS / "survey.toml"}"\n[set]\n"seabed.grid.file" = '
                     '"mine.nc"\n', "set.toml")  # fmt: skip
    spec = load_sweep(set_path)
    assert spec.cases[0].scene.seabed.grid.file == str(folder / "mine.nc")
    grid_path = write(folder, f'scene = "{MODELS / "survey.toml"}"\n[grid]\n"seabed.grid" = '
                      '[{file = "mine.nc"}]\n"seabed.grid.file" = ["mine.nc", "other.nc"]\n',
                      "grid.toml")  # fmt: skip
    with pytest.raises(ValueError, match="a swept value must be a number, a string"):
        load_sweep(grid_path)  # a table is not a coordinate
    grid_path.write_text(f'scene = "{MODELS / "survey.toml"}"\n[grid]\n'
                         '"seabed.grid.file" = ["mine.nc", "other.nc"]\n')  # fmt: skip
    spec = load_sweep(grid_path)
    files = [case.scene.seabed.grid.file for case in spec.cases]
    assert files == [str(folder / "mine.nc"), str(folder / "other.nc")]
    assert [case.overrides["seabed.grid.file"] for case in spec.cases] == ["mine.nc", "other.nc"]


def test_an_implausible_sea_state_in_one_case_is_refused_before_any_case_runs(tmp_path):
    path = write(tmp_path, f'scene = "{MODELS / "survey.toml"}"\n[grid]\n'
                 '"top.heave.sea_state.significant_height" = [2.0, 1e50]\n')  # fmt: skip
    with pytest.raises(ValueError) as error:
        load_sweep(path)
    assert str(error.value).startswith(
        "grid.top.heave.sea_state.significant_height[1] = 1e+50 (case 1): "
        "top.heave.sea_state.significant_height = 1e+50 is out of range: must be > 0 and <= 30"
    )


def test_a_case_whose_outputs_cannot_fit_is_refused_before_any_case_runs(tmp_path):
    """5e7 kept states of a 100-element cable: about 0.5 TB, on any machine of today."""
    path = write(tmp_path, HEADER + '[grid]\n"numerics.output_every" = [100000, 1]\n'
                 '"numerics.duration" = [1000.0]\n"numerics.step" = [2e-5]\n'
                 '"model.elements" = [100]\n')  # fmt: skip
    with pytest.raises(ValueError) as error:
        load_sweep(path)
    text = str(error.value)
    assert text.startswith("case 1: numerics.output_every = 1 (numerics.step = 2e-05 s, ")
    assert "need about" in text and "numerics.output_every = " in text and "\n" not in text
