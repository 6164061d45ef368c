"""The command line: bad input is one line on stderr and exit 2, before any heavy work.

The fuzz tests drive the CLI in-process with bad options and with mutants of the bundled scenes
(deterministic, see conftest.py): each must be refused with one ``cable-ocp CMD: error:`` line and
exit 2 before any simulation (simulating fails the test).
"""

import json
import shutil
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from cable_ocp import cli
from cable_ocp.cli.optimiser_options import optimize_settings
from cable_ocp.control import optimization
from cable_ocp.scene.output import MARKER
from cable_ocp.scene.schema import SceneError, load_scene
from cable_ocp.simulation import run as simulation
from cable_ocp.simulation.trajectory import Trajectory
from cable_ocp.studies import convergence as studies
from cable_ocp.studies import validation

MODELS = Path(__file__).resolve().parent.parent / "models"
HANGING = str(MODELS / "hanging.toml")


@pytest.fixture
def no_heavy_work(monkeypatch):
    """Make every simulation, optimisation, validation and study fail the test if it starts."""

    def forbidden(*args, **kwargs):
        pytest.fail("bad input must be refused before any heavy work")

    for module, name in [(simulation, "simulate"), (optimization, "optimize"),
                         (validation, "catenary_check"), (studies, "step_halving"),
                         (studies, "element_convergence"), (studies, "end_positions")]:  # fmt: skip
        monkeypatch.setattr(module, name, forbidden)


def run_cli(args, capsys):
    """``cli.main(args)`` in-process: (exit code, stdout, stderr)."""
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


# (arguments, a fragment of the message); the scene is HANGING where a scene is needed.
BAD_ARGUMENTS = [
    (["simulate", "missing.toml", "--out", "o"], "missing.toml: scene file not found"),
    (["simulate", MODELS, "--out", "o"], "is a folder, not a scene file"),
    (["simulate", HANGING, "--out", "o", "--knots", "nan"], "knot 1 = 'nan': must be finite"),
    (["simulate", HANGING, "--out", "o", "--knots", "a,b"], "knot 1 = 'a' is not a number"),
    (["simulate", HANGING, "--out", "o", "--knots", ""], "--knots: empty"),
    (["simulate", HANGING, "--out", "o", "--knots", "1,2"],
     "--knots: 2 angles given; the scene has winch.knots = 14"),
    (["simulate", HANGING, "--out", "o", "--set", "model.elements=1e400"],
     "model.elements: expected an integer, got float inf"),
    (["simulate", HANGING, "--out", "o", "--set", f"model.elements={10**400}"],
     "model.elements = 1000000"),
    (["simulate", HANGING, "--out", "o", "--set", "cable.length=1e400"],
     "cable.length = inf is out of range: must be finite"),
    (["simulate", HANGING, "--out", "o", "--set", "cable.density=500"],
     "cable.density = 500.0 kg/m^3 is not denser than environment.water_density = 1025.0 kg/m^3"),
    (["simulate", HANGING, "--out", "o", "--set", "model.elements"], "expected KEY=VALUE"),
    (["validate", "--elements", "0"], "argument --elements: 0 is out of range: must be 1 to 1000"),
    (["validate", "--elements", "1e400"], "argument --elements: expected an integer"),
    (["optimize", HANGING, "--out", "o", "--step", "nan"], "argument --step: 'nan' is out of"),
    (["optimize", HANGING, "--out", "o", "--step", "1e400"], "argument --step: '1e400' is out"),
    (["optimize", HANGING, "--out", "o", "--intervals", "0"], "argument --intervals: 0 is out"),
    (["optimize", HANGING, "--out", "o", "--quiet", "--verbose"], "not allowed with argument"),
    (["compare", HANGING, "missing.toml", "--out", "o"], "missing.toml: scene file not found"),
    (["lower", "deploy", "--out", "o", "--hover=nan"], "argument --hover: 'nan' is out of range"),
    (["lower", "deploy", "--out", "o", "--hover=-5"], "argument --hover: '-5' is out of range"),
    (["compare", HANGING, "--out", "o", "--solver", "nelder-mead"],
     "--solver nelder-mead: compare runs Nelder-Mead anyway, beside a shooting solver; give "
     "--solver gauss-newton or ipopt"),
    (["study", "step", "--out", "o"], "study step needs a scene file"),
    (["study", "stability", HANGING, "--out", "o"], "study stability takes no scene"),
    (["study", "payout", HANGING, "--out", "o"], "study payout takes no scene"),
]  # fmt: skip


