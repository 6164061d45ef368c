"""The RK4 step scan: bracket the stability limit by doubling, then halve below it."""

from __future__ import annotations

import math
from collections.abc import Callable

from cable_ocp.simulation.integrate import SimulationError
from cable_ocp.studies.speed_accuracy.run_point import RunPoint

# The scan for a stable RK4 step gives up below this step (s).
SMALLEST_STEP = 2.0**-16


def first_step_guess(scene, elements: int, torsion: bool, largest: float) -> float:
    """A power-of-two step (s) near the RK4 stability limit, where the scan starts.

    Without torsion: the power law through CONVENTIONS.md §9's 0.4 s at n = 15 and 0.04 s at
    n = 100. With torsion: the time a torsional wave takes to cross an element,
    ``Delta / sqrt(G / rho)``.
    """
    if torsion:
        cable = scene.cable
        guess = cable.length / elements / math.sqrt(cable.shear_modulus / cable.density)
    else:
        guess = 0.4 * (15 / elements) ** (math.log(10) / math.log(100 / 15))
    return min(largest, 2.0 ** math.floor(math.log2(guess)))


def step_scan(
    run: Callable[[float], RunPoint], first: float, largest: float, stable_count: int
) -> list[RunPoint]:
    """Bracket the stability limit by doubling the step, then halve below it.

    From ``first`` the step is halved until a run is stable, then doubled until one is not (or
    ``largest`` is reached); below the largest stable step ``stable_count - 1`` halvings follow.
    """
    done: dict[float, RunPoint] = {}

    def at(step: float) -> RunPoint:
        if step not in done:
            done[step] = run(step)
        return done[step]

    step = first
    while not at(step).stable:
        step /= 2
        if step < SMALLEST_STEP:
            raise SimulationError(f"no stable RK4 step down to {SMALLEST_STEP:g} s")
    while 2 * step <= largest and at(2 * step).stable:
        step *= 2
    for k in range(1, stable_count):
        at(step / 2**k)
    return [done[h] for h in sorted(done)]
