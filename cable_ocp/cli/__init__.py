"""The command line, ``cable-ocp COMMAND``.

Commands: simulate, replay, optimize, compare, mpc, lower, sweep, validate, study, bench;
``cable-ocp scenes`` lists the bundled scenes, ``cable-ocp schema [KEY]`` the fields of a scene;
``cable-ocp COMMAND --help`` tells what each command does.

Every expected failure is one line ``cable-ocp COMMAND: error: ...`` on stderr and a non-zero exit
code: 2 for bad input (arguments, scene and sweep files, a results folder that must not be
written, one inside a read-only folder included), 1 for a failing file system, 3 when the
optimiser fails (or a sweep case, or a sweep's Dask engine) or a run is not physical (a rope
that pushes, an end under the seabed; its results are written all the same), 130 when
interrupted. Bad input is
refused before any simulation.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

from cable_ocp.cli.arguments import OUT_HELP, SCENE_HELP, DefaultsShown, integer, positive
from cable_ocp.cli.exports import winch_csv
from cable_ocp.cli.files import check_replaceable, results_folder
from cable_ocp.cli.lower import add_lower_command
from cable_ocp.cli.mpc import add_mpc_command
from cable_ocp.cli.reference import add_reference_commands
from cable_ocp.cli.sweep import add_sweep_command
from cable_ocp.scene.bundled import models_dir, scene_argument
from cable_ocp.scene.output import claimed_target, json_text
from cable_ocp.scene.schema import load_scene

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib


def parse_overrides(pairs: list[str]) -> dict:
    """``["model.elements=30", "top.motion='tow'"]`` -> ``{"model.elements": 30, ...}``.

    Values are read as TOML, so numbers, booleans, strings and arrays keep their types; a bare
    word is taken as a string.
    """
    overrides = {}
    for pair in pairs:
        key, sep, text = pair.partition("=")
        if not sep:
            raise ValueError(f"--set {pair!r}: expected KEY=VALUE, e.g. model.elements=30")
        try:
            value = tomllib.loads(f"v = {text}")["v"]
        except (ValueError, RecursionError):  # not TOML: taken as a string
            value = text
        overrides[key.strip()] = value
    return overrides


def _simulate(args) -> int:
    from cable_ocp.simulation.progress import stage
    from cable_ocp.simulation.run import simulate

    scene = load_scene(args.scene, parse_overrides(args.set))
    knots = args.knots
    if knots is not None and len(knots) != scene.winch.knots:
        raise ValueError(
            f"--knots: {len(knots)} angles given; the scene has winch.knots = "
            f"{scene.winch.knots} (one angle phi_1..phi_p per knot, rad)"
        )
    # Compiled unless --interpreted: without a compiler or a writable cache, the interpreted
    # model runs after the same warning as the API's.
    with stage(f"simulate {scene.name}", scene.numerics.duration, quiet=args.quiet):
        trajectory = simulate(scene, winch=knots, quiet=args.quiet, compiled=not args.interpreted)
    return _write_run("simulate", trajectory, scene, Path(args.out), args.animate)


def _replay(args) -> int:
    from cable_ocp.control.optimization import OcpResult
    from cable_ocp.control.results import load_result
    from cable_ocp.simulation.progress import stage
    from cable_ocp.simulation.run import simulate

    source = args.result.expanduser().resolve()
    source = source.parent if source.suffix == ".nc" else source
    out = args.out.expanduser().resolve()
    if out == source or out in source.parents:
        raise ValueError(
            f"--out {args.out}: is the folder replay reads ({source}), which the replay's run "
            "would replace; give another folder; nothing was written"
        )
    result = load_result(args.result)
    if not isinstance(result, OcpResult):
        raise ValueError(
            f"{args.result}: holds a {type(result).__name__}; replay takes what optimize saved "
            "(result.nc), whose profile it drives"
        )
    scene = result.scene.updated(parse_overrides(args.set)) if args.set else result.scene
    with stage(f"replay {scene.name}", scene.numerics.duration, quiet=args.quiet):
        trajectory = simulate(scene, winch=result, quiet=args.quiet, compiled=not args.interpreted)
    return _write_run(
        "replay", trajectory, scene, Path(args.out), args.animate, {"saved_omega": result.omega}
    )


# Units of the figures a command adds to a run's summary.json (the run's own: its summary()).
RUN_UNITS = {"saved_omega": "m", "locked_omega": "m"}


def _write_run(
    command: str, trajectory, scene, out: Path, animate: bool, extra: dict | None = None
) -> int:
    """A run's trajectory, figures and summary.json in ``out``; the summary printed.

    Returns the exit code: 3 when the run fails its physics check (a rope that pushes, an end
    under the seabed: :attr:`~cable_ocp.simulation.trajectory.Trajectory.physics`), written all
    the same so that it can be looked at; else 0.
    """
    from cable_ocp import plots

    seabed = scene.seabed
    with results_folder(out) as folder:
        trajectory.save(folder / "trajectory")
        if animate:
            plots.animate(trajectory, folder / "animation.gif", seabed.clearance)
        plots.end_trajectory(trajectory, path=folder / "end_trajectory.png")
        plots.clearance(trajectory, seabed.clearance, path=folder / "clearance.png",
                        minimum_clearance=seabed.minimum_clearance)  # fmt: skip
        plots.cable_shapes(trajectory, seabed=seabed, path=folder / "cable_shapes.png")
        plots.winch_angle(trajectory, bounds=(scene.winch.angle_min, scene.winch.angle_max),
                          path=folder / "winch_angle.png")  # fmt: skip
        if scene.winch.line is not None:  # a line paid out by elements: n over time
            plots.line_run(trajectory, path=folder / "line_run.png")
        figures = trajectory.summary()
        units = {**figures.pop("units"), **{name: RUN_UNITS[name] for name in extra or {}}}
        summary = {**figures, "scene": scene.name, **(extra or {}), "units": units}
        (folder / "summary.json").write_text(json_text(summary))
    print(json_text(summary))
    print(f"results and figures written to {out.resolve()}")
    if not trajectory.success:
        print(
            f"cable-ocp {command}: error: the run is not physical: {trajectory.status}",
            file=sys.stderr,
        )
        return 3
    return 0


def _given(args, names: tuple[str, ...]) -> dict:
    """The options among ``names`` given on the command line (the others are None)."""
    return {name: getattr(args, name) for name in names if getattr(args, name) is not None}


def _optimize_options(args, solver: str | None = None, beside: str | None = None) -> dict:
    """``optimize``'s solver and settings from the options given; unset ones are its own.

    The solver is ``solver``, else ``--solver``, else ``--method nelder-mead``'s, else IPOPT
    when an IPOPT option (``--hessian``, ``--shooting multiple``) is given, else the registry's
    default. ``--hessian exact`` needs the interpreted model. An option that neither the solver
    nor the solver run ``beside`` it on the same options (compare's) takes is refused.
    """
    from cable_ocp.control.settings import GridSettings, ModelSettings, TranscriptionSettings
    from cable_ocp.control.solvers import DEFAULT_SOLVER, solver_named

    method = getattr(args, "method", None)
    if method == "nelder-mead" and args.solver not in (None, "nelder-mead"):
        raise ValueError(
            f"--method nelder-mead with --solver {args.solver}: the paper's method is solver "
            "nelder-mead; give one of them"
        )
    solver = solver or args.solver or ("nelder-mead" if method == "nelder-mead" else None)
    if solver is None and (args.hessian is not None or args.shooting == "multiple"):
        solver = "ipopt"
    solver = solver or DEFAULT_SOLVER
    entry = solver_named(solver)
    _check_solver_options(args, entry, *([solver_named(beside)] if beside else []))
    exact = args.hessian == "exact"
    if exact and not args.quiet:
        print(
            f"cable-ocp {args.command}: note: --hessian exact runs the interpreted model "
            "(compiled = False): the compiled step carries no second derivatives",
            file=sys.stderr,
        )
    own = set(entry.settings.__dataclass_fields__)
    options = {
        "solver": solver,
        "settings": entry.settings(
            **_given(args, own & {"hessian", "max_iter", "max_evaluations"})
        ),
        "model": ModelSettings(**_given(args, ("elements", "step"))),
        "transcription": TranscriptionSettings(
            **_given(args, ("shooting",)), **({"compiled": False} if exact else {})
        ),
    }
    if entry.shootings:  # the paper's Nelder-Mead takes the scene's knots, no grid
        options["grid"] = GridSettings(**_given(args, ("control", "intervals")))
    return options


def _check_solver_options(args, *entries) -> None:
    """Refuse an option given that none of the solvers ``entries`` (of the registry) takes.

    Its settings' fields (``--hessian``, ``--max-iter``, ``--max-evaluations``), its shootings
    (``--shooting``), the shooting grid (``--control``, ``--intervals``; not Nelder-Mead's,
    which takes the scene's knots). An option left unused would run another problem than the
    one asked for (``--solver nelder-mead --hessian exact`` ran the slow interpreted model).
    """
    from cable_ocp.control.solvers import SOLVERS

    def takes(other, name: str) -> bool:
        if name == "shooting":
            return args.shooting in other.shootings
        if name in ("control", "intervals"):
            return bool(other.shootings)
        return name in other.settings.__dataclass_fields__

    names = ("hessian", "max_iter", "max_evaluations", "shooting", "control", "intervals")
    for name in names:
        if getattr(args, name, None) is None or any(takes(entry, name) for entry in entries):
            continue
        option = f"--{name.replace('_', '-')} {getattr(args, name)}"
        others = [other for other in SOLVERS.values() if takes(other, name)]
        raise ValueError(
            f"{option} is an option of {' and '.join(o.label for o in others)}, not of "
            f"{' or '.join(e.label for e in entries)}: give --solver {others[0].name}, or leave "
            f"{option.split()[0]} out"
        )


def _locked_reference(scene):
    """The locked winch's run for comparison, or None and why it failed.

    Only the verified profile must stay sound: a locked run that blows up or leaves the
    bathymetry grid is reported beside the result, never in its place.
    """
    from cable_ocp.simulation.integrate import SimulationError
    from cable_ocp.simulation.run import simulate

    try:
        return simulate(scene, quiet=True), ""
    except SimulationError as error:
        return None, f"the locked reference run failed ({_one_line(error)})"


def _check_step(scene, step: float | None) -> None:
    """Refuse a ``--step`` that does not divide the scene's duration, naming the option."""
    from cable_ocp.simulation.integrate import step_count

    if step is None:
        return
    try:
        step_count(scene.numerics.duration, step)
    except ValueError:
        raise ValueError(
            f"--step {step:g} s must divide the scene's numerics.duration = "
            f"{scene.numerics.duration:g} s into a whole number of RK4 steps"
        ) from None


def _check_start(scene) -> None:
    """Refuse, as ``simulate`` does, an end that starts off the grid or under the seabed.

    Only a bathymetry grid can put the start there; its statics are all it costs, before the
    optimiser's work (``OffGridError``: exit 2, one line).
    """
    if not scene.seabed.absolute:
        return
    from cable_ocp.drive.drive import Drive
    from cable_ocp.model.cable import CableModel
    from cable_ocp.simulation.seabed import check_start
    from cable_ocp.simulation.statics import starting_state

    start = starting_state(CableModel.from_scene(scene), Drive.from_scene(scene))
    check_start(scene.seabed, start[:3])


def _optimize(args) -> int:
    from cable_ocp import plots
    from cable_ocp.control.optimization import optimize

    scene = load_scene(args.scene, parse_overrides(args.set))
    _check_step(scene, args.step)
    _check_start(scene)
    output = {"quiet": args.quiet, "verbose": args.verbose}
    options = _optimize_options(args)
    if options["solver"] != "nelder-mead":
        output["refinements"] = args.refinements
    result = optimize(scene, **options, **output)
    locked, locked_failure = _locked_reference(scene)
    seabed, bounds = scene.seabed, (scene.winch.angle_min, scene.winch.angle_max)
    runs = [("locked winch", locked), (f"optimised ({result.solver})", result.trajectory)]
    runs = [(label, run) for label, run in runs if run is not None]
    summary = {"scene": scene.name, **result.summary(),
               "locked_omega": locked.omega if locked is not None else float("nan")}  # fmt: skip
    summary["units"] = {**summary["units"], "locked_omega": RUN_UNITS["locked_omega"]}
    with results_folder(args.out) as folder:
        result.save(folder)
        (folder / "summary.json").write_text(json_text(summary))
        if result.trajectory is not None:
            (folder / "winch.csv").write_text(winch_csv(result.trajectory, scene))
        if runs:
            labels, pair = [label for label, _ in runs], [run for _, run in runs]
            plots.end_trajectory(pair, labels, path=folder / "end_trajectory.png")
            plots.clearance(pair, seabed.clearance, labels, folder / "clearance.png",
                            seabed.minimum_clearance)  # fmt: skip
            plots.winch_angle(pair, labels, bounds, path=folder / "winch_angle.png")
            plots.cable_shapes(pair[-1], seabed=seabed, path=folder / "cable_shapes.png")
            if args.animate:
                plots.animate(pair[-1], folder / "animation.gif", seabed.clearance)
    n = scene.model.elements
    omega = (
        f"Omega = {result.omega:.3g} m verified on n = {n}"
        if math.isfinite(result.omega)
        else f"Omega not verified on n = {n}"
    )
    locked_omega = "no locked run" if locked is None else f"locked: {locked.omega:.3f} m"
    print(
        f"{result.solver}: success = {result.success} ({result.status}); {omega} "
        f"({locked_omega}); iterations {result.iterations}, evaluations "
        f"{result.evaluations}; optimize() took {result.wall_time:.1f} s (build "
        f"{result.build_time:.1f} s, solver {result.solve_time:.1f} s of which functions "
        f"{result.function_time:.1f} s), the whole command {_elapsed(args):.1f} s (with the "
        "imports, the locked winch's run and the figures)"
    )
    if result.notes:
        print(f"note: {result.notes}")
    if locked_failure:
        print(f"note: {locked_failure}; the comparison with the locked winch is left out")
    print(f"results and figures written to {Path(args.out).resolve()}")
    if not result.success:
        print(f"cable-ocp optimize: the optimiser failed: {result.status}", file=sys.stderr)
        return 3
    return 0


def _compare(args) -> int:
    from dataclasses import replace

    from cable_ocp.control.optimization import optimize

    overrides = parse_overrides(args.set)
    scenes = [load_scene(path, overrides) for path in args.scenes]  # all checked before solving
    for scene in scenes:
        _check_step(scene, args.step)
        _check_start(scene)
    if args.solver == "nelder-mead":
        raise ValueError(
            "--solver nelder-mead: compare runs Nelder-Mead anyway, beside a shooting solver; "
            "give --solver gauss-newton or ipopt"
        )
    shooting = _optimize_options(args, beside="nelder-mead")
    simplex = _optimize_options(args, "nelder-mead", beside=shooting["solver"])
    spline = {**shooting, "grid": replace(shooting["grid"], control="spline")}
    name = shooting["solver"]
    output = {"quiet": args.quiet, "verbose": args.verbose}
    rows = []
    for scene in scenes:
        runs = [
            (f"{name}, hermite", optimize(scene, **shooting, **output)),
            (f"{name}, spline", optimize(scene, **spline, **output)),
            ("nelder-mead, spline", optimize(scene, **simplex, **output)),
        ]
        rows += [(scene.name, label, r) for label, r in runs]
    lines = [
        "| scene | solver | control | Omega verified [m] | success | iterations | evaluations "
        "| wall [s] | build [s] |",
        "|---|---|---|---:|---|---:|---:|---:|---:|",
    ]
    for name, label, r in rows:
        lines.append(
            f"| {name} | {label} | {r.control} | {r.omega:.2e} | {r.success} | {r.iterations} "
            f"| {r.evaluations} | {r.wall_time:.1f} | {r.build_time:.1f} |"
        )
    lines.append(
        f"\nwall: optimize()'s own time (build included); the whole command took "
        f"{_elapsed(args):.1f} s"
    )
    table = "\n".join(lines)
    with results_folder(args.out) as folder:
        (folder / "comparison.md").write_text(table + "\n")
    print(table)
    return 0


def _knots(text: str) -> list[float]:
    """An argparse type: comma-separated finite knot angles, rad."""
    if not text.strip():
        raise argparse.ArgumentTypeError(
            "empty: give the angles phi_1..phi_p in rad, comma-separated, or leave --knots out "
            "for a locked winch"
        )
    values = []
    for k, item in enumerate(text.split(","), start=1):
        try:
            value = float(item)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"knot {k} = {item.strip()!r:.40} is not a number; give the angles phi_1..phi_p "
                "in rad, comma-separated, e.g. 0,0.5,1"
            ) from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"knot {k} = {item.strip()!r}: must be finite")
        values.append(value)
    return values


