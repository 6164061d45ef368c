"""A policy's validation on held-out scenes of its family, and its statistical statement.

On ``n`` scenes drawn from the family with a seed that training did not use
(:func:`held_out_seed`), each run on the scene's full model (the plant) on the Dask engine:

- the MPC alone (:func:`cable_ocp.mpc`), the policy alone
  (:meth:`cable_ocp.policy.policy.Policy.alone`), the policy with its safety net, and the winch
  locked (:func:`~cable_ocp.control.closed_loop.references.reference_runs`), each with its Omega
  (eq. 39);
- a run **succeeds** when the loop does (the plant ran to the end, its physics and the minimum
  clearance held, no solve failed) and its Omega is within :data:`OMEGA_FACTOR` times the MPC's
  on the same scene plus :data:`OMEGA_SLACK` (a policy that keeps the plant alive but lets the
  load wander does not succeed);
- the statement (Hertneck et al. 2018, with Clopper and Pearson's exact bound instead of
  Hoeffding's): with ``N`` runs and ``k`` failures, the success probability is at least ``p``
  with confidence ``1 - delta`` (:func:`success_bound`).
"""

from __future__ import annotations

import numpy as np

from cable_ocp.control.closed_loop.loop import mpc
from cable_ocp.control.closed_loop.references import reference_runs

OMEGA_FACTOR, OMEGA_SLACK = 2.0, 0.02  # -, m: a run's Omega within 2x the MPC's plus 2 cm
DELTA = 0.05  # the statement's 1 - confidence
HELD_OUT = 1_000_003  # added to the training seed: the held-out scenes' seed


def held_out_seed(seed: int) -> int:
    """The seed of a policy's held-out scenes, from its training seed."""
    return seed + HELD_OUT


def success_bound(runs: int, failures: int, delta: float = DELTA) -> float:
    """One-sided Clopper-Pearson lower bound on the success probability, confidence 1 - delta.

    With ``runs`` independent runs of which ``failures`` failed, the success probability is at
    least the returned ``p`` with confidence ``1 - delta`` (0 when every run failed).
    """
    from scipy.stats import beta

    successes = runs - failures
    if not 0 <= failures <= runs or runs < 1:
        raise ValueError(f"success_bound: {failures} failures of {runs} runs")
    if successes == 0:
        return 0.0
    return float(beta.ppf(delta, successes, failures + 1))


def statement(runs: int, failures: int, delta: float = DELTA) -> str:
    """The statistical statement in words (module docstring)."""
    p = success_bound(runs, failures, delta)
    return (
        f"with {runs} validation runs and {failures} failures, the success probability is at "
        f"least {p:.3f} with confidence {1 - delta:.2f} (Clopper-Pearson)"
    )


def succeeded(result, mpc_omega: float) -> bool:
    """Whether a run succeeded (module docstring)."""
    limit = OMEGA_FACTOR * mpc_omega + OMEGA_SLACK
    return bool(result.success and np.isfinite(result.omega) and result.omega <= limit)


def validate_scene(scene, policy) -> dict:
    """One held-out scene: the MPC, the policy alone and with its net, the winch locked.

    A scene whose loop raises (its end starting off a bathymetry grid, say) is a row of
    failures that says why, not the end of the validation.
    """
    try:
        return _runs(scene, policy)
    except Exception as error:  # noqa: BLE001 - a failed scene is a row, not a crash
        nan = float("nan")
        return {"mpc_omega": nan, "mpc_success": False, "mpc_median_solve": nan,
                "alone_omega": nan, "alone_success": False, "net_omega": nan,
                "net_success": False, "handed_share": nan, "locked_omega": nan,
                "alone_status": f"{type(error).__name__}: {error}"}  # fmt: skip