@pytest.mark.parametrize(("args", "message"), BAD_ARGUMENTS, ids=lambda v: None)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path, monkeypatch, capsys, no_heavy_work, args, message
):
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(args, capsys)
    assert code == 2
    assert message in err
    assert f"cable-ocp {args[0]}: error: " in err and "Traceback" not in err + out
    assert err.strip().splitlines()[-1].startswith(f"cable-ocp {args[0]}: error: ")
    assert list(tmp_path.iterdir()) == []  # nothing written


@pytest.mark.parametrize("target", [".", "here", "file.txt"])
def test_out_that_would_delete_files_is_refused_before_simulating(
    tmp_path, monkeypatch, capsys, no_heavy_work, target
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "file.txt").write_text("mine")
    (tmp_path / "here").mkdir()
    (tmp_path / "here" / "data.csv").write_text("1,2")
    code, _, err = run_cli(["simulate", HANGING, "--out", target], capsys)
    assert code == 2 and "nothing was written" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.txt", "here"]
    assert (tmp_path / "here" / "data.csv").read_text() == "1,2"


def test_simulate_writes_a_marked_folder_and_replaces_it(tmp_path, capsys):
    out = tmp_path / "res"
    args = ["simulate", HANGING, "--out", out, "--set", "numerics.duration=2.0", "--quiet"]
    assert run_cli(args, capsys)[0] == 0
    assert (out / MARKER).is_file()
    assert stat.S_IMODE(out.stat().st_mode) & 0o055 == 0o055  # group and others may read
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "hanging" and summary["omega"] == 0.0
    (out / "summary.json").write_text("stale")
    assert run_cli(args, capsys)[0] == 0  # a previous results folder is replaced
    assert json.loads((out / "summary.json").read_text())["scene"] == "hanging"
    assert [p.name for p in tmp_path.iterdir()] == ["res"]


def test_hessian_exact_runs_the_interpreted_model(capsys):
    parser = cli.build_parser()
    args = parser.parse_args(["optimize", HANGING, "--out", "o", "--hessian", "exact"])
    settings = optimize_settings(args)
    assert settings.solver == "ipopt" and settings.solver_settings.hessian == "exact"
    assert settings.transcription.compiled is False
    assert "--hessian exact runs the interpreted model" in capsys.readouterr().err
    args = parser.parse_args(["optimize", HANGING, "--out", "o"])
    assert optimize_settings(args).transcription.compiled is True


@pytest.mark.parametrize(
    ("flags", "quiet", "verbose"),
    [([], False, False), (["--verbose"], False, True), (["--quiet"], True, False)],
)
@pytest.mark.parametrize("command", ["optimize", "compare"])
def test_quiet_and_verbose_reach_the_optimiser(
    tmp_path, monkeypatch, capsys, command, flags, quiet, verbose
):
    calls = []

    def record(scene, solver=None, settings=None, **kwargs):
        calls.append(kwargs)
        raise ValueError("stopped by the test")

    monkeypatch.setattr(optimization, "optimize", record)
    code, _, err = run_cli([command, HANGING, "--out", tmp_path / "o", *flags], capsys)
    assert code == 2 and "stopped by the test" in err
    assert calls[0]["quiet"] is quiet and calls[0]["verbose"] is verbose


@pytest.mark.parametrize(("flags", "compiled"), [([], True), (["--interpreted"], False)])
def test_simulate_compiles_unless_interpreted(tmp_path, monkeypatch, capsys, flags, compiled):
    calls = []

    def record(scene, **kwargs):
        calls.append(kwargs)
        raise ValueError("stopped by the test")

    monkeypatch.setattr(simulation, "simulate", record)
    code, _, err = run_cli(["simulate", HANGING, "--out", tmp_path / "o", *flags], capsys)
    assert code == 2 and "stopped by the test" in err
    assert calls[0]["compiled"] is compiled


def test_simulate_animates_when_asked(tmp_path, monkeypatch, capsys):
    """--animate writes animation.gif through plots.animate (drawn in tests/test_animation.py)."""
    from cable_ocp import plots

    calls = []

    def record(trajectory, path, clearance_depth):
        calls.append((trajectory.scene_name, path.name, clearance_depth))
        path.write_bytes(b"GIF89a")

    monkeypatch.setattr(plots, "animate", record)
    out = tmp_path / "out"
    args = ["simulate", HANGING, "--out", out, "--set", "numerics.duration=2.0", "--quiet",
            "--interpreted", "--animate"]  # fmt: skip
    assert run_cli(args, capsys)[0] == 0
    assert calls == [("hanging", "animation.gif", 5.0)] and (out / "animation.gif").exists()
    assert cli.build_parser().parse_args(["optimize", HANGING, "--out", "o", "--animate"]).animate