def _add_optimiser_options(parser) -> None:
    # No defaults here: unset options keep optimize()'s (cable_ocp.control.solvers.SOLVERS).
    parser.add_argument(
        "--elements",
        type=integer(1, 1000),
        help="elements of the optimisation model (default: optimize()'s reduced model; "
        "verification uses the scene's)",
    )
    parser.add_argument(
        "--step", type=positive, help="RK4 step of the optimisation [s] (default: optimize()'s)"
    )
    parser.add_argument(
        "--intervals",
        type=integer(1, 100_000),
        help="shooting intervals (default: optimize()'s, about 5 s each)",
    )
    parser.add_argument(
        "--solver",
        help="a solver of the registry (cable_ocp.control.solvers.SOLVERS): gauss-newton or "
        "ipopt on the shooting NLP, or the paper's nelder-mead (default: gauss-newton; ipopt "
        "when --hessian or --shooting multiple is given)",
    )
    parser.add_argument(
        "--shooting",
        choices=["single", "multiple"],
        help="IPOPT: only the winch parameters as variables (single) or the interval states too",
    )
    parser.add_argument(
        "--control",
        choices=["hermite", "spline"],
        help="the winch's parametrisation for --method shooting: hermite (cubic Hermite intervals, "
        "the default) or spline (the paper's knots, winch.knots)",
    )
    parser.add_argument(
        "--hessian",
        choices=["limited-memory", "exact"],
        help="exact: second derivatives, on the interpreted (not compiled) model",
    )
    parser.add_argument(
        "--max-iter", type=integer(1, 10**6), help="iterations of Gauss-Newton or IPOPT"
    )
    parser.add_argument("--max-evaluations", type=integer(1, 10**8), help="Nelder-Mead runs")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="override a scene field, e.g. --set model.elements=30 (repeatable)",
    )
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument("--quiet", action="store_true", help="print nothing while solving")
    talk.add_argument("--verbose", action="store_true",
                      help="IPOPT's full log instead of one line per iteration")  # fmt: skip


