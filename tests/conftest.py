"""Shared fixtures of the tests: scene paths, state builders, scene mutants, validation record."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from cable_ocp.model.layout import INPUTS

MODELS = Path(__file__).resolve().parent.parent / "models"


def axis(psi: float, theta: float) -> np.ndarray:
    """Element direction e(psi, theta) of CONVENTIONS.md §3, independent of the package."""
    return np.array([np.cos(theta) * np.cos(psi), np.sin(theta), np.cos(theta) * np.sin(psi)])


def chained_state(model, u: np.ndarray, psi, theta) -> np.ndarray:
    """State at rest with the given element angles, positions chained down from the top point.

    ``A_{n+1} = u[0:3]`` and ``A_i = A_{i+1} - l_i e_i``, so every bond holds exactly. ``psi`` and
    ``theta`` are scalars (a straight line) or one value per element (0..n). Twist angles, if any,
    and all rates are zero.
    """
    count = model.element_count
    psi = np.broadcast_to(np.asarray(psi, dtype=float), (count,))
    theta = np.broadcast_to(np.asarray(theta, dtype=float), (count,))
    lengths = [float(length) for length in model.element_lengths(float(u[INPUTS.top_length]))]
    q = np.zeros((count, model.dofs))
    point = np.asarray(u[INPUTS.top], dtype=float).copy()
    for i in reversed(range(count)):
        point = point - lengths[i] * axis(psi[i], theta[i])
        q[i, :3] = point
        q[i, 3], q[i, 4] = psi[i], theta[i]
    return np.concatenate([q.ravel(), np.zeros(q.size)])


@pytest.fixture(scope="session")
def models_dir() -> Path:
    """The folder of the bundled scene files."""
    return MODELS


@pytest.fixture(scope="session")
def chained():
    """Builder ``(model, u, psi, theta) -> state`` of a chain at rest hanging from the top point."""
    return chained_state


@pytest.fixture(scope="session")
def tilted():
    """Builder ``(model, u) -> state``: the straight line psi = pi/2 + 0.3, theta = 0.1, at rest."""

    def build(model, u, tilt: float = 0.3, theta: float = 0.1) -> np.ndarray:
        return chained_state(model, u, np.pi / 2 + tilt, theta)

    return build


# ----------------------------------------------------------------------------------------------
# Fuzz: deterministic mutants of the bundled scene files. test_scene.py checks that each loads or
# raises SceneError; test_cli.py that the command line refuses the refused ones.
MUTANTS_PER_SCENE = 150
BAD_VALUES = [
    '"text"', "1e400", "-1e400", "nan", "-nan", "inf", "-3", "0", "-0.0", '""', "1" + "0" * 400,
    "-" + "9" * 30, "1" * 5000, "true", "[]", "[1, 2]", "[nan, 1, 2]", "{ a = 1 }", "1979-05-27",
    "0x7fffffffffffffff", "1e-320", "1e308", "'~/missing.csv'",
]  # fmt: skip
EXTRA_LINES = ["[cable]", "unknown = 1", "[[seabed.hills]]\nheight = 1", "model = 3", "[top.x]",
               "name = 3", "source = 'x'", "[[model]]", "[numerics]\nstep = 1"]  # fmt: skip
ASSIGNMENT = re.compile(r"^(\s*[\w.]+\s*=\s*)(\S.*)$")


def made_optimum(run):
    """An OcpResult around ``run`` with made-up solver figures (no solve), to save and load."""
    from cable_ocp.control.optimization import OcpResult

    return OcpResult(
        method="shooting", parameters=np.zeros(2), control="hermite(2)", trajectory=run,
        omega=run.omega, omega_model=run.omega, success=True, status="made here",
        iterations=0, evaluations=0, wall_time=0.0, build_time=0.0, solve_time=0.0,
        function_time=0.0, history=[], refinements=[], scene_record=run.scene_record,
    )  # fmt: skip


@pytest.fixture(scope="session")
def line_file(tmp_path_factory):
    """A line run's file to copy and damage: a pay-out of 20 m on 10 m elements of paper_flat,
    two segments (n = 5, then 6)."""
    import cable_ocp as co

    scene = co.load_scene(
        MODELS / "paper_flat.toml",
        {"top.motion": "fixed", "cable.length": 50.0, "numerics.duration": 12.0,
         "numerics.constraint_tolerance": 1e-4, "winch.knots": 4,
         "winch.line": {"element_length": 10.0, "pay_out_max": 30.0},
         "end.payload": {"mass": 2000.0, "volume": 0.256}},
    )  # fmt: skip
    run = co.simulate(scene, winch=[10.0, 20.0, 30.0, 40.0], quiet=True)
    assert len(run.segments) == 2
    return run.save(tmp_path_factory.mktemp("line") / "line")


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


def scene_mutants(name: str) -> Iterator[tuple[bytes, str]]:
    """The ``MUTANTS_PER_SCENE`` mutants of ``models/<name>.toml``: (bytes, what was done).

    The generator is seeded by the name, so every test sees the same mutants.
    """
    rng = np.random.default_rng(sum(map(ord, name)))
    original = (MODELS / f"{name}.toml").read_bytes()
    for _ in range(MUTANTS_PER_SCENE):
        yield mutate(original, rng)


@pytest.fixture(scope="session")
def mutants():
    """``name -> iterator of (bytes, what was done)``: the mutants of a bundled scene file."""
    return scene_mutants


# ----------------------------------------------------------------------------------------------
# The validation record: tests that check the physics against an independent reference call the
# ``validation`` fixture with what they measured; ``pytest --validation-report=tests/VALIDATION.md``
# writes one row per case with the test's outcome, so the record is regenerated, not typed.
CELLS = ("level", "case", "reference", "metric", "result", "acceptance")
LEVELS = ("analytic", "second formulation", "converged reference", "peer code", "conservation")


def pytest_addoption(parser):
    parser.addoption(
        "--validation-report",
        metavar="PATH",
        help="write the validation record (markdown) of the validation tests that ran to PATH",
    )


VALIDATION_ROW = "validation row"  # the name of a row among a test report's user_properties


def pytest_configure(config):
    path = config.getoption("--validation-report")
    if path and not hasattr(config, "workerinput"):
        # In the run's main process only (not in a pytest-xdist worker), where its reports meet.
        config.pluginmanager.register(ValidationRecord(Path(path)))


class ValidationRecord:
    """The validation record of a run: each test's validation rows and outcome, from its reports.

    The rows travel in the reports' ``user_properties`` (the teardown report carries all of a
    test's), so that a run spread over pytest-xdist's workers writes the same record as one
    process.
    """

    def __init__(self, path: Path):
        self.path, self.rows, self.outcomes = path, [], {}

    def pytest_runtest_logreport(self, report):
        if report.when == "call" or (report.when == "setup" and report.skipped):
            self.outcomes[report.nodeid] = report.outcome
        if report.when == "teardown":
            self.rows += [value for name, value in report.user_properties if name == VALIDATION_ROW]

    def pytest_sessionfinish(self, session, exitstatus):
        rows = sorted(self.rows, key=lambda r: (LEVELS.index(r["level"]), r["test"]))
        lines = [
            "# Validation record",
            "",
            "Generated by `python -m pytest --validation-report=tests/VALIDATION.md`"
            " (do not edit by hand): each row is a test that measured the model against an"
            " independent reference; the outcome is that test's in this run. Speed is not tested:"
            " `cable-ocp bench` prints it (see README).",
            "",
            "| level | case | reference | metric | result | acceptance | test | outcome |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for r in rows:
            outcome = self.outcomes.get(r["test"], "not run")
            cells = [r[k].replace("|", "\\|") for k in CELLS]
            lines.append("| " + " | ".join([*cells, f"`{r['test']}`", outcome]) + " |")
        self.path.write_text("\n".join(lines) + "\n")


@pytest.fixture
def validation(request):
    """Recorder ``(case, level, reference, metric, result, acceptance)`` of a validation row.

    ``result`` is the measured figure as text (with units); ``acceptance`` the bound the test
    asserts. Call it before asserting, so that a failing case is recorded with its figure.
    """

    def record(case: str, level: str, reference: str, metric: str, result: str, acceptance: str):
        if level not in LEVELS:
            raise ValueError(f"level = {level!r}: must be one of {LEVELS}")
        row = {
            "case": case,
            "level": level,
            "reference": reference,
            "metric": metric,
            "result": result,
            "acceptance": acceptance,
            "test": request.node.nodeid,
        }
        request.node.user_properties.append((VALIDATION_ROW, row))

    return record