@pytest.mark.parametrize("shooting", ["single", "multiple"])
def test_shooting_option_reaches_the_ipopt_settings(tmp_path, monkeypatch, capsys, shooting):
    calls = []

    def record(scene, solver=None, settings=None, **kwargs):
        calls.append(settings.transcription)
        raise ValueError("stopped by the test")

    monkeypatch.setattr(optimization, "optimize", record)
    args = ["optimize", HANGING, "--out", tmp_path / "o", "--shooting", shooting, "--quiet"]
    code, _, err = run_cli(args, capsys)
    assert code == 2 and "stopped by the test" in err
    assert calls[0].shooting == shooting


def test_help_exits_0(capsys):
    assert cli.main(["--help"]) == 0
    assert "simulate" in capsys.readouterr().out


def _console_script() -> list[str]:
    script = shutil.which("cable-ocp")
    return [script] if script else [sys.executable, "-m", "cable_ocp.cli"]


def test_console_script_exit_codes_end_to_end(tmp_path):
    (tmp_path / "notes.txt").write_text("keep me")
    runs = {
        "missing": ["simulate", "missing.toml", "--out", "res"],
        "cwd": ["simulate", HANGING, "--out", "."],
    }
    for name, args in runs.items():
        done = subprocess.run(_console_script() + args, cwd=tmp_path, capture_output=True,
                              text=True, timeout=120)  # fmt: skip
        assert done.returncode == 2, name
        assert done.stderr.count("\n") == 1 and done.stderr.startswith("cable-ocp simulate: error")
        assert "Traceback" not in done.stderr + done.stdout
    assert [p.name for p in tmp_path.iterdir()] == ["notes.txt"]
    assert (tmp_path / "notes.txt").read_text() == "keep me"


# --- fuzz: bad command lines and mutants of the bundled scene files ----------------------------


def assert_refused(args, capsys) -> str:
    """Run the CLI in-process; assert exit 2 and one error line without a traceback."""
    code, out, err = run_cli(args, capsys)
    assert code == 2, (args, out, err)
    assert "Traceback" not in out + err, args
    assert err.strip().splitlines()[-1].startswith(f"cable-ocp {args[0]}: error: "), err
    return err


@pytest.mark.parametrize("name", sorted(p.stem for p in MODELS.glob("*.toml")))
def test_refused_scene_mutants_are_refused_by_every_command(
    tmp_path, capsys, no_heavy_work, mutants, name
):
    """The first 12 mutants that load_scene refuses: the CLI refuses them too, before simulating."""
    refused = []
    for k, (text, _) in enumerate(mutants(name)):
        path = tmp_path / f"mutant_{k}.toml"
        path.write_bytes(text)
        try:
            load_scene(path)
        except SceneError:
            refused.append(path)
        if len(refused) == 12:
            break
    assert refused
    for path in refused:
        for command in (["simulate", path], ["optimize", path], ["validate", path]):
            assert_refused([*command, "--out", tmp_path / "out"], capsys)
    assert not (tmp_path / "out").exists()


BAD_OPTIONS = {
    "--knots": ["nan", "inf", "a,b", "1,,2", "", " ", "1e400", "0x1", "1;2"],
    "--set": ["model.elements=nan", "model.elements=0", "cable.length=-1", "numerics.step=0",
              "top.motion=42", "seabed.hills=3", "x", "=", "cable=1", "model.elements=1e400",
              f"model.elements={10**400}", "cable.density=500", "numerics.step=1e-300",
              "cable.diameter=1e200", "environment.current=[1,2]"],
}  # fmt: skip
BAD_INTEGERS = ["nan", "-1", "1e400", "", "a", "1.5", "9" * 5000, "0x10"]
BAD_OPTIMISER = {
    "--elements": [*BAD_INTEGERS, "0", "1001"],
    "--intervals": [*BAD_INTEGERS, "0"],
    "--max-iter": [*BAD_INTEGERS, "0"],
    "--max-evaluations": [*BAD_INTEGERS, "0"],
    "--refinements": [*BAD_INTEGERS, "101"],
    "--step": ["nan", "inf", "-inf", "0", "-0.5", "1e400", "", "a"],
    "--method": ["", "ipopt2", "nelder-mead", "shooting"],
    "--solver": ["", "sqp", "Gauss-Newton"],
    "--hessian": ["", "approx"],
}


@pytest.mark.parametrize("option", sorted(BAD_OPTIONS))
def test_bad_simulate_options_are_refused(tmp_path, capsys, no_heavy_work, option):
    for value in BAD_OPTIONS[option]:
        assert_refused(["simulate", HANGING, "--out", tmp_path / "o", option, value], capsys)


