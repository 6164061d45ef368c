"""The optimiser's options of ``optimize`` and ``compare``, and their checks before any work."""

from __future__ import annotations

import argparse
import sys
import time

from cable_ocp.cli.arguments import add_set, integer, positive


def _given(args, names: tuple[str, ...]) -> dict:
    """The options among ``names`` given on the command line (the others are None)."""
    return {name: getattr(args, name) for name in names if getattr(args, name) is not None}


def optimize_options(args, solver: str | None = None, beside: str | None = None) -> dict:
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


def check_step(scene, step: float | None) -> None:
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


def check_start(scene) -> None:
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


def add_optimiser_options(parser: argparse.ArgumentParser) -> None:
    """Add the optimiser's options (each unset by default: ``optimize()``'s own) to a command."""
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
    add_set(parser, "model.elements=30")
    talk = parser.add_mutually_exclusive_group()
    talk.add_argument("--quiet", action="store_true", help="print nothing while solving")
    talk.add_argument("--verbose", action="store_true",
                      help="IPOPT's full log instead of one line per iteration")  # fmt: skip


def elapsed(args: argparse.Namespace) -> float:
    """Seconds since :func:`cable_ocp.cli.main` started the command, s."""
    return time.perf_counter() - args.started
