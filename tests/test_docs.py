"""The documentation the code points to is in the repository."""

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_no_reference_to_a_design_file_outside_the_repository():
    pattern = re.compile(r"DESIGN(\.md| §| section)")
    offenders = [
        f"{path.relative_to(ROOT)}:{number}"
        for folder in ("cable_ocp", "tests", "models", "notebooks", "studies")
        for path in (ROOT / folder).rglob("*")
        if path.suffix in (".py", ".toml", ".md", ".ipynb") and path.name != "test_docs.py"
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line)
    ]
    offenders += [
        f"README.md:{n}"
        for n, line in enumerate((ROOT / "README.md").read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line)
    ]
    assert not offenders, f"references to DESIGN.md, which is not shipped: {offenders}"
    assert (ROOT / "cable_ocp" / "CONVENTIONS.md").is_file()


def test_the_readmes_python_writes_nothing_into_the_working_directory():
    """A newcomer running the README's Python got run/ and tow.gif in the working directory
    (issue 45 item 10): every file it writes goes under a temporary folder."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", readme, re.S)
    assert blocks and "tempfile.mkdtemp()" in blocks[0]
    literal = re.compile(r"""(path=|\.save\(|load_result\()\s*["']""")
    offenders = [line for block in blocks for line in block.splitlines() if literal.search(line)]
    assert not offenders, offenders


def test_the_readme_leads_with_set_up_and_a_quick_start():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    headings = re.findall(r"^#{1,2} (.+)$", readme, re.M)
    assert headings[1].startswith("Set-up") and headings[2] == "Quick start", headings
    assert headings.index("Reference") == 3
    ignored = (ROOT / ".gitignore").read_text(encoding="utf-8").split()
    assert ".venv/" in ignored and "runs/" in ignored
