"""Parameter sweeps: many simulations or OCPs of one scene on Dask, one xarray Dataset out.

``spec`` reads and validates the sweep file, ``execute`` runs one case (on a worker), ``store``
writes case files and assembles the Dataset, ``runner`` fans the cases out on Dask, ``command``
is the ``cable-ocp sweep`` subcommand and ``benchmark`` times 1 against 2 workers.
"""

from cable_ocp.sweep.runner import SweepReport, run_sweep
from cable_ocp.sweep.spec import Case, SweepSpec, load_sweep
from cable_ocp.sweep.store import open_sweep

__all__ = ["Case", "SweepReport", "SweepSpec", "load_sweep", "open_sweep", "run_sweep"]
