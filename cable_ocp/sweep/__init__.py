"""Parameter sweeps: many simulations or OCPs of one scene on Dask, one xarray Dataset out.

``spec`` reads and validates the sweep file, ``execute`` runs one case (on a worker), ``store``
writes case files and assembles the Dataset, ``runner`` fans the cases out on Dask and
``benchmark`` times 1 against 2 workers; the ``cable-ocp sweep`` command is in
``cable_ocp.cli.sweep``.

The names below are imported on first use (PEP 562), so that ``cable-ocp --help`` does not
import Dask and xarray.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from cable_ocp.lazy import lazy_names

if TYPE_CHECKING:  # what __getattr__ imports (lazy_names reads it), for type checkers too
    from cable_ocp.sweep.benchmark import sweep_benchmark
    from cable_ocp.sweep.runner import SweepReport, run_sweep
    from cable_ocp.sweep.spec import Case, SweepSpec, load_sweep
    from cable_ocp.sweep.store import open_sweep

__all__ = [
    "Case", "SweepReport", "SweepSpec", "load_sweep", "open_sweep", "run_sweep",
    "sweep_benchmark",
]  # fmt: skip
__getattr__, __dir__ = lazy_names(globals())
