"""``cable-ocp lower SCENE --out DIR``: an open-loop landing, its checks, the closed-loop hold."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from cable_ocp.cli.arguments import (
    add_animate,
    add_command,
    add_quiet,
    add_set,
    positive,
    scene_from,
)
from cable_ocp.cli.exits import SUCCESS, failed
from cable_ocp.lowering.landing import HOVER

# Units of the figures in summary.json.
UNITS = {
    "landing_line": "m", "landing_error": "m", "landing_speed": "m/s", "least_tension": "N",
    "peak_tension": "N", "least_bond_tension": "N", "hold_deviation": "m", "wall_time": "s",
    "closed_loop_deviation": "m", "compensation_ratio": "%", "real_time_factor": "1",
    "locked_hold_deviation": "m", "hover": "m", "hover_optimised_landing_error": "m",
    "hover_optimised_landing_speed": "m/s", "hover_optimised_wall_time": "s",
    "hover_closed_loop_landing_error": "m", "hover_closed_loop_landing_speed": "m/s",
    "hover_closed_loop_compensation_ratio": "%", "hover_closed_loop_real_time_factor": "1",
}  # fmt: skip


def add_lower_command(subparsers) -> None:
    """Add the ``lower`` command to the ``cable-ocp`` sub-command parsers."""
    parser = add_command(
        subparsers,
        "lower",
        "land a [lowering] scene's load in open loop and hold it by the closed loop",
        "Lower the load of SCENE (a scene with [lowering] and [winch.line]) onto its "
        "target: the reference descent simulated on the scene's own model, the heave fed "
        "forward on the approach, the landing line corrected until the verified run lands; "
        "every constraint measured on that run. Then the landed line held above the target by "
        "the closed loop (mpc), with its compensation ratio. Writes landing.nc (the verified "
        "run), summary.json and figures to --out. Then the landing from a hover (--hover m above "
        "the target): optimised (optimize, Gauss-Newton) and closed-loop (mpc), each with its "
        "checks and figure.",
    )
    add_set(parser, "lowering.land_time=1000")
    parser.add_argument("--no-hold", action="store_true", help="leave out the closed-loop hold")
    parser.add_argument(
        "--hover", type=positive, default=HOVER,
        help="m above the target where the descent stops before the landing from the hover",
    )  # fmt: skip
    parser.add_argument(
        "--no-hover", action="store_true",
        help="leave out the optimised and the closed-loop landing from the hover",
    )  # fmt: skip
    add_animate(parser)
    add_quiet(parser)
    parser.set_defaults(run=run_lower_command)


def run_lower_command(args: argparse.Namespace) -> int:
    """Run ``cable-ocp lower``; 3 when the landing or the hold fails, 0 otherwise."""
    from cable_ocp import plots, result_files
    from cable_ocp.cli.files import results_folder
    from cable_ocp.lowering.hold import hold
    from cable_ocp.lowering.landing import land, landing_scene
    from cable_ocp.lowering.plan import plan_landing
    from cable_ocp.plots import landing, survey
    from cable_ocp.plots.drum_limits import drum_use
    from cable_ocp.plots.tension import tension_against_static
    from cable_ocp.scene.output import json_text
    from cable_ocp.simulation.run import simulate

    scene = scene_from(args)
    if scene.lowering is None or scene.winch.line is None:
        raise ValueError(
            f"{args.scene}: lower needs a scene with [lowering] and [winch.line] (see "
            "models/deploy.toml)"
        )
    hovering = None if args.no_hover else landing_scene(scene, args.hover)  # refused early
    plan = plan_landing(scene, quiet=args.quiet)
    held = None if args.no_hold else hold(scene, quiet=args.quiet)
    hover = {}
    if hovering is not None:
        hover = {"optimised": land(hovering, quiet=args.quiet),
                 "closed_loop": land(hovering, closed_loop=True, quiet=args.quiet)}  # fmt: skip
    summary = {"scene": scene.name, "landing_success": plan.success, "landing": plan.status,
               "landing_line": plan.descent.landing_line, "wall_time": plan.wall_time}  # fmt: skip
    if plan.report is not None:
        report = plan.report
        summary.update(
            landing_error=report.landing_error, landing_speed=report.landing_speed,
            least_tension=report.least_tension, peak_tension=report.peak_tension,
            least_bond_tension=report.least_bond_tension, hold_deviation=report.hold_deviation,
            checks=[str(check) for check in report.checks],
        )  # fmt: skip
    if held is not None:
        locked = simulate(held.scene, quiet=True)  # the hold's baseline: the same sea, no winch
        ratio = held.compensation_ratio
        summary.update(
            hold_success=held.success, hold=held.status, closed_loop_deviation=held.deviation,
            compensation_ratio=ratio if math.isfinite(ratio) else None,
            real_time_factor=held.mpc.real_time_factor,
            locked_hold_deviation=float(abs(locked.clearance_error).max()),
        )  # fmt: skip
    if hover:
        summary["hover"] = args.hover
    for name, result in hover.items():
        summary.update(_hover_fields(name, result))
    summary["units"] = {name: unit for name, unit in UNITS.items() if name in summary}
    with results_folder(args.out) as folder:
        (folder / "summary.json").write_text(json_text(summary))
        if plan.run is not None:
            plan.run.save(folder / "landing")
            landing.landing(plan.run, plan.descent, plan.report, folder / "landing.png",
                            label="open-loop landing")  # fmt: skip
            survey.seabed_view(plan.run, scene.seabed, window=None,
                               path=folder / "seabed_view.png")  # fmt: skip
            plots.line_run(plan.run, path=folder / "line_run.png")
            if args.animate:
                plots.animate(plan.run, folder / "animation.gif", scene.seabed.clearance)
        for name, result in hover.items():
            result_files.save(result.result, folder / f"hover_{name}.nc")  # co.load_result
            run = result.result.trajectory
            if run is not None:
                label = "closed loop" if result.closed_loop else "optimised"
                if not result.closed_loop:
                    label += f" ({result.result.solver})"
                landing.landing(run, report=result.report, label=label,
                                path=folder / f"hover_{name}.png")  # fmt: skip
                drum_use(result.result, [label], folder / f"hover_{name}_drum.png")
        if held is not None:
            result_files.save(held.mpc, folder / "hold.nc")
            plots.clearance([locked, held.mpc], held.scene.seabed.clearance,
                            ["winch locked", "closed loop"], folder / "hold_clearance.png",
                            zoom=True)  # fmt: skip
            drum_use(held.mpc, ["closed loop"], folder / "hold_drum.png")
            tension_against_static([locked, held.mpc], ["winch locked", "closed loop"],
                                   folder / "hold_tension.png")  # fmt: skip
    print(f"landing: {plan.status}")
    if held is not None:
        print(f"hold: {held.status}; {held.mpc.real_time_factor:.0f}x faster than real time")
    for name, result in hover.items():
        print(f"from the hover ({name.replace('_', ' ')}): {result.status}")
    print(f"results and figures written to {Path(args.out).resolve()}")
    outcomes = [("landing", plan), ("hold", held)]
    outcomes += [(f"{name.replace('_', '-')} landing from the hover", result)
                 for name, result in hover.items()]  # fmt: skip
    failures = [name for name, outcome in outcomes if outcome is not None and not outcome.success]
    if failures:
        return failed("lower", f"the {' and the '.join(failures)} failed")
    return SUCCESS


def _hover_fields(name: str, result) -> dict:
    """The summary's figures of a landing from the hover (``name``: optimised or closed_loop)."""
    key = f"hover_{name}"
    fields = {f"{key}_success": result.success, key: result.status}
    report = result.report
    if report is not None:
        fields.update({f"{key}_landing_error": report.landing_error,
                       f"{key}_landing_speed": report.landing_speed})  # fmt: skip
    if result.closed_loop:
        ratio = result.compensation_ratio
        fields[f"{key}_compensation_ratio"] = ratio if math.isfinite(ratio) else None
        fields[f"{key}_real_time_factor"] = result.result.real_time_factor
    else:
        fields[f"{key}_wall_time"] = result.result.wall_time
    return fields