def _validate(args) -> int:
    import numpy as np

    from cable_ocp import plots
    from cable_ocp.studies.catenary import catenary_shape
    from cable_ocp.studies.validation import catenary_check

    scene = load_scene(args.scene or models_dir() / "catenary.toml")
    print("catenary (paper 4.1): largest relative errors against the analytic catenary, in %")
    print(f"{'n':>5}{'eps_x [%]':>12}{'eps_z [%]':>12}{'inextensible [%]':>18}"
          f"{'top tension [%]':>17}")  # fmt: skip
    checks = [catenary_check(scene, n) for n in args.elements]
    for c in sorted(checks, key=lambda check: check.elements):
        print(
            f"{c.elements:>5}{100 * c.max_error_x:>12.4f}{100 * c.max_error_z:>12.4f}"
            f"{100 * c.max_error_inextensible:>18.5f}{100 * c.top_tension_error:>17.2e}"
        )
    if args.out:
        check = checks[0]
        s = np.linspace(0, scene.cable.length, 300)
        c, e = scene.cable, scene.end
        x, z, _ = catenary_shape(s, c.length, c.mass_per_length * scene.environment.gravity,
                                 float(np.hypot(*e.force[:2])), e.force[2],
                                 c.youngs_modulus * c.cross_section_area)  # fmt: skip
        with results_folder(args.out) as folder:
            plots.catenary_comparison(check.joints, np.vstack([x, z]), folder / "catenary.png",
                                      scene.name, check.elements)  # fmt: skip
        print(f"figure written to {Path(args.out).resolve() / 'catenary.png'}")
    return 0


