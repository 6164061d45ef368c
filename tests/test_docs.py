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
