"""Learning a policy: ``learn_policy(family, ...)`` draws scenes, records the MPC, trains, repeats.

1. Draw ``scenes`` scenes of the family with ``seed`` (:meth:`.family.Family.draw`).
2. Round 0: run the closed loop (the MPC) on each on the Dask engine, recording (observation,
   action) pairs (:func:`.data.generate`); fit the network by L-BFGS
   (:meth:`.network.Network.fit`, its initial weights seeded by ``seed``).
3. Each DAgger round: run the current network on the same scenes, the MPC labelling every
   state it visits; add the pairs, fit again.

The same family, seed and settings give the same policy, bit for bit, on one machine: the
scenes are drawn by a seeded generator, each scene's pairs are kept in the scenes' order
whichever worker ran them, and the fit is deterministic.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cable_ocp.policy.data import SKIPPED_SHOWN as SHOWN
from cable_ocp.policy.data import generate
from cable_ocp.policy.defaults import C_NAME, HIDDEN, POLICY_FILE, ROUNDS, SCENES
from cable_ocp.policy.family import Family, load_family
from cable_ocp.policy.network import Network
from cable_ocp.policy.policy import Policy


def rate_limit(family: Family, actions: np.ndarray) -> float:
    """The drum rate's clip (rad/s): the winch's ``rate_max``, else the data's largest rate."""
    limit = family.base.winch.rate_max
    if limit is not None:
        return float(limit)
    return float(max(np.max(np.abs(actions), initial=0.0), 1e-3))


def learn_policy(
    family: Family | str | Path,
    out: str | Path | None = None,
    scenes: int = SCENES,
    rounds: int = ROUNDS,
    hidden: tuple[int, ...] = HIDDEN,
    seed: int = 0,
    scheduler: str | None = None,
    workers: int | None = None,
    quiet: bool = False,
) -> Policy:
    """Learn a winch policy for a scene family (module docstring).

    Parameters
    ----------
    family : Family, str or path-like
        The family, its file, or a bundled family's name (``"hill_tow"``, ``"landing_hold"``).
    out : path-like, optional
        A folder to write ``policy.nc`` and the C export ``policy.c``/``policy.h`` in.
    scenes : int
        Training scenes drawn.
    rounds : int
        DAgger rounds after the MPC's own runs (0: imitate the MPC's runs only).
    hidden : tuple of int
        Widths of the network's hidden layers.
    seed : int
        Seeds the scenes drawn and the network's initial weights.
    scheduler : str, optional
        A Dask scheduler's address; None: a LocalCluster on this machine.
    workers : int, optional
        The LocalCluster's workers (None: one per core).
    quiet : bool
        No progress bar.

    Raises
    ------
    ValueError
        A count out of its range, a family file at fault, or ``workers`` with ``scheduler``,
        before any scene runs.
    """
    for name, value, low in (("scenes", scenes, 2), ("rounds", rounds, 0), ("seed", seed, 0)):
        if isinstance(value, bool) or not isinstance(value, int) or value < low:
            raise ValueError(f"learn_policy: {name} = {value!r}: expected an integer >= {low}")
    family = load_family(family)
    drawn = family.draw(scenes, seed)
    from tqdm.auto import tqdm

    bar = tqdm(total=scenes * (rounds + 1), desc=f"learn {family.name}", disable=quiet)
    figures: dict = {"rounds": []}
    network = None
    pairs = None
    try:
        for round_ in range(rounds + 1):
            done = bar.n
            new, records = generate(
                drawn,
                network,
                round_,
                scheduler,
                workers,
                lambda k, d=done: bar.update(d + k - bar.n),
            )
            pairs = new if pairs is None else pairs + new
            network, error = Network.fit(
                pairs.observations, pairs.actions, hidden,
                rate_limit(family, pairs.actions), seed,
            )  # fmt: skip
            figures["rounds"].append({
                "round": round_,
                "pairs": int(new.actions.size),
                # Samples that gave no pair (the MPC's solve failed there, a non-finite
                # observation or label: data.Recorder), and why, on the first scenes they hit.
                "samples_skipped": int(sum(r["skipped"] for r in records)),
                "skipped_why": [why for r in records for why in r["skipped_why"]][:SHOWN],
                "runs_succeeded": int(sum(bool(r["success"]) for r in records)),
                "median_omega": float(np.nanmedian([r["omega"] for r in records])),
                "fit_error": error,
            })  # fmt: skip
            bar.set_postfix(round=round_, fit=f"{error:.3g}")
    finally:
        bar.close()
    figures["hidden"] = list(hidden)
    figures["scenes"] = scenes
    policy = Policy(
        network, family.record(), pairs.observations, pairs.actions, pairs.rounds, seed,
        {"training": figures},
    )  # fmt: skip
    if out is not None:
        out = Path(out)
        policy.save(out / POLICY_FILE)
        policy.to_c(out / C_NAME)
    return policy