def _bench(args) -> int:
    from cable_ocp.studies import (
        bench,
        bench_elastic,
        bench_lowering,
        bench_payout,
        bench_simulate,
        robustness,
    )
    from cable_ocp.studies.moordyn_compare import moordyn_report

    if args.hessian:
        bench.hessian_report(models_dir())
        return 0
    parts = {
        "rk4": bench.rk4_report,
        "simulate": bench_simulate.report,
        "moordyn": moordyn_report,
        "payout": bench_payout.report,
        "elastic": bench_elastic.report,
        "ocp": bench.ocp_report,
        "ocp-speed": bench.ocp_speed_report,
        "mpc": lambda models, quick: _bench_mpc(models, quick, args.out),
        "robustness": lambda _, quick: robustness.report(
            args.cases or (6 if quick else 50), args.seed
        ),
        "lowering": lambda _, quick: bench_lowering.report(
            args.cases or (3 if quick else 10), args.seed
        ),
    }
    named_only = ("robustness", "lowering")
    for name in args.only or [part for part in parts if part not in named_only]:
        parts[name](models_dir(), quick=args.quick)
        print()
    return 0


def _bench_mpc(models: Path, quick: bool = False, out: Path | None = None) -> None:
    """The closed loop's benchmark; its figure of solve times saved in ``out`` when given."""
    from cable_ocp.plots.closed_loop import solve_time_comparison
    from cable_ocp.studies import bench_mpc

    results = bench_mpc.report(models, quick=quick)
    if out is None:
        print("figure of the solve times not written (give --out DIR)")
        return
    with results_folder(out) as folder:
        path = folder / "mpc_solve_times.png"
        solve_time_comparison(results, path=path, scene_name="paper_hill")  # bench_mpc's scene
    print(f"figure written to {(Path(out) / path.name).resolve()}")