@pytest.mark.parametrize("option", sorted(BAD_OPTIMISER))
def test_bad_optimiser_options_are_refused(tmp_path, capsys, no_heavy_work, option):
    for value in BAD_OPTIMISER[option]:
        assert_refused(["optimize", HANGING, "--out", tmp_path / "o", option, value], capsys)
        if option not in ("--method", "--refinements"):
            assert_refused(["compare", HANGING, "--out", tmp_path / "o", option, value], capsys)


def test_bad_validate_elements_are_refused(capsys, no_heavy_work):
    for value in [*BAD_INTEGERS, "0", "1001"]:
        assert_refused(["validate", "--elements", "5", value], capsys)


# --- simulate end to end -----------------------------------------------------------------------

FIGURES = {"end_trajectory.png", "clearance.png", "cable_shapes.png", "winch_angle.png",
           "tension.png"}  # fmt: skip


def test_cli_simulate_writes_results(tmp_path, capsys):
    out = tmp_path / "out"
    args = ["simulate", HANGING, "--out", str(out),
            "--set", "numerics.duration=10.0", "--quiet"]  # fmt: skip
    assert cli.main(args) == 0
    names = {p.name for p in out.iterdir()}
    written = {"trajectory.nc", "summary.json", ".cable_ocp-results"}
    assert names == written | FIGURES
    assert all((out / f).stat().st_size > 1000 for f in FIGURES)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "hanging"
    run = Trajectory.load(out / "trajectory")
    assert run.time[-1] == 10.0 and run.scene_name == "hanging"
    # Hanging at rest stays at rest: rise tolerance 1e-6 m.
    assert abs(summary["end_rise"]) < 1e-6
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no scratch folder left over
    assert "written to" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("scene", "step", "message"),
    [("hanging", 7.0, "must divide"), ("paper_flat", 5.0, "bond residual")],
    ids=["step does not divide", "step blows up"],
)
def test_cli_failing_run_writes_nothing(tmp_path, capsys, scene, step, message):
    # A cable at rest stays at rest at any step, so the blow-up needs the towed scene.
    settings = ["--set", "numerics.duration=10.0", "--set", f"numerics.step={step}"]
    args = ["simulate", str(MODELS / f"{scene}.toml"), "--out", str(tmp_path / "bad"), *settings,
            "--quiet"]  # fmt: skip
    assert cli.main(args) != 0
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []  # neither "bad" nor a hidden scratch folder


def test_cli_failure_while_writing_keeps_the_old_folder(tmp_path, monkeypatch, capsys):
    """A failure inside the atomic block (here: a figure) leaves an existing folder untouched."""
    from cable_ocp import plots

    def broken(*args, **kwargs):
        raise RuntimeError("figure failed")

    kept = tmp_path / "kept"
    kept.mkdir()
    (kept / ".cable_ocp-results").write_text("")  # a previous results folder
    (kept / "old.txt").write_text("previous results")
    monkeypatch.setattr(plots, "winch_angle", broken)
    args = ["simulate", HANGING, "--out", str(kept),
            "--set", "numerics.duration=2.0", "--quiet"]  # fmt: skip
    assert cli.main(args) != 0
    assert "figure failed" in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["kept"]
    assert sorted(p.name for p in kept.iterdir()) == [".cable_ocp-results", "old.txt"]


# --- issue 17: mpc weights, optimiser defaults, one exit code for a read-only --out ---------------


@pytest.mark.parametrize("value", ["inf", "-inf", "nan", "-1", "1e400", "a"])
def test_mpc_rate_weight_must_be_finite(tmp_path, monkeypatch, capsys, no_heavy_work, value):
    from cable_ocp.control.closed_loop import loop

    monkeypatch.setattr(loop, "mpc", lambda *a, **k: pytest.fail("refused before any work"))
    err = assert_refused(["mpc", HANGING, "--out", tmp_path / "o", "--rate-weight", value], capsys)
    assert "argument --rate-weight: " in err
    assert not (tmp_path / "o").exists()


