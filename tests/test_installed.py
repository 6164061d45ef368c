"""The package as a user installs it: a wheel built from this checkout, run from another folder.

The wheel is installed into a folder of its own (``pip install --target``) that comes first on
``PYTHONPATH``, and the checks run in a fresh interpreter whose working directory is outside the
checkout, so nothing can be found through the source tree. About 15 s (building the wheel).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
SOURCES = ("pyproject.toml", "README.md", "LICENSE", "cable_ocp", "models")

CHECK = """
import sys
from pathlib import Path

import cable_ocp
from cable_ocp.scene.bundled import models_dir
from cable_ocp.sweep.spec import bundled_sweeps, load_sweep

site = Path(sys.argv[1])
assert Path(cable_ocp.__file__).is_relative_to(site), cable_ocp.__file__
assert models_dir().is_relative_to(site), models_dir()
Path("by_name.toml").write_text('scene = "small_tow"\\n')
spec = load_sweep("by_name.toml")
assert spec.scene_path == models_dir() / "small_tow.toml", spec.scene_path
assert sorted(bundled_sweeps()) == ["ocp_sample", "tow_speeds"], bundled_sweeps()
example = load_sweep("tow_speeds")  # a bundled example by name; its scene beside it
assert example.scene_path == models_dir() / "small_tow.toml" and len(example.cases) == 6
survey = cable_ocp.load_scene(models_dir() / "survey.toml")  # its bathymetry grid ships too
assert Path(survey.seabed.grid.file) == models_dir() / "data" / "survey_grid.nc", survey.seabed
from cable_ocp.control.step_end_tangent import SOURCE  # the closed loop's C kernel ships too
assert SOURCE.is_file() and SOURCE.is_relative_to(site), SOURCE
from cable_ocp.policy.family import bundled_families  # and the learned policy's families
assert sorted(bundled_families()) == ["hill_tow", "landing_hold"], bundled_families()
print("installed ok")
"""


@pytest.fixture(scope="module")
def installed(tmp_path_factory) -> Path:
    """The folder the wheel of this checkout is installed into."""
    scratch = tmp_path_factory.mktemp("wheel")
    source = scratch / "source"
    source.mkdir()
    for name in SOURCES:
        if (ROOT / name).is_dir():
            ignore = shutil.ignore_patterns("__pycache__", "*.pyc", "*.so")
            shutil.copytree(ROOT / name, source / name, ignore=ignore)
        else:
            shutil.copy2(ROOT / name, source / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "--no-input"]
    built = subprocess.run([*pip, "wheel", "--no-deps", "-q", "-w", str(scratch), str(source)],
                           capture_output=True, text=True, timeout=300)  # fmt: skip
    if built.returncode != 0:
        pytest.skip(f"cannot build a wheel here (pip wheel: {built.stderr.strip()[-300:]})")
    (wheel,) = scratch.glob("cable_ocp-*.whl")
    site = scratch / "site"
    subprocess.run([*pip, "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True, capture_output=True, timeout=300)  # fmt: skip
    return site


def test_sweeps_find_the_bundled_scenes_and_examples_in_an_installed_wheel(installed, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "PYTHONPATH": str(installed)}
    done = subprocess.run([sys.executable, "-c", CHECK, str(installed)], cwd=elsewhere, env=env,
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "installed ok"
    refused = subprocess.run(
        [sys.executable, "-m", "cable_ocp.cli", "sweep", "nowhere", "--out", "o"],
        cwd=elsewhere, env=env, capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert refused.returncode == 2
    assert refused.stderr.strip() == (
        "cable-ocp sweep: error: sweep file nowhere: not found (nor a bundled example: "
        "ocp_sample, tow_speeds)"
    )