def _study(args) -> int:
    from cable_ocp.studies import convergence as studies

    if args.name == "payout":
        return _payout_study(args)
    if args.name in ("speed-accuracy", "stability"):
        if args.scene is not None:
            raise ValueError(f"study {args.name} takes no scene: it runs its own (see --help)")
        if args.name == "speed-accuracy":
            from cable_ocp.studies.speed_accuracy import run_speed_accuracy as run
        else:
            from cable_ocp.studies.stability import run_stability as run
        run(args.out, models_dir(), quick=args.quick, quiet=args.quiet)
        print(f"written to {Path(args.out).resolve()}")
        return 0
    if args.scene is None:
        raise ValueError(f"study {args.name} needs a scene file, e.g. models/paper_flat.toml")
    scene = load_scene(args.scene, parse_overrides(args.set))
    with results_folder(args.out) as folder:
        if args.name == "step":
            result = studies.step_halving(scene, quiet=args.quiet)
        elif args.name == "elements":
            result = studies.element_convergence(scene, quiet=args.quiet)
            result.chart(folder / "element_convergence.png")
        else:
            result = studies.end_positions(
                scene, studies.END_FORCE_SETTINGS, quiet=args.quiet, compiled=args.compiled
            )
        text = result.table()
        (folder / f"{args.name}.md").write_text(f"# {args.name} study of {scene.name}\n\n{text}\n")
    print(text)
    print(f"written to {Path(args.out).resolve()}")
    return 0


