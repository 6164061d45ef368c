"""The work arrays of a sensitivity sweep, shared by the linearisations of one shape.

A sweep writes every RK4 step's stage Jacobians into an array of ``K x 4 x (nx + 3) x nx``
numbers (82 MB on whole-space seed 0 case 11: 1494 steps, 40 states). Fresh memory costs its
first writes: on the 2-core test machine, filling those 82 MB the first time took 0.07-0.14 s
against 0.006 s for memory already written, as much as the sweep itself (0.07 s), and the
views of its steps another 0.04 s (2026-12-06). Every solver has its own linearisation, and
the adaptive control grid builds three or four on one model and step
(:mod:`cable_ocp.control.adaptive_grid`); they take their sweeps one after another, so one set
of arrays serves them all, and the next ``optimize`` of the scene too.

:func:`sweep_scratch` keeps the last set made: a process holds one set (165 MB for 3000 steps of
a 3-element model) until a sweep of another shape replaces it. A set is only written and read
within one linearisation's call, which holds its lock: two threads sweeping one shape at once
take turns.
"""

from __future__ import annotations

import threading
from functools import cached_property

import numpy as np


class SweepScratch:
    """The arrays one sweep writes, and the views of its steps.

    Parameters
    ----------
    steps : int
        RK4 steps ``K`` of the horizon.
    states : int
        The model's state size ``nx``.
    inputs : int
        Rows of a stage's inputs.
    width : int
        ``nx + 3``: the columns of a stage Jacobian, state and winch inputs.
    at_ends : bool
        Jacobians at the step ends (``(K + 1) x width x nx``) instead of every stage's.

    Attributes
    ----------
    states : array (K + 1, nx)
        The run, the initial state first.
    inputs : array (K, 3, inputs)
        Each step's stage inputs.
    jacobians : array (K, 4, width, nx), or (K + 1, width, nx) at the ends
        The stage Jacobians, transposed (CasADi's column-major layout).
    lock : threading.Lock
        Held while a linearisation writes and reads the arrays.
    sweeps : int
        Sweeps written into the arrays so far (a linearisation that reads them again checks
        that no other sweep has written them since its own).
    """

    def __init__(self, steps: int, states: int, inputs: int, width: int, at_ends: bool):
        self.steps = steps
        self.states = np.zeros((steps + 1, states))
        self.inputs = np.zeros((steps, 3, inputs))
        shape = (steps + 1, width, states) if at_ends else (steps, 4, width, states)
        self.jacobians = np.zeros(shape)
        self.lock = threading.Lock()
        self.sweeps = 0

    @cached_property
    def views(self) -> list[tuple[memoryview, ...]]:
        """Each step's start, inputs, end and Jacobians, as the sweep writes them."""
        states, inputs, jacobians = self.states, self.inputs, self.jacobians
        return [
            tuple(
                memoryview(array)
                for array in (states[k], inputs[k], states[k + 1], jacobians[k])
            )
            for k in range(self.steps)
        ]  # fmt: skip


_LAST: dict[tuple, SweepScratch] = {}  # the last shape's arrays
_GUARD = threading.Lock()


def sweep_scratch(steps: int, states: int, inputs: int, width: int, at_ends: bool) -> SweepScratch:
    """The work arrays of this shape: the last ones made, if they are of it, or new ones."""
    key = (steps, states, inputs, width, at_ends)
    with _GUARD:
        if key not in _LAST:
            _LAST.clear()  # one shape at a time: the others' arrays go with their holders
            _LAST[key] = SweepScratch(steps, states, inputs, width, at_ends)
        return _LAST[key]
