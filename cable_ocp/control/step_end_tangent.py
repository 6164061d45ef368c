"""The closed loop's forward sensitivities, from the step ends' Jacobians, in compiled C.

:func:`~cable_ocp.control.linearisation.propagate_sensitivities` runs the tangent of the RK4
steps in numpy: per step, four products of the touched rows of ``S`` (size x nx) by the stage
Jacobians and a dozen sums, each a numpy call of a microsecond or two on a few hundred numbers.
Over a thin rope's controller horizon (2 elements, nx = 30, 10 parameters, h = 0.05 s, 400
steps) that loop took 8.8 ms against 1.4 ms for the same arithmetic in ``step_end_tangent.c``
(gcc -O3 for this processor, the state size fixed at compile time: 2.8 ms with it a variable;
loaded with :mod:`ctypes`), and CasADi's own code for it 14.5 ms (an MX Function mapped over
the steps: its generated products decode the sparsity at every call) or 5.9 ms after a 23 s
compile (flat SX). The two agree to 2e-15 of the sensitivities' size
(``tests/test_step_end_tangent.py``). Without a compiler the numpy loop runs, after a warning.
"""

from __future__ import annotations

import ctypes
import warnings
from collections.abc import Callable
from functools import cache
from pathlib import Path

import numpy as np

from cable_ocp.model.compile import compiled_source

SOURCE = Path(__file__).with_name("step_end_tangent.c")
WORK_BLOCKS = 4  # size x nx blocks of the kernel's scratch, beside one (nx + 3) x nx Jacobian


@cache
def step_end_kernel(nx: int) -> Callable | None:
    """The kernel for a state of ``nx`` components (compiled once into the cache), or None.

    None after a warning when it cannot be compiled or loaded (the caller runs numpy).
    """
    library = compiled_source(SOURCE, {"NX": nx})
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
    kernel.argtypes = [*[ctypes.c_int] * 3, ctypes.c_double, array, array, array, array]
    kernel.restype = None
    return kernel


class StepEndTangent:
    """Forward sensitivities of one horizon's RK4 run from the Jacobians at its points.

    Parameters
    ----------
    kernel : ctypes function
        :func:`step_end_kernel` of the state size ``nx``.
    steps, nx, size, kept : int
        RK4 steps, state size, winch parameters, state components returned.
    step : float, s
    """

    def __init__(self, kernel, steps: int, nx: int, size: int, kept: int, step: float):
        self.kernel, self.steps, self.size, self.kept, self.step = kernel, steps, size, kept, step
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
            self.steps, self.size, self.kept, self.step,
            np.ascontiguousarray(points), np.ascontiguousarray(winch), out, self._work,
        )  # fmt: skip
        return out
