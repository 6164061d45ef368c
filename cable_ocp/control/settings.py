"""The open loop's settings: what is optimised, how it is transcribed, and by which solver.

Three separate choices, each a frozen dataclass checked once by its declared rules
(:mod:`cable_ocp.control.checks`):

- :class:`ModelSettings`: the optimisation model, a reduction of the scene's (elements, RK4
  step); the closed loop's controller model is one too (``MpcSettings.model``);
- :class:`GridSettings`: the control grid of the open loop (the winch parametrisation and its
  intervals);
- :class:`TranscriptionSettings`: how the problem becomes an NLP (single or multiple shooting,
  compiled or interpreted).

The solver's own settings are its module's (``GaussNewtonSettings``, ``IpoptSettings``,
``NelderMeadSettings``, :mod:`cable_ocp.control.solvers`). :class:`OcpSettings` holds all four
for one ``optimize`` and checks what they must agree on. Every field left None is derived from
the scene (:mod:`cable_ocp.control.defaults`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np

from cable_ocp.control.checks import Rule, check_fields
from cable_ocp.control.hermite_nodes import check_nodes


@dataclass(frozen=True)
class ModelSettings:
    """The reduced model an optimiser or controller steers (Omega is verified on the scene's).

    Attributes
    ----------
    elements : int or None
        Elements of the model (None: derived from the scene; in the open loop
        :func:`cable_ocp.control.defaults.reduced_elements`, in the closed loop 2). The scene's
        ``model.elements`` asks for its own model.
    step : float or None, s
        Its RK4 step (None: derived from the model's RK4 limit along its locked run,
        :mod:`cable_ocp.control.defaults`). A step above that limit is refused.
    """

    elements: int | None = None
    step: float | None = None

    def __post_init__(self):
        check_fields(
            self,
            {
                "elements": Rule("integer", low=1, optional=True),
                "step": Rule("number", above=0, unit="s", optional=True),
            },
        )


@dataclass(frozen=True)
class GridSettings:
    """The winch parametrisation of the open loop.

    Attributes
    ----------
    control : str or None
        ``"hermite"`` (piecewise cubic per control interval) or ``"spline"`` (the paper's knots,
        ``winch.knots`` of the scene). None: Hermite for the shooting solvers, the spline for
        Nelder-Mead (which takes the spline only).
    intervals : int or None
        Shooting intervals (None: about one per 5 s of the duration,
        :func:`cable_ocp.control.defaults.control_intervals`); the number of RK4 steps must be a
        multiple of it (a derived step is chosen so; with a fixed step, derived intervals are the
        nearest count that divides its steps). With single shooting they only cut the chain of
        RK4 steps (and set the Hermite control's intervals). Not for Nelder-Mead.
    control_intervals : int or None
        Intervals of the Hermite control (None: as many as shooting intervals).
    nodes : tuple of float or None, s
        The Hermite control's node times, from 0 to ``numerics.duration``, strictly increasing
        and each on an RK4 step end of the optimisation model and of the full model's runs
        (:mod:`cable_ocp.control.hermite_nodes`); None: equal intervals. Not with
        ``control_intervals``.
    adaptive : bool
        Choose the nodes among candidates by coarsening (:mod:`cable_ocp.control.adaptive_grid`):
        after the first solve on the default grid, before any full-model run, remove the
        candidates whose removal keeps the model's predicted Omega within ``adaptive_tolerance``
        of the default grid's predicted optimum, and run the model correction on the nodes left.
        Off by default: it does not yet measure better in wall time (CONVENTIONS.md section 5).
        Hermite control and the shooting solvers only.
    adaptive_tolerance : float
        The coarsening's relative tolerance on Omega (CONVENTIONS.md §5).
    adaptive_finest : int
        The candidates are the nodes of a grid this many times finer than the default one (its
        intervals about 5 s / ``adaptive_finest``; the shooting intervals when ``intervals`` is
        unset). 2 by default: among the default grid's own nodes (1) no choice reached the
        default grid's Omega on paper_hill with fewer parameters (CONVENTIONS.md §5).
    """

    control: str | None = None
    intervals: int | None = None
    control_intervals: int | None = None
    nodes: tuple[float, ...] | None = None
    adaptive: bool = False
    adaptive_tolerance: float = 0.02
    adaptive_finest: int = 2

    def __post_init__(self):
        check_fields(
            self,
            {
                "control": Rule("choice", choices=("hermite", "spline"), optional=True),
                "intervals": Rule("integer", low=1, optional=True),
                "control_intervals": Rule("integer", low=1, optional=True),
                "adaptive": Rule("flag"),
                "adaptive_tolerance": Rule("number", above=0, high=1),
                "adaptive_finest": Rule("integer", low=1, high=8),
            },
        )
        if self.nodes is not None:
            times = check_nodes(self.nodes, float(np.ravel(self.nodes)[-1]))
            object.__setattr__(self, "nodes", tuple(float(t) for t in times))
        misfits = {
            "nodes with control_intervals": self.nodes and self.control_intervals,
            "adaptive with nodes": self.adaptive and self.nodes,
            "adaptive with control_intervals": self.adaptive and self.control_intervals,
            "nodes or adaptive with the spline": (self.nodes or self.adaptive)
            and self.control == "spline",
        }
        for what, misfit in misfits.items():
            if misfit:
                raise ValueError(
                    f"GridSettings: {what} do not go together (the nodes are the Hermite "
                    "control's, given or chosen adaptively): leave one out"
                )


@dataclass(frozen=True)
class TranscriptionSettings:
    """How the winch problem becomes an NLP.

    Attributes
    ----------
    shooting : str
        ``"single"`` (only the winch parameters are variables) or ``"multiple"`` (the states at
        the interval ends too, joined by continuity constraints; IPOPT only).
    threads : int
        Shooting intervals evaluated in parallel (multiple shooting only).
    compiled : bool
        Compile the model's right-hand side and its first derivatives to C (cached on disk,
        one library per model structure), and verify on the compiled full model.
    """

    shooting: str = "single"
    threads: int = 1
    compiled: bool = True

    def __post_init__(self):
        check_fields(
            self,
            {
                "shooting": Rule("choice", choices=("single", "multiple")),
                "threads": Rule("integer", low=1),
                "compiled": Rule("flag"),
            },
        )


@dataclass(frozen=True)
class OcpSettings:
    """Everything one ``optimize`` runs with: the problem, its transcription and its solver.

    Attributes
    ----------
    solver : str
        The solver's name in :data:`cable_ocp.control.solvers.SOLVERS`.
    solver_settings : GaussNewtonSettings, IpoptSettings or NelderMeadSettings
        That solver's own settings (its class is the registry's).
    model : ModelSettings
        The optimisation model (elements, RK4 step; unset ones derived from the scene).
    grid : GridSettings
        The winch parametrisation and its intervals (its control set to the solver's default
        by :func:`~cable_ocp.control.solvers.ocp_settings`).
    transcription : TranscriptionSettings
        Single or multiple shooting, compiled or interpreted.
    """

    solver: str
    solver_settings: object
    model: ModelSettings = field(default_factory=ModelSettings)
    grid: GridSettings = field(default_factory=GridSettings)
    transcription: TranscriptionSettings = field(default_factory=TranscriptionSettings)

    @property
    def control(self) -> str | None:
        """The winch parametrisation (``grid.control``).

        :func:`~cable_ocp.control.solvers.ocp_settings` sets it to the solver's default
        control (the registry's) when the grid leaves it unset.
        """
        return self.grid.control

    @property
    def elements(self) -> int | None:
        """The model's elements (``model.elements``)."""
        return self.model.elements

    @property
    def step(self) -> float | None:
        """The model's RK4 step, s (``model.step``)."""
        return self.model.step

    @property
    def intervals(self) -> int | None:
        """The shooting intervals (``grid.intervals``)."""
        return self.grid.intervals

    @property
    def control_intervals(self) -> int | None:
        """The Hermite control's intervals (the shooting intervals unless set apart)."""
        return self.grid.control_intervals or self.grid.intervals

    @property
    def compiled(self) -> bool:
        """Whether the models run compiled (``transcription.compiled``)."""
        return self.transcription.compiled

    def record(self) -> dict:
        """The settings as a result stores them: one table per object, the solver named."""
        return {
            "solver": self.solver,
            "model": asdict(self.model),
            "grid": asdict(self.grid),
            "transcription": asdict(self.transcription),
            "solver_settings": asdict(self.solver_settings),
        }
