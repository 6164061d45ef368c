"""Execute the notebooks: a broken example fails the suite, so does one that shows no figure."""

import copy
import re
import sys
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

ROOT = Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
# The longest two (61 and 43 s of the default run's 812 s on 2 cores) run with -m slow.
SLOW = {"07_deploy.ipynb", "09_policy.ipynb"}
# Code that draws or displays a figure: pyplot, cable_ocp.plots, an image file shown by IPython.
PLOTTING = re.compile(r"\bplt\.\w+\(|\bplots\.\w+\(|\bImage\(")


def images(cell) -> int:
    return sum("image/png" in out.get("data", {}) for out in cell.get("outputs", []))


@pytest.mark.parametrize(
    "path",
    [pytest.param(p, marks=pytest.mark.slow) if p.name in SLOW else p for p in NOTEBOOKS],
    ids=lambda p: p.name,
)
def test_notebook_runs_and_shows_its_figures(path, monkeypatch):
    monkeypatch.setenv("CABLE_OCP_QUICK", "1")
    # As in a user's Jupyter: the kernel picks the inline backend only if no backend is forced.
    monkeypatch.delenv("MPLBACKEND", raising=False)
    source = nbformat.read(path, as_version=4)
    notebook = copy.deepcopy(source)
    NotebookClient(notebook, timeout=600, kernel_name="python3").execute(cwd=str(path.parent))

    code = [(i, cell) for i, cell in enumerate(notebook.cells) if cell.cell_type == "code"]
    if any(PLOTTING.search(cell.source) for _, cell in code):
        assert sum(images(cell) for _, cell in code) > 0, f"{path.name} plots but shows no image"
    blank = [i for i, cell in code if "plt.show()" in cell.source and images(cell) == 0]
    assert not blank, f"{path.name}: cells {blank} call plt.show() but show no image"
    for i, cell in code:  # an animation is shown as the GIF it wrote
        if "plots.animate(" in cell.source:
            assert any("image/gif" in out.get("data", {}) for out in cell.outputs), (path.name, i)
    cache_for_the_site(path, source, notebook)
    if "CABLE_OCP_QUICK" in path.read_text(encoding="utf-8"):  # the page says it was shortened
        shown = [out for _, cell in code for out in cell.outputs]
        banner = [out for out in shown if "**Shortened run**" in out.get("data", {}).get(
            "text/markdown", "")]  # fmt: skip
        assert len(banner) == 1, f"{path.name}: a shortened run that does not say so on its page"


def cache_for_the_site(path: Path, source, executed) -> None:
    """Keep this run's outputs in the site's notebook cache, so the docs build reuses them.

    myst-nb matches a notebook by its code cells (source and metadata) and kernelspec; the
    outputs are put on the unexecuted cells, so the key is the file's own.
    """
    try:
        from jupyter_cache import get_cache
        from jupyter_cache.base import CacheBundleIn
    except ImportError:  # the docs extra is not installed: no site to build
        return
    sys.path.insert(0, str(ROOT / "docs" / "_ext"))
    try:
        from cable_ocp_docs import CACHE
    finally:
        sys.path.remove(str(ROOT / "docs" / "_ext"))
    cached = copy.deepcopy(source)
    for cell, run in zip(cached.cells, executed.cells, strict=True):
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = run.outputs, run.execution_count
    cached.metadata = copy.deepcopy(executed.metadata)  # language_info, widgets' state
    cached.metadata.pop("kernelspec", None)
    if "kernelspec" in source.metadata:
        cached.metadata["kernelspec"] = source.metadata["kernelspec"]
    uri = str(ROOT / "docs" / "gallery" / path.name)
    get_cache(str(CACHE)).cache_notebook_bundle(
        CacheBundleIn(cached, uri, data={"source": "tests/test_notebooks.py"}),
        check_validity=False,
        overwrite=True,
    )


def test_the_image_check_catches_a_notebook_that_shows_nothing(tmp_path, monkeypatch):
    """A notebook that plots under a forced non-interactive backend has no image outputs."""
    monkeypatch.setenv("MPLBACKEND", "Agg")
    notebook = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_code_cell(
                "import matplotlib.pyplot as plt\nplt.plot([0, 1], [1, 0])\nplt.show()"
            )
        ]
    )
    NotebookClient(notebook, timeout=120, kernel_name="python3").execute(cwd=str(tmp_path))
    assert images(notebook.cells[0]) == 0
    monkeypatch.delenv("MPLBACKEND")
    NotebookClient(notebook, timeout=120, kernel_name="python3").execute(cwd=str(tmp_path))
    assert images(notebook.cells[0]) == 1


WIDGET = "application/vnd.jupyter.widget-view+json"


def test_progress_is_a_widget_in_a_notebook_and_absent_when_quiet(tmp_path, models_dir):
    """tqdm.auto draws a simulation's progress as a Jupyter widget; quiet = True shows nothing."""
    scene = f"co.load_scene({str(models_dir / 'hanging.toml')!r}, {{'numerics.duration': 2.0}})"
    cells = [f"import cable_ocp as co\nscene = {scene}", "run = co.simulate(scene, quiet=False)",
             "run = co.simulate(scene, quiet=True)"]  # fmt: skip
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(c) for c in cells])
    NotebookClient(notebook, timeout=300, kernel_name="python3").execute(cwd=str(tmp_path))
    shown, quiet = notebook.cells[1].outputs, notebook.cells[2].outputs
    assert any(WIDGET in out.get("data", {}) for out in shown), shown
    assert not any(out.get("name") == "stderr" for out in shown)  # no text bar beside it
    assert quiet == []