def _runs(scene, policy) -> dict:
    """:func:`validate_scene`'s runs."""
    plain = mpc(scene, quiet=True)
    alone = mpc(scene, quiet=True, policy=policy.alone())
    netted = mpc(scene, quiet=True, policy=policy)
    locked = reference_runs(scene, plain).omegas.get("locked", float("nan"))
    return {
        "mpc_omega": plain.omega,
        "mpc_success": bool(plain.success),
        "mpc_median_solve": float(np.median(plain.solves.solve_time)),
        "alone_omega": alone.omega,
        "alone_success": succeeded(alone, plain.omega),
        "net_omega": netted.omega,
        "net_success": succeeded(netted, plain.omega),
        "handed_share": netted.handed_share,
        "locked_omega": locked,
        "alone_status": alone.status,
    }


def validate_policy(
    policy, family, scenes: int = 100, scheduler: str | None = None,
    workers: int | None = None, quiet: bool = False, indices: range | None = None,
) -> dict:  # fmt: skip
    """Validate a policy on ``scenes`` held-out scenes of its family (module docstring).

    ``indices``: run only these of the ``scenes`` drawn (a part of a long validation, run in
    chunks; :func:`summarise` of the parts' ``rows`` together gives the whole's figures).

    Returns the figures (json-ready): per run kind the successes, the median Omega and its
    ratio to the MPC's, the share handed to the MPC, and the statements; ``rows`` holds each
    scene's, with its index in ``scene``.

    Raises
    ------
    ValueError
        ``indices`` not a range within ``range(scenes)``, or a policy of another family, before
        any run.
    """
    from tqdm.auto import tqdm

    from cable_ocp.policy.family import load_family
    from cable_ocp.sweep.runner import mapped

    indices = range(scenes) if indices is None else indices
    if (
        not isinstance(indices, range)
        or not indices
        or not (0 <= min(indices) and max(indices) < scenes)
    ):
        raise ValueError(
            f"validate_policy: indices = {indices!r:.60}: expected a non-empty range within "
            f"range({scenes}) (the scenes drawn)"
        )
    family = load_family(family)
    if policy.family.get("fingerprint") != family.fingerprint:
        raise ValueError(
            f"validate_policy: the policy was learned for {policy.family.get('name')!r}, not "
            f"for the family {family.name!r}"
        )
    drawn = family.draw(scenes, held_out_seed(policy.seed))
    bar = tqdm(total=len(indices), desc=f"validate {family.name}", disable=quiet)
    try:
        rows = mapped(validate_scene, [(drawn[k], policy) for k in indices], scheduler, workers,
                      lambda done: bar.update(done - bar.n))  # fmt: skip
    finally:
        bar.close()
    return summarise([{"scene": k, **row} for k, row in zip(indices, rows, strict=True)])


def summarise(rows: list[dict]) -> dict:
    """The validation's figures from its scenes' rows (:func:`validate_scene`)."""

    def column(name):
        return np.array([row[name] for row in rows], dtype=float)

    n = len(rows)
    mpc_omega = np.nanmedian(column("mpc_omega"))
    figures = {"scenes": n, "mpc": {"successes": int(column("mpc_success").sum()),
                                    "median_omega": float(mpc_omega),
                                    "median_solve_time": float(np.median(
                                        column("mpc_median_solve")))}}  # fmt: skip
    for kind in ("alone", "net"):
        successes = int(column(f"{kind}_success").sum())
        median = float(np.nanmedian(column(f"{kind}_omega")))
        figures[kind] = {
            "successes": successes,
            "success_rate": successes / n,
            "median_omega": median,
            "median_omega_ratio": median / float(mpc_omega),
            "statement": statement(n, n - successes),
            "success_bound": success_bound(n, n - successes),
        }
    figures["net"]["handed_share"] = float(np.nanmean(column("handed_share")))
    figures["locked"] = {"median_omega": float(np.nanmedian(column("locked_omega")))}
    figures["rows"] = [{k: v for k, v in row.items() if k != "alone_status"} for row in rows]
    return figures
