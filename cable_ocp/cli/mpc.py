"""``cable-ocp mpc SCENE --out DIR``: a closed-loop run with its figures and figures of merit."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from cable_ocp.cli.arguments import (
    add_command,
    add_model_options,
    add_quiet,
    add_set,
    fraction,
    integer,
    positive,
    scene_from,
    weight,
)
from cable_ocp.cli.exits import SUCCESS, failed
from cable_ocp.control.closed_loop.settings import CLOSED_LOOP_SOLVERS, MpcSettings
from cable_ocp.control.settings import ModelSettings

# The open-loop optimum with the heave paid out by eq. 38 knows the heave exactly: an ideal, not
# a controller, which is why it can beat the closed loop (issue 45).
IDEAL = "open-loop + heave feedback"
IDEAL_NOTE = (
    f"'{IDEAL}' pays out the scene's own heave exactly at every RK4 step (eq. 38: the heave "
    "known in advance, with no measurement, filter, sample-and-hold or margin): an ideal the "
    "closed loop cannot have, as it measures the heave and acts every {sample:g} s, so it may "
    "come out ahead; judge the closed loop against 'locked' and 'open-loop'"
)


# The options that set the MpcSettings field of their name, with their argparse keywords; a
# field that is True by default is turned off by --no-FIELD.
SETTINGS_OPTIONS = {
    "horizon": dict(type=positive, help="prediction horizon [s] (default: about 20 s, a multiple "
                    "of --interval within the scene's duration)"),
    "sample": dict(type=positive, help="time between solves [s] (default: the duration's whole "
                   "fraction nearest 1 s that the plant's steps divide)"),
    "interval": dict(type=positive, help="interval of the plan [s] (default: the multiple of "
                     "--sample nearest 5 s)"),
    "first_interval": dict(type=positive, help="the plan's first interval [s], at most "
                           "--interval (move blocking: one sample roughly halves Omega where "
                           "the winch can follow; default: --interval)"),
    "heave_filter": dict(type=positive, help="time constant of the heave low-pass [s]"),
    "heave_margin": dict(type=fraction, help="room kept for the heave feedback, 0..1"),
    "limiter_band": dict(type=positive, help="width of the plant's soft limiter at each end of "
                         "the winch range [rad] (default: 0.5 rad, or a quarter of a narrower "
                         "range)"),
    "rate_weight": dict(type=weight, help="pay-out speed weight [s^2]"),
    "solver": dict(choices=tuple(CLOSED_LOOP_SOLVERS), help="gauss-newton: one Gauss-Newton "
                   "step per sample (real-time iteration); ipopt: IPOPT"),
    "heave_feedback": dict(help="apply the plan only (no pay-out of the measured heave)"),
}  # fmt: skip


def add_settings_options(parser: argparse.ArgumentParser) -> None:
    """Add an option for each field of :data:`SETTINGS_OPTIONS`, its default the settings' own."""
    defaults = MpcSettings()
    for field, keywords in SETTINGS_OPTIONS.items():
        default = getattr(defaults, field)
        if default is True:
            parser.add_argument(f"--no-{field.replace('_', '-')}", dest=field,
                                action="store_false", **keywords)  # fmt: skip
        else:
            parser.add_argument(f"--{field.replace('_', '-')}", default=default, **keywords)


