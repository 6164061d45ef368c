"""Models of every ``n`` of one line, all stepped by one compiled library of element kernels.

A paid-out line changes its number of elements (:mod:`cable_ocp.scene.line_mesh`). A library per
``n`` (:func:`cable_ocp.model.structured.compiled_library`) would compile 2 to 3.5 s for each of
the 200 counts between 20 m and 2000 m of line at 10 m elements. The structured loops call the
same small Functions at any ``n`` (the element terms, the bending joint, the bond blocks, one step
of each Thomas sweep): :func:`compiled_kernels` compiles those once per structure (``n`` aside),
and :class:`LineModels` builds for each ``n`` the loops around them (an MX graph, evaluated by
CasADi's virtual machine, built in milliseconds), installed as that model's library so that
integration, statics and outputs run on it unchanged.

The kernels take the parameters ``p`` of their own structure, whose segment length is
``(L - l_top) / (n_k - 1/2)`` at the kernels' ``n_k``: the loops of ``n`` hand them ``p`` with
``L`` set so that this is the ``Delta`` of ``n`` (:func:`kernel_parameters`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import lru_cache, partial

import casadi as ca

from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel, ModelSpec
from cable_ocp.model.compile import CompileReport, Library, compiled_from
from cable_ocp.model.joints import Kernels
from cable_ocp.model.parameters import parameter_names, structure_of
from cable_ocp.model.parametric import ParametricModel

KERNEL_ELEMENTS = 2  # n of the structure the kernels are built on
KERNEL_NAMES = (
    "joint", "element", "element_end", "bond", "top_bond", "forward", "backward", "acc",
    "inverse",
)  # fmt: skip
KERNEL_FIELDS = (
    "joint", "element", "element_end", "bond", "top_bond", "forward", "backward",
    "accelerations", "inverse",
)  # fmt: skip


# Columns per call of the compiled loops: n columns are covered greedily by these (100 = 64 +
# 2 x 16 + 4), so a loop over n costs a few calls from CasADi's virtual machine, not n.
BLOCKS = (64, 16, 4, 1)
LINE_MODELS_KEPT = 4  # lines whose models a process keeps (line_models)
MAPPED = ("joint", "element", "bond", "accelerations")
ACCUMULATED = ("forward", "backward")


@dataclass(frozen=True)
class BlockedKernels:
    """Kernels whose loops over n columns call compiled loops over :data:`BLOCKS` columns.

    ``kernels`` are a structure's own (:class:`~cable_ocp.model.joints.Kernels`, or an
    elastic rope's :class:`~cable_ocp.model.axial_structured.ElasticKernels`), whose Functions
    and parameters this answers for; ``blocks[name][size]`` is kernel ``name`` mapped (or
    accumulated) over ``size`` columns.
    """

    kernels: Kernels
    blocks: dict = field(default_factory=dict)

    def __getattr__(self, name: str):
        return getattr(self.kernels, name)

    def map(self, name: str, count: int) -> Callable:
        """Kernel ``name`` over ``count`` columns, in blocks (see the class)."""
        return partial(_blocked, self.blocks[name], getattr(self.kernels, name), count, False)

    def mapaccum(self, name: str, count: int) -> Callable:
        """Kernel ``name`` accumulated over ``count`` columns, in blocks."""
        return partial(_blocked, self.blocks[name], getattr(self.kernels, name), count, True)


def _cover(count: int) -> list[int]:
    """Block sizes of :data:`BLOCKS` that add up to ``count``, largest first."""
    sizes = []
    for size in BLOCKS:
        sizes += [size] * ((count - sum(sizes)) // size)
    return sizes


def _blocked(blocks: dict, single: ca.Function, count: int, accumulate: bool, *args):
    """The outputs of ``single`` over ``count`` columns of ``args``, by calls of ``blocks``.

    An argument as wide as one call's input is shared by every column (as ``map`` broadcasts
    it); an accumulated loop's first argument is the accumulator, its first output the states.
    """
    widths = [single.size2_in(k) for k in range(single.n_in())]
    shared = [a.size2() == w and count > 1 for a, w in zip(args, widths, strict=True)]
    outputs: list[list] = [[] for _ in range(single.n_out())]
    start, state = 0, args[0] if accumulate else None
    for size in _cover(count):
        piece = []
        for k, (a, w) in enumerate(zip(args, widths, strict=True)):
            if accumulate and k == 0:
                piece.append(state)
            else:
                piece.append(a if shared[k] else a[:, start * w : (start + size) * w])
        results = blocks[size](*piece)
        results = results if isinstance(results, tuple | list) else [results]
        for k, r in enumerate(results):
            outputs[k].append(r)
        if accumulate:
            width = single.size2_out(0)
            state = results[0][:, (size - 1) * width :]
        start += size
    joined = [ca.horzcat(*pieces) for pieces in outputs]
    return joined[0] if len(joined) == 1 else tuple(joined)


def _loop(single: ca.Function, name: str, size: int) -> ca.Function:
    """``single`` mapped (or accumulated) over ``size`` columns, named ``name_size``."""
    if name in ACCUMULATED:
        return single.mapaccum(f"{name}_{size}", size)
    return single.map(f"{name}_{size}", "serial", size, [], [])


def line_spec(template: ModelSpec, elements: int, element_length: float) -> ModelSpec:
    """The spec of ``n = elements`` below-top elements of ``element_length`` (m) each.

    The top element's length is an input; ``top_length`` here only fixes ``Delta``
    (``cable_length = top_length + (n - 1/2) Delta``).
    """
    top = element_length
    return replace(
        template,
        elements=elements,
        top_length=top,
        cable_length=top + (elements - 0.5) * element_length,
    )


def compiled_kernels(
    template: ModelSpec, compiled: bool
) -> tuple[BlockedKernels, CompileReport | None]:
    """The structured kernels of ``template``'s structure at ``n = 2``, compiled to C or not.

    Returns the kernels and a :class:`~cable_ocp.model.compile.CompileReport` (None when not
    compiled).
    """
    reference = ParametricModel(structure_of(replace(template, elements=KERNEL_ELEMENTS)))
    kernels = structured.kernels_of(reference)
    loops = {}
    for name in (*MAPPED, *ACCUMULATED):
        single = getattr(kernels, name)
        loops[name] = {size: single if size == 1 else _loop(single, name, size) for size in BLOCKS}
    names = [f"{name}_{size}" for name in loops for size in BLOCKS if size > 1]
    functions = [loops[name][size] for name in loops for size in BLOCKS if size > 1]
    if compiled:
        library = Library(
            lambda: [getattr(kernels, name) for name in KERNEL_FIELDS] + functions,
            list(KERNEL_NAMES) + names,
            f"{reference.structure!r}|structured kernels for every n, blocks {BLOCKS}",
            False,
        )
        compiled_functions, report = compiled_from(library)
        singles = dict(zip(KERNEL_FIELDS, compiled_functions, strict=False))
        kernels = replace(kernels, **singles)
        built = iter(compiled_functions[len(KERNEL_FIELDS) :])
        for name in loops:
            for size in BLOCKS:
                loops[name][size] = getattr(kernels, name) if size == 1 else next(built)
    else:
        report = None
    return BlockedKernels(kernels, blocks=loops), report


def kernel_parameters(names: list[str], elements: int):
    """``p -> p`` of the kernels for the loops of ``n = elements``, and ``p -> Delta`` (m).

    The kernels' segment length is ``(L - l_top) / (n_k - 1/2)``; the loops of ``n`` give them
    ``L = l_top + Delta (n_k - 1/2)``, ``Delta = (L - l_top) / (n - 1/2)`` of their own ``p``.
    """
    length, top = names.index("cable_length"), names.index("top_length")

    def delta(p: ca.MX) -> ca.MX:
        return (p[length] - p[top]) / (elements - 0.5)

    def parameters(p: ca.MX) -> ca.MX:
        kernel_length = p[top] + delta(p) * (KERNEL_ELEMENTS - 0.5)
        return ca.vertcat(p[:length], kernel_length, p[length + 1 :])

    return parameters, delta


class LineModels:
    """The models of a line at every ``n``, built on first use and kept.

    Parameters
    ----------
    template : ModelSpec
        The scene's model (its rope, water, payload, gains); its ``n`` and lengths are replaced.
    element_length : float, m
        ``Delta``.
    compiled : bool
        Kernels compiled to C (cached on disk) or interpreted.
    """

    def __init__(self, template: ModelSpec, element_length: float, compiled: bool):
        if template.element.torsion:
            raise ValueError(
                "model.torsion = true: a paid-out line (winch.line) needs 5-DOF elements"
            )
        self.template, self.element_length = template, element_length
        self.kernels, self.report = compiled_kernels(template, compiled)
        self._models: dict[int, CableModel] = {}

    def model(self, elements: int) -> CableModel:
        """The model of ``n = elements`` (>= 2)."""
        if elements not in self._models:
            self._models[elements] = self._build(elements)
        return self._models[elements]

    def _build(self, elements: int) -> CableModel:
        spec = line_spec(self.template, elements, self.element_length)
        parametric = ParametricModel(structure_of(spec))
        parameters, delta = kernel_parameters(parameter_names(spec), elements)
        p = ca.MX.sym("p", parametric.p.numel())
        own = replace(
            self.kernels.kernels,
            segment_length=ca.Function("segment_length", [p], [delta(p)]),
            parameters=parameters,
        )
        kernels = replace(self.kernels, kernels=own)
        graph = structured.structured_graph(parametric, kernels)
        parametric.memo(("structured", "graph"), lambda: graph)
        functions = {key: build(parametric) for key, (_, build) in structured.LIBRARY.items()}
        report = self.report or CompileReport(False, 0.0, None)
        parametric.memo(("structured", "compiled"), lambda: (functions, report))
        return CableModel(spec, parametric=parametric)


@lru_cache(maxsize=LINE_MODELS_KEPT)
def line_models(template: ModelSpec, element_length: float, compiled: bool) -> LineModels:
    """The :class:`LineModels` of a line, built once per process and shared by later calls.

    A run, the statics of its landing line and the checks of the run all ask for the models of
    the same line; each ``n``'s model costs 10-20 ms to build (1 s for the 100 counts of a
    1000 m line), so they are kept. Models are immutable once built (their memos only add).
    """
    return LineModels(template, element_length, compiled)
