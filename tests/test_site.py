"""The documentation site: built by Sphinx with warnings as errors, and looked at in a browser.

The site executes the notebooks through myst-nb's cache, which ``tests/test_notebooks.py`` fills
with its own runs: this file is named to run after it, so that one process executes each notebook
once. On pytest-xdist's workers (the default run's two, by files) the site may build beside the
notebooks and execute those not cached yet itself (pytest-xdist's ``loadgroup``, which could keep
them on one worker, ignores its groups on pytest 9.2: pytest-xdist issue 1386). Needs the
``docs`` extra; the browser test needs Debian's headless Chromium
(``apt-get install chromium-headless-shell``, as ``.ci/run`` does).

Slow (``python -m pytest -m slow``): the build took 121 s of the default run's 812 s on 2 cores,
which has to stay under 10 minutes.
"""

from __future__ import annotations

import importlib
import os
import pkgutil
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

import cable_ocp
from cable_ocp.scene.fields import field_rows, schema_sections

pytest.importorskip("sphinx", reason="the site needs the docs extra (pip install -e '.[docs]')")
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs"

BROWSERS = ("chromium-headless-shell", "chromium", "chromium-browser")


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The site built from scratch, as the README's command builds it (``-W``: warnings fail)."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_nb")
    pytest.importorskip("numpydoc")
    pytest.importorskip("furo")
    out = tmp_path_factory.mktemp("site")
    command = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-E", "-q", "-b", "html",
               "-d", str(out / "doctrees"), str(DOCS), str(out / "html")]  # fmt: skip
    start = time.perf_counter()
    done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=1800)
    took = time.perf_counter() - start
    warnings = [line for line in done.stderr.splitlines() if "WARNING" in line or "ERROR" in line]
    warnings = [line for line in warnings if "IPKernelApp" not in line]  # the kernel's own log
    assert done.returncode == 0, f"sphinx -W failed after {took:.0f} s:\n" + "\n".join(warnings)
    print(f"site built in {took:.1f} s")
    return out / "html"


def test_the_site_builds_with_warnings_as_errors(site):
    for page in ("index", "getting_started", "guide/scenes", "guide/command_line", "gallery",
                 "validation", "conventions", "api/index"):  # fmt: skip
        assert (site / f"{page}.html").is_file(), page


def test_the_included_pages_are_their_sources_not_copies(site):
    """CONVENTIONS.md and VALIDATION.md appear on the site; docs/ holds no copy of either."""
    copies = [p for p in DOCS.rglob("*.md") if p.name in ("CONVENTIONS.md", "VALIDATION.md")]
    assert not copies
    conventions = (site / "conventions.html").read_text(encoding="utf-8")
    heading = re.search(r"^## (1\..*)$", (ROOT / "cable_ocp" / "CONVENTIONS.md").read_text(), re.M)
    assert heading.group(1).split()[-1] in conventions
    validation = (site / "validation.html").read_text(encoding="utf-8")
    first_test = re.search(
        r"`(tests/test_\w+\.py::\w+)", (ROOT / "tests" / "VALIDATION.md").read_text()
    )
    assert first_test.group(1) in validation
    assert "speed_accuracy_paper_flat.png" in validation  # the benchmark figures, in place


def test_every_scene_field_is_in_the_guide_with_its_unit_and_range(site):
    page = (site / "guide" / "scenes.html").read_text(encoding="utf-8")
    rows = [(path, row) for path, cls in schema_sections()
            for row in field_rows(cls, path)]  # fmt: skip
    assert len(rows) > 50
    missing = [row["path"] for _, row in rows if row["missing"]]
    assert not missing, f"scene fields without a unit or meaning: {missing}"
    for _, row in rows:
        assert row["unit"] and row["range"], row
        assert (
            f'<code class="docutils literal notranslate"><span class="pre">{row["field"]}' in page
        )
    assert "kg/m^3" in page and "rad/s^2" in page


def test_the_command_line_help_is_on_the_site(site):
    page = (site / "guide" / "command_line.html").read_text(encoding="utf-8")
    for command in (
        "simulate",
        "validate",
        "optimize",
        "compare",
        "mpc",
        "sweep",
        "study",
        "bench",
    ):
        assert f"usage: cable-ocp {command}" in page, command


