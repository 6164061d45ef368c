"""The policy's speed: its C function's time per sample beside the MPC's median solve.

:func:`bench_policy` compiles the policy's C export
(:meth:`cable_ocp.policy.policy.Policy.to_c`) with a timing loop (``cc -O2``), evaluates it on
the policy's own training observations, and runs the closed loop (the MPC) on the family's base
scene in the same process, so that the ratio is of one run on one machine. It then runs the
policy with its safety net on that scene, and times its rollout check per sample
(:mod:`cable_ocp.policy.rollout`) and the whole step where the policy acted (the observation,
the network in numpy and the three checks).
"""

from __future__ import annotations

import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.policy.observation import FEATURES
from cable_ocp.scene.schema import Scene

EVALUATIONS = 200_000  # C evaluations timed
HARNESS = """#include <stdio.h>
#include <time.h>
#include "{header}"
int main(void) {{
    static double o[{rows}][{width}];
    volatile double sink = 0.0;
    struct timespec a, b;
    long i; int r, j;
    for (r = 0; r < {rows}; ++r)
        for (j = 0; j < {width}; ++j)
            if (scanf("%lf", &o[r][j]) != 1) return 1;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (i = 0; i < {evaluations}L; ++i) sink += cable_ocp_policy(o[i % {rows}]);
    clock_gettime(CLOCK_MONOTONIC, &b);
    printf("%.6f\\n", ((b.tv_sec - a.tv_sec) * 1e9 + (b.tv_nsec - a.tv_nsec)) / {evaluations}.0);
    return sink != sink;
}}
"""


def c_time(policy, observations: np.ndarray, evaluations: int = EVALUATIONS) -> float:
    """Mean wall time (s) of one evaluation of the compiled C function (``cc -O2``).

    Raises
    ------
    RuntimeError
        No C compiler ``cc`` on this machine.
    """
    compiler = shutil.which("cc")
    if compiler is None:
        raise RuntimeError("bench_policy: no C compiler (cc) to time the policy's C export")
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        c_file, h_file = policy.to_c(folder / "policy")
        main = folder / "bench.c"
        rows = observations.shape[0]
        main.write_text(HARNESS.format(header=h_file.name, rows=rows, width=len(FEATURES),
                                       evaluations=evaluations))  # fmt: skip
        binary = folder / "bench"
        subprocess.run([compiler, "-O2", str(c_file), str(main), "-o", str(binary), "-lm"],
                       check=True, cwd=folder)  # fmt: skip
        text = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in observations)
        out = subprocess.run([str(binary)], input=text, capture_output=True, text=True,
                             check=True)  # fmt: skip
    return float(out.stdout) * 1e-9


def bench_policy(policy, scene, quiet: bool = False) -> dict:
    """Time the policy's C function, numpy and CasADi forms, and the MPC on ``scene``.

    Parameters
    ----------
    policy : Policy
    scene : Scene, Family, str or path-like
        The MPC's scene, or a family (its file or bundled name) whose base scene it is.
    quiet : bool
        Print nothing (else a table of the figures).

    Returns
    -------
    dict
        ``c_per_sample``, ``numpy_per_sample``, ``casadi_per_sample`` and
        ``mpc_median_solve`` (s), ``ratio`` (the MPC's median solve over the C function's),
        ``rollout_check_median`` and ``net_step_median`` (s, with the safety net: its rollout
        check's median time per sample, and the median time of a step the policy acted at),
        and ``handed_share``.
    """
    from cable_ocp.policy.family import load_family

    observations = policy.observations[:: max(1, policy.observations.shape[0] // 1000)][:1000]
    c_seconds = c_time(policy, observations)
    numpy_seconds = _per_call(lambda o: policy(o[None, :]), observations)
    function = policy.function()
    casadi_seconds = _per_call(function, observations)
    if not isinstance(scene, Scene):
        scene = load_family(scene).base
    result = mpc(scene, quiet=True)
    solve = float(np.median(result.solves.solve_time))
    kept = _Kept(policy)
    netted = mpc(scene, quiet=True, policy=kept)
    checks = kept.made.check.seconds
    acted = netted.solves.solve_time[netted.solves.by_policy]
    figures = {
        "c_per_sample": c_seconds,
        "numpy_per_sample": numpy_seconds,
        "casadi_per_sample": casadi_seconds,
        "mpc_median_solve": solve,
        "ratio": solve / c_seconds,
        "rollout_check_median": float(np.median(checks)) if checks else float("nan"),
        "net_step_median": float(np.median(acted)) if acted.size else float("nan"),
        "handed_share": netted.handed_share,
    }
    if not quiet:
        print(f"policy {policy.name}: hidden {policy.network.hidden}, {len(FEATURES)} inputs")
        print(f"  C (cc -O2)        {c_seconds * 1e6:10.3f} us per sample")
        print(f"  numpy             {numpy_seconds * 1e6:10.3f} us per sample")
        print(f"  CasADi Function   {casadi_seconds * 1e6:10.3f} us per sample")
        print(f"  MPC median solve  {solve * 1e6:10.1f} us ({scene.name}, the same run)")
        print(f"  ratio MPC / C     {figures['ratio']:10.0f}")
        print(
            f"  with its safety net on {scene.name} ({netted.handed_share:.1%} handed to the MPC):"
        )
        print(f"    rollout check   {figures['rollout_check_median'] * 1e6:10.1f} us per sample "
              f"(median of {len(checks)}, {kept.made.check.sweeps} Jacobian sweeps)")  # fmt: skip
        print(f"    policy's step   {figures['net_step_median'] * 1e6:10.1f} us per sample "
              "(median: observation, network, checks)")  # fmt: skip
    return figures


class _Kept:
    """The policy, keeping the controller it made for the loop (to read its check's times)."""

    def __init__(self, policy):
        self.policy, self.name, self.made = policy, policy.name, None

    def controller(self, parts):
        self.made = self.policy.controller(parts)
        return self.made


def _per_call(function, observations: np.ndarray, repeats: int = 3) -> float:
    """Least mean time (s) of ``function(observation)`` over the rows, of ``repeats``."""
    best = float("inf")
    for _ in range(repeats):
        started = time.perf_counter()
        for row in observations:
            function(row)
        best = min(best, (time.perf_counter() - started) / observations.shape[0])
    return best
