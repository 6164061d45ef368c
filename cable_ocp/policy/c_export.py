"""The policy's network as dependency-free C: a ``.c`` and a ``.h``, for a winch controller.

The C function evaluates the same network as :meth:`.network.Network.function`, in the same
order of operations, with ``tanh`` from ``math.h`` the only library call::

    double cable_ocp_policy(const double observation[CABLE_OCP_POLICY_INPUTS]);

Its weights are written with 17 significant digits, which give back the same doubles, so the C
function agrees with the CasADi Function to round-off (1e-12 is the test's bound).
"""

from __future__ import annotations

from pathlib import Path

from cable_ocp.policy.network import Network

NAME = "cable_ocp_policy"


def _numbers(values) -> str:
    """The numbers as a C initialiser, 17 significant digits each (exact doubles)."""
    return ", ".join(f"{float(v):.17g}" for v in values)


def header(network: Network, features: tuple[str, ...]) -> str:
    """The ``.h`` text: the function's declaration and the observation's layout."""
    guard = NAME.upper() + "_H"
    lines = [
        f"/* Drum rate (rad/s) of a learned winch policy, clipped to +-{network.rate_limit:g} "
        "rad/s; written by cable_ocp. */",
        f"#ifndef {guard}",
        f"#define {guard}",
        f"#define {NAME.upper()}_INPUTS {network.inputs}",
        "/* The observation, in this order: */",
        *(f"/*   {k:2d} {name} */" for k, name in enumerate(features)),
        f"double {NAME}(const double observation[{NAME.upper()}_INPUTS]);",
        f"#endif /* {guard} */",
        "",
    ]
    return "\n".join(lines)


def source(network: Network, header_name: str) -> str:
    """The ``.c`` text: the weights as static arrays and the function's loops."""
    widest = max([network.inputs, *network.hidden])
    lines = [
        "/* A learned winch policy: a tanh MLP (cable_ocp.policy.network). No dependency */",
        "/* beyond math.h's tanh. */",
        "#include <math.h>",
        f'#include "{header_name}"',
        "",
        f"static const double input_mean[{network.inputs}] = {{{_numbers(network.input_mean)}}};",
        f"static const double input_scale[{network.inputs}] = {{{_numbers(network.input_scale)}}};",
    ]
    for k, (w, b) in enumerate(zip(network.weights, network.biases, strict=True)):
        lines.append(f"static const double w{k}[{w.size}] = {{{_numbers(w.ravel())}}};")
        lines.append(f"static const double b{k}[{b.size}] = {{{_numbers(b)}}};")
    lines += [
        "",
        f"double {NAME}(const double observation[{NAME.upper()}_INPUTS])",
        "{",
        f"    double a[{widest}], z[{widest}], rate;",
        "    int i, j;",
        f"    for (i = 0; i < {network.inputs}; ++i)",
        "        a[i] = (observation[i] - input_mean[i]) / input_scale[i];",
    ]
    last = len(network.weights) - 1
    for k, w in enumerate(network.weights):
        rows, columns = w.shape
        lines += [
            f"    for (i = 0; i < {rows}; ++i) {{",
            f"        z[i] = w{k}[i * {columns}] * a[0];",
            f"        for (j = 1; j < {columns}; ++j)",
            f"            z[i] += w{k}[i * {columns} + j] * a[j];",
            f"        z[i] += b{k}[i];",
            "    }",
        ]
        if k < last:
            lines.append(f"    for (i = 0; i < {rows}; ++i) a[i] = tanh(z[i]);")
    limit = f"{network.rate_limit:.17g}"
    lines += [
        f"    rate = {network.output_mean:.17g} + {network.output_scale:.17g} * z[0];",
        f"    if (rate > {limit}) rate = {limit};",
        f"    if (rate < -{limit}) rate = -{limit};",
        "    return rate;",
        "}",
        "",
    ]
    return "\n".join(lines)


def write_c(network: Network, features: tuple[str, ...], path: str | Path) -> tuple[Path, Path]:
    """Write ``path`` with the suffixes ``.c`` and ``.h``; returns their paths."""
    path = Path(path)
    if path.suffix in (".c", ".h"):
        path = path.with_suffix("")
    if len(features) != network.inputs:
        raise ValueError(f"to_c: {len(features)} feature names for {network.inputs} inputs")
    path.parent.mkdir(parents=True, exist_ok=True)
    c_file, h_file = path.with_suffix(".c"), path.with_suffix(".h")
    h_file.write_text(header(network, features), encoding="utf-8")
    c_file.write_text(source(network, h_file.name), encoding="utf-8")
    return c_file, h_file
