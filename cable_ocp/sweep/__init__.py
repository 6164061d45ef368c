"""Parameter sweeps: many simulations or OCPs of one scene on Dask, one xarray Dataset out.

``spec`` reads and validates the sweep file, ``execute`` runs one case (on a worker), ``store``
writes case files and assembles the Dataset, ``runner`` fans the cases out on Dask and
``benchmark`` times 1 against 2 workers; the ``cable-ocp sweep`` command is in
``cable_ocp.cli.sweep``.
"""

from cable_ocp.lazy import lazy_names

# Loaded on first use, so that ``cable-ocp --help`` does not import Dask and xarray.
_HOMES = {
    "Case": "spec", "SweepSpec": "spec", "load_sweep": "spec", "SweepReport": "runner",
    "run_sweep": "runner", "open_sweep": "store", "sweep_benchmark": "benchmark",
}  # fmt: skip
__all__ = sorted(_HOMES)
__getattr__, __dir__ = lazy_names(
    globals(), {name: f"cable_ocp.sweep.{module}" for name, module in _HOMES.items()}
)
