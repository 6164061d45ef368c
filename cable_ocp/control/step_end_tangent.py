"""The closed loop's forward sensitivities, from the step ends' Jacobians, in compiled C.

:func:`~cable_ocp.control.linearisation.propagate_sensitivities` runs the tangent of the RK4
steps in numpy: per step, four products of the touched rows of ``S`` (size x nx) by the stage
Jacobians and a dozen sums, each a numpy call of a microsecond or two on a few hundred numbers.
Over a thin rope's controller horizon (2 elements, nx = 30, 10 parameters, h = 0.05 s, 400
steps) that loop took 8.8 ms against 2.6 ms for the same arithmetic in ``step_end_tangent.c``
(gcc -O3 for this processor, loaded with :mod:`ctypes`), and CasADi's own code for it 14.5 ms
(an MX Function mapped over the steps: its generated products decode the sparsity at every call)
or 5.9 ms after a 23 s compile (flat SX). The two agree to 2e-15 of the sensitivities' size
(``tests/test_step_end_tangent.py``). Without a compiler the numpy loop runs, after a warning.
"""

from __future__ import annotations

import ctypes
import warnings
from functools import cache
from pathlib import Path

import numpy as np

from cable_ocp.model.compile import compiled_source

SOURCE = Path(__file__).with_name("step_end_tangent.c")
WORK_BLOCKS = 5  # size x nx blocks of the kernel's scratch, beside one (nx + 3) x nx Jacobian


@cache
def step_end_kernel() -> ctypes._CFuncPtr | None:
    """The compiled kernel (compiled once into the cache), or None after a warning."""
    library = compiled_source(SOURCE)
    if library is None:
        return None
    try:
        kernel = ctypes.CDLL(str(library)).step_end_tangent
    except OSError as error:
        warnings.warn(
            f"cannot load {library} ({error}): the sensitivities run in numpy",
            RuntimeWarning,
            stacklevel=2,
        )
        return None
    array = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
    integers = np.ctypeslib.ndpointer(dtype=np.intc, flags="C_CONTIGUOUS")
    kernel.argtypes = [
        *[ctypes.c_int] * 4, ctypes.c_double, array, array, integers, integers, integers, array,
        array,
    ]  # fmt: skip
    kernel.restype = None
    return kernel


class StepEndTangent:
    """Forward sensitivities of one horizon's RK4 run from the Jacobians at its points.

    Parameters
    ----------
    kernel : ctypes function
        :func:`step_end_kernel`.
    steps, nx, size, kept : int
        RK4 steps, state size, winch parameters, state components returned.
    step : float, s
    pattern : array of bool (nx, nx + 3), optional
        Where ``d x'/d [x; w]`` may be nonzero (its sparsity): the kernel multiplies only there
        (the default: everywhere).
    """

    def __init__(
        self, kernel, steps: int, nx: int, size: int, kept: int, step: float, pattern=None
    ):
        self.kernel, self.steps, self.nx, self.size, self.kept = kernel, steps, nx, size, kept
        self.step = step
        pattern = np.ones((nx, nx + 3), bool) if pattern is None else np.asarray(pattern, bool)
        self._segments = nonzero_segments(pattern.T)
        self._work = np.zeros(WORK_BLOCKS * size * nx + (nx + 3) * nx)

    def __call__(self, points: np.ndarray, winch: np.ndarray) -> np.ndarray:
        """``S_k`` transposed (K + 1, size, kept), ``S_0 = 0``.

        Parameters
        ----------
        points : array (K + 1, nx + 3, nx)
            The transposed Jacobians ``[d x'/d x, d x'/d w]^T`` at the RK4 points.
        winch : array (K, 9, size)
            ``D_k`` of :func:`~cable_ocp.control.linearisation.winch_map`.
        """
        out = np.empty((self.steps + 1, self.size, self.kept))
        self.kernel(
            self.steps, self.nx, self.size, self.kept, self.step,
            np.ascontiguousarray(points), np.ascontiguousarray(winch), *self._segments, out,
            self._work,
        )  # fmt: skip
        return out


def nonzero_segments(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs of True in each row of ``rows`` (r, c): ``first`` (r + 1), ``low``, ``high``.

    Row ``i``'s runs are ``[low[s], high[s])`` for ``s`` in ``first[i] .. first[i + 1]``.
    """
    padded = np.zeros((rows.shape[0], rows.shape[1] + 2), bool)
    padded[:, 1:-1] = rows
    change = np.diff(padded.astype(np.int8), axis=1)  # +1 where a run starts, -1 past its end
    row_of_start, low = np.nonzero(change == 1)
    _, high = np.nonzero(change == -1)
    first = np.searchsorted(row_of_start, np.arange(rows.shape[0] + 1))
    return tuple(np.ascontiguousarray(a, dtype=np.intc) for a in (first, low, high))