def _payout_study(args) -> int:
    """Acceptance 4 of the line on the drum: the top tension at the splits, figure and table."""
    from cable_ocp.studies import payout_validation as pv

    if args.scene is not None:
        raise ValueError("study payout takes no scene: it runs paper_flat's rope (see --help)")
    runs, finest = pv.insertion_runs(
        pv.TRANSIENT_LENGTHS[:1] if args.quick else pv.TRANSIENT_LENGTHS
    )
    rows = ["| Delta [m] | new top [m] | splits | largest jump | against the finest |",
            "|---:|---:|---:|---:|---:|"]  # fmt: skip
    for delta, run in runs.items():
        t = pv.transient(run, finest)
        rows.append(
            f"| {delta:g} | {t.new_top_length:.3g} | {t.changes} | {100 * t.jump:.3f} % "
            f"| {100 * t.against_finest:.3f} % |"
        )
    text = "\n".join(rows)
    with results_folder(args.out) as folder:
        pv.transient_chart(runs, finest, folder / "payout_transients.png")
        (folder / "payout.md").write_text(
            "# Top tension at the splits: pay-out 100 -> 200 m at 0.5 m/s under the tow\n\n"
            f"Jumps relative to the static top tension; reference Delta = "
            f"{pv.FINEST_TRANSIENT} m.\n\n{text}\n"
        )
    print(text)
    print(f"written to {Path(args.out).resolve()}")
    return 0


