"""One exit-code mapping for every command (cable_ocp.cli.exits), as the README states it.

An error that ends a command gets the same code whichever command raised it: 2 for bad input,
3 for work that failed (a run that blew up: ``SimulationError``), 1 for the file system, 130 for
an interrupt; each one line on stderr, without a traceback.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from cable_ocp import cli
from cable_ocp.cli import exits
from cable_ocp.lowering import results
from cable_ocp.scene import schema
from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.simulation.seabed import OffGridError
from cable_ocp.simulation.statics import EquilibriumError
from cable_ocp.sweep import spec

MODELS = Path(__file__).resolve().parent.parent / "models"
HANGING = str(MODELS / "hanging.toml")

# Every command that reads a scene (load_scene), a result (load_result) or a sweep (load_sweep).
COMMANDS = {
    "simulate": ["simulate", HANGING],
    "optimize": ["optimize", HANGING],
    "compare": ["compare", HANGING],
    "mpc": ["mpc", HANGING],
    "lower": ["lower", HANGING],
    "study": ["study", "step", HANGING],
    "validate": ["validate", HANGING],
    "replay": ["replay", "RESULT"],
    "sweep": ["sweep", "SWEEP"],
}

# (the error, its code, what stderr says after "cable-ocp COMMAND: ").
ERRORS = [
    (KeyboardInterrupt(), 130, "interrupted"),
    (OSError(28, "No space left on device"), 1, "error: [Errno 28] No space left on device"),
    (OverflowError("math range\nerror"), 2, "error: math range error"),
    (ValueError("scene.field = 3: must be 1 to 2"), 2, "error: scene.field = 3: must be 1 to 2"),
    (EquilibriumError("no equilibrium"), 2, "error: no equilibrium"),
    (OffGridError("seabed.grid: the end leaves the grid"), 2,
     "error: seabed.grid: the end leaves the grid"),
    (SimulationError("the bond residual grew to 1 m at t = 3 s"), 3,
     "error: the bond residual grew to 1 m at t = 3 s"),
]  # fmt: skip


@pytest.mark.parametrize("command", sorted(COMMANDS))
@pytest.mark.parametrize(("error", "code", "line"), ERRORS, ids=lambda e: type(e).__name__)
def test_an_error_has_one_exit_code_in_every_command(
    tmp_path, monkeypatch, capsys, command, error, code, line
):
    def fail(*args, **kwargs):
        raise error

    for module, name in ((schema, "load_scene"), (results, "load_result"), (spec, "load_sweep")):
        monkeypatch.setattr(module, name, fail)
    args = [tmp_path / a if a in ("RESULT", "SWEEP") else a for a in COMMANDS[command]]
    result = cli.main([*map(str, args), "--out", str(tmp_path / "o")])
    out, err = capsys.readouterr()
    assert result == code
    assert err == f"cable-ocp {args[0]}: {line}\n" and out == ""
    assert not (tmp_path / "o").exists()


def test_a_run_that_blows_up_in_simulate_exits_3_not_2(tmp_path, capsys):
    """Issue 41: a SimulationError exited 2, the code for bad input. Here a real one: the tow
    on a 2 s RK4 step drifts off its bonds at t = 2 s (nothing is written)."""
    out = tmp_path / "o"
    code = cli.main(["simulate", "small_tow", "--out", str(out), "--quiet", "--interpreted",
                     "--set", "numerics.step=2.0", "--set", "numerics.duration=4.0"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 3, err
    assert err.startswith("cable-ocp simulate: error: bond residual") and err.count("\n") == 1
    assert not out.exists()


@pytest.mark.parametrize(
    ("error", "code"),
    [(BrokenPipeError(), 141), (PermissionError(13, "denied"), 1), (TypeError("a bug"), None),
     (RuntimeError("NetCDF: HDF error"), 2), (UnicodeDecodeError("utf-8", b"\xff", 0, 1, "bad"), 2),
     (OffGridError("start"), 2), (SimulationError("blew up"), 3)],
)  # fmt: skip
def test_the_mapping_takes_the_first_class_that_matches(error, code):
    assert exits.exit_code(error) == code


def test_the_help_states_every_exit_code_the_mapping_gives(capsys):
    """The codes are stated once (exits.MEANINGS) and ``cable-ocp --help`` prints that table."""
    given = {code for _, code, _ in ERRORS} | {exits.exit_code(BrokenPipeError()), 0}
    assert given <= set(exits.MEANINGS)
    assert cli.main(["--help"]) == 0
    text = capsys.readouterr().out
    for code in given:
        assert f"\n{code:>5}  {exits.MEANINGS[code][:40]}" in text
