"""The PEP 562 loader written once (cable_ocp.lazy, issue 41): names imported on first use, each
module stated once, under the package's ``if TYPE_CHECKING:``."""

from __future__ import annotations

import subprocess
import sys

import pytest

import cable_ocp
from cable_ocp.lazy import declared, lazy_names


def test_every_public_name_is_declared_once_and_resolves():
    from pathlib import Path

    sources = declared(Path(cable_ocp.__file__), "cable_ocp")
    assert sorted(sources) == sorted(cable_ocp.__all__)
    assert (
        sources["plots"] == "cable_ocp.plots" and sources["simulate"] == "cable_ocp.simulation.run"
    )
    for name in cable_ocp.__all__:
        assert getattr(cable_ocp, name) is not None, name
    assert set(cable_ocp.__all__) <= set(dir(cable_ocp))
    with pytest.raises(AttributeError, match="module 'cable_ocp' has no attribute 'simulat'"):
        cable_ocp.simulat  # noqa: B018


def test_importing_the_package_imports_no_name_until_used():
    code = (
        "import sys, cable_ocp; "
        "assert 'casadi' not in sys.modules and 'cable_ocp.simulation.run' not in sys.modules; "
        "cable_ocp.simulate; assert 'cable_ocp.simulation.run' in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_package_of_its_own_loads_lazily_and_refuses_renamed_imports(tmp_path, monkeypatch):
    package = tmp_path / "toy"
    package.mkdir()
    (package / "leaf.py").write_text("VALUE = 3\n")
    (package / "sub").mkdir()
    (package / "sub" / "__init__.py").write_text("")
    (package / "__init__.py").write_text(
        "from typing import TYPE_CHECKING\n"
        "from cable_ocp.lazy import lazy_names\n"
        "if TYPE_CHECKING:\n"
        "    from toy import sub\n"
        "    from toy.leaf import VALUE\n"
        "__getattr__, __dir__ = lazy_names(globals())\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    import toy

    assert "toy.leaf" not in sys.modules
    assert toy.VALUE == 3 and toy.sub.__name__ == "toy.sub"
    (package / "bad.py").write_text("if TYPE_CHECKING:\n    from toy.leaf import VALUE as V\n")
    with pytest.raises(ValueError, match="VALUE as V: not renamed"):
        lazy_names({"__name__": "toy", "__file__": str(package / "bad.py")})