def test_optimiser_defaults_are_the_registrys(monkeypatch):
    """Unset options are optimize()'s defaults: the CLI keeps no copy of them; the options given
    are built into OcpSettings by the settings classes (ocp_settings_from)."""
    from cable_ocp.control.settings import ModelSettings
    from cable_ocp.control.solvers import SOLVERS, ocp_settings

    parser = cli.build_parser()
    args = parser.parse_args(["optimize", HANGING, "--out", "o"])
    assert optimize_settings(args) == ocp_settings()
    simplex = parser.parse_args(["optimize", HANGING, "--out", "o", "--solver", "nelder-mead"])
    assert optimize_settings(simplex) == ocp_settings("nelder-mead")
    given = parser.parse_args(["optimize", HANGING, "--out", "o", "--elements", "5", "--step",
                               "0.25", "--max-iter", "7", "--solver", "ipopt"])  # fmt: skip
    ipopt = SOLVERS["ipopt"].settings(max_iter=7)
    assert optimize_settings(given) == ocp_settings("ipopt", ipopt, ModelSettings(5, 0.25))


def test_mpc_options_are_the_settings_fields_with_their_defaults():
    """Unset mpc options are MpcSettings()'s own; --no-heave-feedback turns its True field off."""
    from cable_ocp.cli.mpc import settings_from
    from cable_ocp.control.closed_loop.settings import MpcSettings
    from cable_ocp.control.settings import ModelSettings

    parser = cli.build_parser()
    unset = settings_from(parser.parse_args(["mpc", HANGING, "--out", "o"]))
    assert unset == MpcSettings(model=ModelSettings())
    given = ["mpc", HANGING, "--out", "o", "--no-heave-feedback", "--solver", "ipopt",
             "--sample", "2", "--elements", "3"]  # fmt: skip
    assert settings_from(parser.parse_args(given)) == MpcSettings(
        sample=2.0, solver="ipopt", heave_feedback=False, model=ModelSettings(3)
    )


@pytest.mark.parametrize(
    ("options", "solver"),
    [([], "gauss-newton"), (["--shooting", "single"], "gauss-newton"),
     (["--shooting", "multiple"], "ipopt"), (["--hessian", "limited-memory"], "ipopt"),
     (["--max-iter", "3", "--control", "spline"], "gauss-newton")],
)  # fmt: skip
def test_an_option_of_another_shooting_solver_picks_it(options, solver):
    """Without --solver, an option that only IPOPT takes picks IPOPT; the registry says which."""
    args = cli.build_parser().parse_args(["optimize", HANGING, "--out", "o", *options])
    assert optimize_settings(args).solver == solver


def test_method_is_refused_saying_it_became_solver(tmp_path, capsys, no_heavy_work):
    """Issue 41: --method and --solver overlapped; --method is refused, naming --solver."""
    err = assert_refused(["optimize", HANGING, "--out", tmp_path / "o", "--method",
                          "nelder-mead"], capsys)  # fmt: skip
    assert "argument --method: became --solver: --solver nelder-mead is the paper's" in err
    assert "--method" not in cli.build_parser()._subparsers._group_actions[0].choices[
        "optimize"].format_help()  # fmt: skip


def _sweep_file(tmp_path) -> Path:
    path = tmp_path / "sweep.toml"
    path.write_text(f'scene = "{HANGING}"\n[set]\n"numerics.duration" = 1.0\n')
    return path


# Every command that takes --out: (arguments before --out).
OUT_COMMANDS = {
    "simulate": ["simulate", HANGING],
    "optimize": ["optimize", HANGING],
    "compare": ["compare", HANGING],
    "mpc": ["mpc", HANGING],
    "sweep": ["sweep", "SWEEP"],
    "validate": ["validate", HANGING],
    "study step": ["study", "step", HANGING],
    "study stability": ["study", "stability"],
}


@pytest.mark.parametrize("command", sorted(OUT_COMMANDS))
def test_out_in_a_read_only_folder_is_exit_2_for_every_command(
    tmp_path, monkeypatch, capsys, no_heavy_work, command
):
    """Bad input (README): one line naming the folder, exit 2, nothing written, no work done."""
    import os

    from cable_ocp.control.closed_loop import loop

    monkeypatch.setattr(loop, "mpc", lambda *a, **k: pytest.fail("refused before any work"))
    locked = tmp_path / "locked"
    locked.mkdir()
    real_access = os.access

    def access(path, mode, *args, **kwargs):  # read-only for root too, who may write anywhere
        if mode & os.W_OK and Path(path).resolve().is_relative_to(locked):
            return False
        return real_access(path, mode, *args, **kwargs)

    monkeypatch.setattr(os, "access", access)
    locked.chmod(0o555)
    try:
        args = [a if a != "SWEEP" else _sweep_file(tmp_path) for a in OUT_COMMANDS[command]]
        err = assert_refused([*args, "--out", locked / "res"], capsys)
        assert f"the folder {locked} is not writable" in err and err.count("\n") == 1
        assert list(locked.iterdir()) == []
    finally:
        locked.chmod(0o755)