def add_mpc_command(subparsers) -> None:
    """Add the ``mpc`` command to the ``cable-ocp`` sub-command parsers."""
    parser = add_command(
        subparsers,
        "mpc",
        "closed-loop winch control: a receding-horizon OCP driving the scene's model",
        "Closed-loop winch control of SCENE: every --sample seconds a receding-horizon OCP on a "
        "reduced model is solved from the measured state; the scene's own model (with its heave, "
        "e.g. --set top.heave.amplitude=1 --set top.heave.period=8) is the plant. Writes mpc.nc "
        "(the run, netCDF), summary.json and figures to --out.",
    )
    add_settings_options(parser)
    add_model_options(
        parser,
        elements="elements of the controller's reduced model (default: 2)",
        step="RK4 step of the reduced model [s] (default: the largest whole fraction of --sample "
        "within 0.7 of the reduced model's RK4 limit along the locked run, at most 1 s)",
    )
    parser.add_argument(
        "--max-iter", type=integer(1, 10**6),
        help="iterations per solve (default: 1 with gauss-newton, the real-time iteration; "
        "IPOPT's own default with ipopt)",
    )  # fmt: skip
    parser.add_argument(
        "--open-loop", action="store_true",
        help="also optimise open loop (without the heave) and simulate that profile as a reference",
    )  # fmt: skip
    parser.add_argument(
        "--policy", type=Path, metavar="POLICY.nc",
        help="a learned policy (cable-ocp learn) acts where its safety net trusts it, the MPC "
        "elsewhere; summary.json's handed_share says how often the MPC did",
    )  # fmt: skip
    add_set(parser, "top.heave.amplitude=1")
    add_quiet(parser)
    parser.set_defaults(run=run_mpc_command)


def settings_from(args: argparse.Namespace) -> MpcSettings:
    """The closed loop's settings from the command line's options.

    ``--max-iter`` follows the solver when it is not given (:meth:`MpcSettings.resolved`): one
    Gauss-Newton step (the real-time iteration) or IPOPT's own default, since one IPOPT
    iteration never converges.
    """
    solver_settings = None
    if args.max_iter is not None:
        solver_settings = replace(CLOSED_LOOP_SOLVERS[args.solver], max_iter=args.max_iter)
    return MpcSettings(
        **{field: getattr(args, field) for field in SETTINGS_OPTIONS},
        model=ModelSettings(args.elements, args.step),
        solver_settings=solver_settings,
    )


def run_mpc_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp mpc``; returns the exit code (3 if a solve, the plant or a check failed)."""
    from cable_ocp import plots
    from cable_ocp.cli.files import results_folder
    from cable_ocp.control.closed_loop.loop import mpc
    from cable_ocp.control.closed_loop.references import reference_runs
    from cable_ocp.plots import closed_loop
    from cable_ocp.plots.drum_limits import drum_use
    from cable_ocp.plots.tension import tension_against_static
    from cable_ocp.scene.output import json_text

    scene = scene_from(args)
    policy = None
    if args.policy is not None:
        from cable_ocp.policy.policy import load_policy

        policy = load_policy(args.policy)  # refused here, before any work, when it is no policy
    result = mpc(scene, settings_from(args), quiet=args.quiet, policy=policy)
    names = ("locked", "open-loop") if args.open_loop else ("locked",)
    references = reference_runs(scene, result, names)
    figures = result.summary()
    units = {**figures.pop("units"), "reference_omegas": "m"}
    notes = list(references.notes)
    if IDEAL in references.omegas:
        notes.append(IDEAL_NOTE.format(sample=result.settings["sample"]))
    figures.update(reference_omegas=references.omegas, reference_notes=notes)
    figures["units"] = units
    runs = [*references.runs.values(), result]
    labels = [*references.runs, plots.result_label(result)]
    seabed = scene.seabed
    with results_folder(args.out) as folder:
        result.save(folder)
        plots.clearance(runs, seabed.clearance, labels, folder / "clearance.png",
                        seabed.minimum_clearance, zoom=True)  # fmt: skip
        closed_loop.solve_times(result, folder / "solve_times.png", scene.name)
        plots.winch_angle(result, bounds=result.angle_range, path=folder / "winch_angle.png")
        drum_use(result, path=folder / "drum.png")
        tension_against_static(runs, labels, folder / "tension.png")
        (folder / "summary.json").write_text(json_text(figures))
    summary = {k: v for k, v in figures.items() if k != "failures"}
    print(json_text(summary))
    print(f"results and figures written to {Path(args.out).resolve()}")
    if not result.success:
        return failed("mpc", f"the closed loop failed: {result.status}")
    return SUCCESS
