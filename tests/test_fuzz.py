"""Fuzz: mutants of the bundled scenes and bad command lines never end in a traceback or exit 0.

The mutants are deterministic (a seeded generator). ``load_scene`` must return a valid scene or
raise ``SceneError``; the command line, driven in-process, must refuse every bad input with one
``cable-ocp CMD: error:`` line and exit 2, before any simulation (simulating fails the test).
"""

import re
from pathlib import Path

import numpy as np
import pytest

from cable_ocp import cli, optimization, simulation, studies, validation
from cable_ocp.scene import Scene, SceneError, load_scene, scene_from_dict

MODELS = Path(__file__).resolve().parent.parent / "models"
SCENES = sorted(p.stem for p in MODELS.glob("*.toml"))
MUTANTS_PER_SCENE = 150
BAD_VALUES = [
    '"text"', "1e400", "-1e400", "nan", "-nan", "inf", "-3", "0", "-0.0", '""', "1" + "0" * 400,
    "-" + "9" * 30, "1" * 5000, "true", "[]", "[1, 2]", "[nan, 1, 2]", "{ a = 1 }", "1979-05-27",
    "0x7fffffffffffffff", "1e-320", "1e308", "'~/missing.csv'",
]  # fmt: skip
EXTRA_LINES = ["[cable]", "unknown = 1", "[[seabed.hills]]\nheight = 1", "model = 3", "[top.x]",
               "name = 3", "source = 'x'", "[[model]]", "[numerics]\nstep = 1"]  # fmt: skip
ASSIGNMENT = re.compile(r"^(\s*[\w.]+\s*=\s*)(\S.*)$")


def mutate(text: bytes, rng: np.random.Generator) -> tuple[bytes, str]:
    """One to three random mutations of a scene file; returns (bytes, what was done)."""
    done = []
    for _ in range(rng.integers(1, 4)):
        lines = text.decode("utf-8", errors="surrogateescape").split("\n")
        k = int(rng.integers(len(lines)))
        kind = rng.choice(["delete", "truncate", "value", "duplicate", "bytes", "insert", "swap"])
        if kind == "delete":
            del lines[k]
        elif kind == "value":
            values = [i for i, line in enumerate(lines) if ASSIGNMENT.match(line)]
            k = int(rng.choice(values)) if values else k
            bad = str(rng.choice(BAD_VALUES))
            lines[k] = ASSIGNMENT.sub(lambda m, bad=bad: m.group(1) + bad, lines[k])
        elif kind == "duplicate":
            lines.insert(k, lines[k])
        elif kind == "insert":
            lines.insert(k, str(rng.choice(EXTRA_LINES)))
        elif kind == "swap":
            j = int(rng.integers(len(lines)))
            lines[k], lines[j] = lines[j], lines[k]
        text = "\n".join(lines).encode("utf-8", errors="surrogateescape")
        if kind == "truncate":
            text = text[: int(rng.integers(len(text) + 1))]
        elif kind == "bytes":
            start = int(rng.integers(len(text) + 1))
            size = int(rng.integers(1, 9))
            text = text[:start] + rng.bytes(size) + text[start + size :]
        done.append(f"{kind} at line {k}")
    return text, ", ".join(done)


@pytest.fixture
def no_heavy_work(monkeypatch):
    """Make every simulation, optimisation, validation and study fail the test if it starts."""

    def forbidden(*args, **kwargs):
        pytest.fail("bad input must be refused before any heavy work")

    for module, name in [(simulation, "simulate"), (optimization, "optimize"),
                         (validation, "catenary_check"), (studies, "step_halving"),
                         (studies, "element_convergence"), (studies, "end_positions")]:  # fmt: skip
        monkeypatch.setattr(module, name, forbidden)


def assert_refused(args, capsys) -> str:
    """Run the CLI in-process; assert exit 2 and one error line without a traceback."""
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    assert code == 2, (args, out, err)
    assert "Traceback" not in out + err, args
    assert err.strip().splitlines()[-1].startswith(f"cable-ocp {args[0]}: error: "), err
    return err


@pytest.mark.parametrize("name", SCENES)
def test_scene_mutants_load_or_raise_scene_error(tmp_path, capsys, no_heavy_work, name):
    rng = np.random.default_rng(sum(map(ord, name)))
    original = (MODELS / f"{name}.toml").read_bytes()
    refused, loaded, wrong = [], 0, []
    for k in range(MUTANTS_PER_SCENE):
        text, what = mutate(original, rng)
        path = tmp_path / f"mutant_{k}.toml"
        path.write_bytes(text)
        try:
            scene = load_scene(path)
        except SceneError as error:
            assert str(error), what
            refused.append(path)
            continue
        except Exception as error:  # the failure this test looks for
            wrong.append(f"{what}: {type(error).__name__}: {error}")
            continue
        assert isinstance(scene, Scene)
        assert scene_from_dict(scene.to_dict(), name=scene.name) == scene, what
        loaded += 1
    assert wrong == []
    # The mutations must exercise both outcomes (measured: 88 to 95 % of the mutants refused).
    assert len(refused) > MUTANTS_PER_SCENE // 2 and loaded > 0
    for path in refused[:12]:  # the CLI refuses them too, before simulating
        for command in (["simulate", path], ["optimize", path], ["validate", path]):
            assert_refused([*command, "--out", tmp_path / "out"], capsys)
    assert not (tmp_path / "out").exists()


HANGING = MODELS / "hanging.toml"
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
    "--method": ["", "ipopt2"],
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


def test_library_entry_points_reject_bad_numbers_before_integrating(monkeypatch):
    def forbidden(*args, **kwargs):
        pytest.fail("bad input must be refused before any heavy work")

    monkeypatch.setattr(simulation, "equilibrium", forbidden)
    monkeypatch.setattr(simulation, "integrate", forbidden)
    scene = load_scene(HANGING, {"model.elements": 2, "winch.top_length_max": 160.0})
    knots = np.zeros(scene.winch.knots)
    with pytest.raises(ValueError, match=r"^winch: knot value 3 is nan: must be finite \(rad\)$"):
        simulation.simulate(scene, winch=np.where(np.arange(knots.size) == 2, np.nan, knots))
    with pytest.raises(ValueError, match=r"^winch: 2 knot values given; .* winch\.knots = 14$"):
        simulation.simulate(scene, winch=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"^winch: expected 14 knot angles in rad$"):
        simulation.simulate(scene, winch=["a"] * 14)
    size = 2 * 5 * 3  # 5 coordinates per element, n + 1 = 3 elements, positions and rates
    with pytest.raises(ValueError, match=rf"^initial_state: expected shape \({size},\) .*\(29,\)$"):
        simulation.simulate(scene, initial_state=np.zeros(size - 1))
    with pytest.raises(ValueError, match=r"^initial_state\[4\] = nan: must be finite$"):
        simulation.simulate(scene, initial_state=np.where(np.arange(size) == 4, np.nan, 0.0))
    with pytest.raises(ValueError, match=r"^elements = 0: must be an integer from 1 to 1000$"):
        validation.catenary_check(scene, 0)