def public_modules() -> list[str]:
    names = ["cable_ocp"]
    for module in pkgutil.walk_packages(cable_ocp.__path__, "cable_ocp."):
        if not any(
            part.startswith("_") for part in module.name.split(".")
        ) and not module.name.startswith("cable_ocp.models"):
            names.append(module.name)
    return names


def test_the_api_reference_has_every_module_and_every_public_name(site):
    index = (site / "api" / "index.html").read_text(encoding="utf-8")
    for name in cable_ocp.__all__:
        assert f">{name}<" in index or f'<span class="pre">{name}</span>' in index, name
    pages = site / "api" / "generated"
    missing = [m for m in public_modules()[1:] if not (pages / f"{m}.html").is_file()]
    assert not missing, f"modules without a page in the API reference: {missing}"
    for module_name in ("cable_ocp.simulation.run", "cable_ocp.control.optimization"):
        module = importlib.import_module(module_name)
        page = (pages / f"{module_name}.html").read_text(encoding="utf-8")
        public = [n for n, v in vars(module).items() if not n.startswith("_")
                  and getattr(v, "__module__", None) == module_name and callable(v)]  # fmt: skip
        for name in public:
            assert f'id="{module_name}.{name}"' in page, (module_name, name)


def test_the_sidebar_lists_the_api_packages_not_every_module(site):
    """Every page's sidebar listed all 146 API modules (issue 45 item 10): two levels now."""
    for page in ("index.html", "guide/scenes.html", "api/generated/cable_ocp.result_files.html"):
        html = (site / page).read_text(encoding="utf-8")
        tree = html.split('<div class="sidebar-tree">', 1)[1].split("</div>", 1)[0]
        names = re.findall(r'<a class="[^"]*reference internal[^"]*" href="[^"]+">(.*?)</a>', tree)
        assert 20 < len(names) < 60, (page, len(names))
        assert "cable_ocp.result_files" in names and "cable_ocp.result_files.netcdf" not in names


def test_every_gallery_page_shows_a_figure(site):
    for notebook in sorted((ROOT / "notebooks").glob("*.ipynb")):
        page = site / "gallery" / f"{notebook.stem}.html"
        html = page.read_text(encoding="utf-8")
        images = re.findall(r'<img[^>]+src="([^"]+)"', html)
        assert images, f"{page.name} shows no figure"
        for src in images:
            if not src.startswith("data:"):
                assert (page.parent / src).is_file(), (page.name, src)


def browser() -> str | None:
    return next((shutil.which(name) for name in BROWSERS if shutil.which(name)), None)


def chromium(binary: str, *arguments: str) -> subprocess.CompletedProcess:
    options = ["--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
               "--virtual-time-budget=5000", "--window-size=1280,1600"]  # fmt: skip
    command = [binary, *options, *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=120)


def test_the_site_opens_in_a_browser(site, tmp_path):
    """Headless Chromium opens the index and a gallery page: the API's contents, a figure."""
    binary = browser()
    if binary is None:
        if os.environ.get("CI"):
            pytest.fail("CI has no headless Chromium: .ci/run installs chromium-headless-shell")
        pytest.skip("no headless Chromium (apt-get install chromium-headless-shell)")
    from matplotlib.image import imread

    pages = {"index": site / "index.html", "gallery": site / "gallery" / "03_optimal_winch.html"}
    dom = {}
    for name, page in pages.items():
        shot = tmp_path / f"{name}.png"
        done = chromium(binary, f"--screenshot={shot}", page.as_uri())
        assert shot.is_file(), done.stderr[-2000:]
        pixels = imread(shot)
        assert pixels.shape[0] >= 800 and pixels.std() > 0.05, f"{name}: a blank page"
        dom[name] = chromium(binary, "--dump-dom", page.as_uri()).stdout
    assert 'href="api/index.html"' in dom["index"]  # the API reference in the table of contents
    assert "Every module, layer by layer" in dom["index"]
    figures = re.findall(r'<img[^>]+src="([^"]+\.png)"', dom["gallery"])
    assert figures, "the gallery page shows no figure in the browser"
    assert all((pages["gallery"].parent / src).is_file() for src in figures)
