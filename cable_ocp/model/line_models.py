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

from dataclasses import replace

import casadi as ca

from cable_ocp.model import structured
from cable_ocp.model.cable import CableModel, ModelSpec
from cable_ocp.model.compile import CompileReport, compiled_from
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
) -> tuple[structured.Kernels, CompileReport | None]:
    """The structured kernels of ``template``'s structure at ``n = 2``, compiled to C or not.

    Returns the kernels and a :class:`~cable_ocp.model.compile.CompileReport` (None when not
    compiled).
    """
    reference = ParametricModel(structure_of(replace(template, elements=KERNEL_ELEMENTS)))
    kernels = structured.kernels_of(reference)
    if not compiled:
        return kernels, None
    functions, report = compiled_from(
        lambda: [getattr(kernels, name) for name in KERNEL_FIELDS],
        list(KERNEL_NAMES),
        f"{reference.structure!r}|structured kernels for every n",
        False,
    )
    return replace(kernels, **dict(zip(KERNEL_FIELDS, functions, strict=True))), report


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
        kernels = replace(
            self.kernels,
            segment_length=ca.Function("segment_length", [p], [delta(p)]),
            parameters=parameters,
        )
        graph = structured.structured_graph(parametric, kernels)
        parametric.memo(("structured", "graph"), lambda: graph)
        functions = {key: build(parametric) for key, (_, build) in structured.LIBRARY.items()}
        report = self.report or CompileReport(False, 0.0, None)
        parametric.memo(("structured", "compiled"), lambda: (functions, report))
        return CableModel(spec, parametric=parametric)
