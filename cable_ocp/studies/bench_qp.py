"""``cable-ocp bench --only qp``: the Gauss-Newton QP's constraint screening against the whole QP.

The first solve of the default ``optimize`` (Gauss-Newton on the default grid, from its first
guess) on a whole-space scene whose winch rides its bounds for minutes (seed 0 case 6: 309 s,
120 parameters, 16200 bound rows) and on ``paper_hill``. Every QP of its iterations is solved
as the solver solves it (:meth:`GaussNewton._screened_solve`: the rows near their limits in the
smallest of the QPs of :data:`~cable_ocp.control.gauss_newton.SCREENED_ROWS` rows that holds
them, broken rows added, or thinned where they do not fit) and, as the baseline in the same
run, whole (every row at once); the solve takes the screened step. Printed per QP: its rows and
parameters, the rows near their limits, both times and their ratio, and the largest difference
of the two steps (DAQP holds its rows to about 1e-5 rad, so that other active rows than the
whole QP's give steps apart by up to the QP's margin,
:data:`~cable_ocp.control.gauss_newton.QP_MARGIN`).
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from cable_ocp.control.gauss_newton import (
    SCREEN_DISTANCE,
    SCREENED_ROWS,
    GaussNewton,
    GaussNewtonSettings,
)
from cable_ocp.control.optimization import resolved_scene
from cable_ocp.control.solvers import SOLVERS, ocp_settings
from cable_ocp.scene.bundled import scene_path
from cable_ocp.scene.schema import load_scene
from cable_ocp.studies.scene_space import space_cases, space_scene

SPACE_CASE = (0, 6)  # seed and case of the whole-space scene (the winch on its bounds)


@dataclass(frozen=True)
class QpTiming:
    """One QP of a Gauss-Newton solve, screened and whole.

    Attributes
    ----------
    rows, parameters : int
        The QP's constraint rows (bounds and any clearance rows) and its unknowns.
    near : int
        Rows within :data:`~cable_ocp.control.gauss_newton.SCREEN_DISTANCE` of their limits.
    screened, whole : float, s
        Wall time of the screened solve (all its rounds) and of the whole QP.
    difference : float, rad or rad/s
        The largest difference of the two steps (nan where one failed).
    """

    rows: int
    parameters: int
    near: int
    screened: float
    whole: float
    difference: float


class BothQps(GaussNewton):
    """A Gauss-Newton solver that solves every QP screened and whole, and takes the screened.

    Every QP size is built before the first one is timed (CasADi builds a QP at its first use).
    """

    def __init__(self, problem, settings: GaussNewtonSettings):
        super().__init__(problem, settings)
        self.timings: list[QpTiming] = []
        whole = self._qp_shape[1]
        for width in {*(min(width, whole) for width in SCREENED_ROWS), whole}:
            self._qp(width)

    def _screened_solve(self, hessian, gradient, matrix, lba, uba, lbx, ubx):
        near = int(np.count_nonzero((-lba < SCREEN_DISTANCE) | (uba < SCREEN_DISTANCE)))
        begun = time.perf_counter()
        step, status = super()._screened_solve(hessian, gradient, matrix, lba, uba, lbx, ubx)
        screened = time.perf_counter() - begun
        begun = time.perf_counter()
        whole, _ = self._whole_solve(hessian, gradient, matrix, lba, uba, lbx, ubx)
        elapsed = time.perf_counter() - begun
        missing = step is None or whole is None
        difference = float("nan") if missing else float(np.max(np.abs(step - whole)))
        timing = QpTiming(matrix.shape[0], gradient.size, near, screened, elapsed, difference)
        self.timings.append(timing)
        return step, status


def first_solve_qps(scene) -> list[QpTiming]:
    """The QPs of the default ``optimize``'s first Gauss-Newton solve of ``scene``, both ways."""
    settings = ocp_settings(None, None, None, None, None)
    entry = SOLVERS[settings.solver]
    settings, scene, _ = resolved_scene(entry.transcription, scene, settings)
    problem = entry.transcription.problem(scene, settings, entry.needs_compiled)
    solver = BothQps(problem, GaussNewtonSettings())
    solver.solve(problem.parameter_values(), problem.first_guess(compiled=True))
    return solver.timings


def report(models_dir: Path | None = None, quick: bool = False) -> dict[str, list[QpTiming]]:
    """Print the QPs of both scenes (``quick``: paper_hill only) and return their timings."""
    scenes = {"paper_hill": load_scene(scene_path("paper_hill"))}
    with tempfile.TemporaryDirectory(prefix="cable_ocp-qp-") as folder:
        if not quick:
            seed, case = SPACE_CASE
            name = f"whole-space seed {seed} case {case}"
            scenes[name] = space_scene(space_cases(case + 1, seed)[case], Path(folder))
        timings = {name: first_solve_qps(scene) for name, scene in scenes.items()}
    print("Gauss-Newton QPs of the default optimize's first solve: screened (the default) "
          "against the whole QP (baseline), same QPs, same run")  # fmt: skip
    print(f"{'scene':34s} {'QP':>3s} {'rows':>6s} {'params':>6s} {'near':>5s} "
          f"{'screened':>9s} {'whole':>9s} {'ratio':>6s} {'max |step diff|':>15s}")  # fmt: skip
    for name, rows in timings.items():
        for k, t in enumerate(rows):
            print(f"{name:34s} {k:3d} {t.rows:6d} {t.parameters:6d} {t.near:5d} "
                  f"{1e3 * t.screened:7.1f}ms {1e3 * t.whole:7.1f}ms "
                  f"{t.whole / t.screened:5.1f}x {t.difference:15.2e}")  # fmt: skip
        total = sum(t.screened for t in rows), sum(t.whole for t in rows)
        print(f"{name:34s} all {1e3 * total[0]:.1f} ms screened against {1e3 * total[1]:.1f} ms "
              f"whole ({total[1] / total[0]:.1f}x)")  # fmt: skip
    return timings