ANIMATE_HELP = "also write animation.gif: the cable, the end's path and the seabed over time"
INTERPRETED_HELP = "the interpreted model (default: compiled to C, the library cached on disk)"


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``cable-ocp``."""
    # The module docstring is reStructuredText; the terminal gets it without the markup.
    parser = argparse.ArgumentParser(
        prog="cable-ocp",
        description=__doc__.replace("``", ""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    commands = parser.add_subparsers(dest="command", required=True)
    shown = {"formatter_class": DefaultsShown}  # every option's default in its help

    sim = commands.add_parser(
        "simulate", **shown, help="simulate a scene and write results and figures"
    )
    sim.add_argument("scene", type=scene_argument, help=SCENE_HELP)
    sim.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    sim.add_argument("--knots", type=_knots,
                     help="winch knot angles phi_1..phi_p in rad, comma-separated, p = "
                     "winch.knots (write --knots=-1,0.5 when the first is negative): phi(0) = 0 "
                     "is put before them, knot i sits at t = i T / p (T = numerics.duration), and "
                     "the cubic spline through them starts at rest (zero rate; free at the end); "
                     "phi > 0 pays out; default: the winch locked")  # fmt: skip
    sim.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="override a scene field, e.g. --set model.elements=30")  # fmt: skip
    sim.add_argument("--quiet", action="store_true", help="no progress bar")
    sim.add_argument("--interpreted", action="store_true", help=INTERPRETED_HELP)
    sim.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    sim.set_defaults(run=_simulate)

    rep = commands.add_parser(
        "replay", **shown,
        help="drive a scene by a saved optimum (on its own scene, or changed by --set)",
    )  # fmt: skip
    rep.add_argument("result", type=Path,
                     help="a folder that optimize wrote (or its result.nc)")  # fmt: skip
    rep.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    rep.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                     help="change the saved scene, e.g. --set model.elements=60")  # fmt: skip
    rep.add_argument("--quiet", action="store_true", help="no progress bar")
    rep.add_argument("--interpreted", action="store_true", help=INTERPRETED_HELP)
    rep.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    rep.set_defaults(run=_replay)

    val = commands.add_parser(
        "validate", **shown, help="statics check against the analytic catenary"
    )
    val.add_argument("scene", type=scene_argument, nargs="?",
                     help=SCENE_HELP + "; default: catenary")  # fmt: skip
    val.add_argument("--elements", type=integer(1, 1000), nargs="+", default=[15, 5, 30, 60],
                     help="element counts n to check, listed in ascending order; the figure "
                     "shows the first given")  # fmt: skip
    val.add_argument("--out", type=Path, help="folder for the comparison figure; " + OUT_HELP)
    val.set_defaults(run=_validate)

    opt = commands.add_parser("optimize", **shown, help="optimise the winch angle of a scene")
    opt.add_argument("scene", type=scene_argument, help=SCENE_HELP)
    opt.add_argument("--method", choices=["shooting", "nelder-mead", "ipopt"], default="shooting",
                     help="shooting: direct shooting on the winch parameters, solved by --solver "
                     "(Gauss-Newton SQP or IPOPT), refined by model correction (ipopt: its old "
                     "name); nelder-mead: the paper's simplex on winch.knots (as --solver "
                     "nelder-mead)")  # fmt: skip
    opt.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    opt.add_argument("--refinements", type=integer(0, 100), default=3,
                     help="model-correction solves")  # fmt: skip
    _add_optimiser_options(opt)
    opt.add_argument("--animate", action="store_true", help=ANIMATE_HELP)
    opt.set_defaults(run=_optimize)

    cmp = commands.add_parser(
        "compare", **shown, help="a shooting solver against Nelder-Mead in one table"
    )
    cmp.add_argument("scenes", type=scene_argument, nargs="+",
                     help="scene files (TOML) or bundled scenes' names")  # fmt: skip
    cmp.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    _add_optimiser_options(cmp)
    cmp.set_defaults(run=_compare)
    add_mpc_command(commands)
    add_lower_command(commands)
    add_sweep_command(commands)
    add_reference_commands(commands)

    study = commands.add_parser(
        "study",
        **shown,
        help="convergence, validation, speed-accuracy and stability studies",
        description="step, elements, end-force: studies of SCENE. speed-accuracy: error vs CPU "
        "time on paper_flat and end_force, and the OCP's Omega vs wall time. stability: largest "
        "stable step vs n, Baumgarte gains, Nelder-Mead vs IPOPT as the knots grow. payout: the "
        "top tension where a line paid out by elements splits one off, against element length.",
    )
    study.add_argument(
        "name",
        choices=["step", "elements", "end-force", "speed-accuracy", "stability", "payout"],
        help="the study (see above)",
    )
    study.add_argument("scene", type=scene_argument, nargs="?",
                       help="the scene of step, elements and end-force: a TOML file or a "
                       "bundled scene's name")  # fmt: skip
    study.add_argument("--out", type=Path, required=True, help=OUT_HELP)
    study.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                       help="override a field of SCENE, e.g. --set numerics.step=0.02")  # fmt: skip
    study.add_argument("--quiet", action="store_true", help="no progress bars")
    study.add_argument("--compiled", action="store_true", help="end-force: model compiled to C")
    study.add_argument(
        "--quick", action="store_true", help="speed-accuracy, stability, payout: a small version"
    )
    study.set_defaults(run=_study)

    bench = commands.add_parser(
        "bench",
        **shown,
        help="speed benchmarks against baselines (long: see bench --help)",
        description="Speed of the toolkit against its baselines, each part comparing within "
        "one run: rk4 (the simulation loop, interpreted against compiled), simulate (the "
        "command end to end), moordyn (MoorDyn at the same accuracy), payout (a line paid out "
        "by elements against fixed n), elastic (the elastic rope beside the rigid one and "
        "MoorDyn on a 2000 m deep lift, about a minute), ocp (IPOPT against Nelder-Mead), ocp-"
        "speed (the default optimize, cold and warm), mpc (the closed loop's solve times). The "
        "default parts run for tens of minutes on 2 cores (MoorDyn and the optimisers "
        "dominate); --quick runs short versions; --only picks parts. robustness (random scenes)"
        " and lowering (random landings: 10 cases took 5 min on 2 cores) run only when named. "
        "Nothing is written without --out.",
    )
    bench.add_argument(
        "--quick", action="store_true", help="scene steps only, short MoorDyn runs, small OCP"
    )
    bench.add_argument(
        "--only",
        nargs="+",
        choices=["rk4", "simulate", "moordyn", "payout", "elastic", "ocp", "ocp-speed", "mpc",
                 "robustness", "lowering"],
        help="run only these parts (robustness and lowering run only when named)",
    )  # fmt: skip
    bench.add_argument(
        "--cases",
        type=integer(1, 10_000),
        default=None,
        help="robustness, lowering: random scenes to draw (default 50 and 10; 6 and 3 with "
        "--quick)",
    )
    bench.add_argument(
        "--seed", type=int, default=0,
        help="robustness, lowering: seed of the random scenes (default 0)",
    )  # fmt: skip
    bench.add_argument(
        "--hessian", action="store_true", help="IPOPT exact vs limited-memory Hessian instead"
    )
    bench.add_argument(
        "--out", type=Path, default=None,
        help="folder for the benchmarks' figures (none are written without it)",
    )  # fmt: skip
    bench.set_defaults(run=_bench)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``cable-ocp``; returns the exit code (see the module docstring)."""
    started = time.perf_counter()
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exit_:  # argparse: --help (0) or a usage error (2), already printed
        return exit_.code if isinstance(exit_.code, int) else 0
    prefix = f"cable-ocp {args.command}"
    args.started = started
    try:
        # Before any work, so a bad or busy --out costs nothing, and held to the last write; a
        # sweep folder is resumed, and cable_ocp.sweep checks and locks it as its own.
        out = getattr(args, "out", None) if args.command != "sweep" else None
        if out is not None:
            check_replaceable(out)
        with claimed_target(out):
            return args.run(args)
    except KeyboardInterrupt:
        print(f"{prefix}: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OverflowError, RuntimeError) as error:  # SceneError, UnicodeDecodeError
        print(f"{prefix}: error: {_one_line(error)}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # the output's reader closed it (| head): stop without a word
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 141
    except OSError as error:
        print(f"{prefix}: error: {_one_line(error)}", file=sys.stderr)
        return 1


def _elapsed(args) -> float:
    """Seconds since :func:`main` started the command, s."""
    return time.perf_counter() - args.started


def _one_line(error: BaseException) -> str:
    return " ".join(str(error).split()) or type(error).__name__
