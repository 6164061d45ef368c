"""The optimiser's options of ``optimize`` and ``compare``, and their checks before any work."""

from __future__ import annotations

import argparse
import sys
import time

from cable_ocp.cli.arguments import add_model_options, add_set, integer
from cable_ocp.control.settings import GridSettings, ModelSettings, OcpSettings
from cable_ocp.control.solvers import DEFAULT_SOLVER, SOLVERS, Solver, ocp_settings_from

# The optimiser's options, each named as the settings field it sets (OcpSettings' parts), and
# optimize()'s keyword of the model correction (optimize's option only).
OPTIONS = ("elements", "step", "control", "intervals", "adaptive", "shooting", "hessian",
           "max_iter", "max_evaluations")  # fmt: skip
CORRECTION = "refinements"


def _takes(entry: Solver, args: argparse.Namespace, name: str) -> bool:
    """Whether the registry's solver ``entry`` takes the option ``name`` as given in ``args``.

    The model's (``--elements``, ``--step``) every solver; the shooting grid's (``--control``,
    ``--intervals``, ``--adaptive``) a shooting solver (not the paper's Nelder-Mead, on the
    scene's knots); a shooting its own; ``--refinements`` a solver whose transcription
    corrects its model; else a field of its settings (``--hessian``, ``--max-iter``, ...).
    """
    if name in ModelSettings.__dataclass_fields__:
        return True
    if name == CORRECTION:
        return entry.transcription.model_correction
    if name == "shooting":
        return args.shooting in entry.shootings
    if name in GridSettings.__dataclass_fields__:
        return bool(entry.shootings)
    return name in entry.settings.__dataclass_fields__


def _given(args: argparse.Namespace) -> list[str]:
    """The optimiser's options given on the command line (the others are None)."""
    return [name for name in (*OPTIONS, CORRECTION) if getattr(args, name, None) is not None]


def _solver(args: argparse.Namespace) -> Solver:
    """``--solver``'s entry, or the one the options given ask for.

    Unset, the default, unless it does not take an option given: then the first solver of the
    same problem that takes them all (``--hessian`` or ``--shooting multiple``: IPOPT), never
    one of another problem (the paper's Nelder-Mead on the knots: name it).
    """
    if args.solver is not None:
        return SOLVERS[args.solver]
    default = SOLVERS[DEFAULT_SOLVER]
    same_problem = [e for e in SOLVERS.values() if e.transcription is default.transcription]
    return next(
        (entry for entry in [default, *same_problem]
         if all(_takes(entry, args, name) for name in _given(args))),
        default,
    )  # fmt: skip


def optimize_settings(
    args: argparse.Namespace, solver: str | None = None, beside: str | None = None
) -> OcpSettings:
    """``optimize``'s settings from the options given, built by the settings classes.

    The solver is ``solver``, else ``--solver``, else the default unless an option given asks
    for another solver of the same problem (:func:`_solver`). Unset options keep the settings'
    defaults (derived from the scene). ``--hessian exact`` needs the interpreted model. An option
    that neither the solver nor the solver run ``beside`` it on the same options (compare's)
    takes is refused; one that only the other takes is left to it.
    """
    entry = SOLVERS[solver] if solver is not None else _solver(args)
    _check_solver_options(args, entry, *([SOLVERS[beside]] if beside else []))
    table = {name: getattr(args, name) for name in _given(args)
             if name != CORRECTION and _takes(entry, args, name)}  # fmt: skip
    if table.get("hessian") == "exact":
        table["compiled"] = False
        if not args.quiet:
            print(
                f"cable-ocp {args.command}: note: --hessian exact runs the interpreted model "
                "(compiled = False): the compiled step carries no second derivatives",
                file=sys.stderr,
            )
    return ocp_settings_from(table, entry.name)


def _check_solver_options(args: argparse.Namespace, *entries: Solver) -> None:
    """Refuse an option given that none of the solvers ``entries`` (of the registry) takes.

    An option left unused would run another problem than the one asked for (``--solver
    nelder-mead --hessian exact`` ran the slow interpreted model).
    """
    for name in _given(args):
        if any(_takes(entry, args, name) for entry in entries):
            continue
        option = f"--{name.replace('_', '-')} {getattr(args, name)}"
        others = [other for other in SOLVERS.values() if _takes(other, args, name)]
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


def add_optimiser_options(parser: argparse.ArgumentParser) -> None:
    """Add the optimiser's options (each unset by default: ``optimize()``'s own) to a command."""
    # No defaults here: unset options keep optimize()'s (cable_ocp.control.solvers.SOLVERS).
    add_model_options(
        parser,
        elements="elements of the optimisation model (default: optimize()'s reduced model; "
        "verification uses the scene's)",
        step="RK4 step of the optimisation [s] (default: optimize()'s)",
    )
    parser.add_argument(
        "--intervals",
        type=integer(1, 100_000),
        help="shooting intervals (default: optimize()'s, about 5 s each)",
    )
    parser.add_argument(
        "--adaptive",
        action="store_const",
        const=True,
        help="an adaptive control grid: Hermite nodes chosen among candidates twice as fine as "
        "the default grid's by coarsening after its first solve (GridSettings(adaptive=True))",
    )
    parser.add_argument(
        "--solver",
        choices=list(SOLVERS),
        help=f"a solver of the registry (cable_ocp.control.solvers.SOLVERS): gauss-newton or "
        f"ipopt on the shooting NLP, or the paper's nelder-mead on the scene's knots (default: "
        f"{DEFAULT_SOLVER}; ipopt when --hessian or --shooting multiple is given)",
    )
    parser.add_argument(
        "--shooting",
        choices=["single", "multiple"],
        help="IPOPT: only the winch parameters as variables (single) or the interval states too",
    )
    parser.add_argument(
        "--control",
        choices=["hermite", "spline"],
        help="the winch's parametrisation of a shooting solver: hermite (cubic Hermite "
        "intervals, the default) or spline (the paper's knots, winch.knots)",
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
