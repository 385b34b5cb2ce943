r"""``emit_numpy``: a compiled network or program as a standalone, readable numpy package.

Generated layout (``<out_dir>/<name>/``)::

    __init__.py        run, INPUTS, InputError, OutOfRangeWarning
    __main__.py        python -m <name> [PORT=]X.npy ... -o OUT.npz [--counts] [--clip]
    program.py         run(inputs, *, with_counts=False, out_of_range="reject"):
                       the segments in order; input values above an encoder's
                       range are refused (InputError) unless clipped on request
    network_<k>.py     the step loop of spiking segment k
    stage_<node>.py    per IR node: folded neuron updates, deliveries, encoders,
                       decoders, or the host op's compute(x)
    _kernels.py        numpy kernels (delivery, ports, host CFAR)
    weights.npz        every array (deterministic bytes)
    names.json         original ids -> generated names, chain, target, version

Every ``.py`` file starts with a header naming the radarsnn version, the chain
and the target.  Equal input gives byte-identical files.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

from backends.artifact import load
from backends.artifact_io import npz_bytes
from backends.emit.names import slug
from backends.emit.numpy_host import emit_host
from backends.emit.numpy_loop import emit_network, import_from
from backends.emit.package import PackageBuilder
from backends.emit.render import Code, comment, ident, indent, join, lit, render, template
from backends.emit.writer import write_package
from backends.manifest import radarsnn_version
from backends.program_artifact import is_program, load_program
from backends.reference.guards import check_simulation
from backends.reference.plan import build_plan
from backends.reference.units import normalized_inputs, unit_plan
from compiler.program import CompiledProgram, Segment
from compiler.snn.network import SpikingNetwork
from ir.errors import CompileError

__all__ = ["emit_numpy"]

def _as_program(source: object) -> tuple[CompiledProgram | None, list[SpikingNetwork]]:
    if isinstance(source, str | os.PathLike):
        if is_program(source):  # a compiled program's folder (radarsnn compile -o)
            program = load_program(source)
            return program, program.networks
        return None, [load(source)]
    kinds = {SpikingNetwork: lambda s: (None, [s]),
             CompiledProgram: lambda s: (s, s.networks)}
    if type(source) not in kinds:
        raise CompileError(f"emit_numpy: source must be a SpikingNetwork, a CompiledProgram or "
                           f"an artifact directory, got {type(source).__name__}")
    return kinds[type(source)](source)


#: Top-level modules a generated package imports or runs beside (besides the standard library).
_SHADOWED = frozenset({"numpy", "builtins", "__main__"})


def check_package_name(name: str) -> None:
    """Refuse a package name that is no identifier or would shadow a module it needs.

    The package is imported from its parent directory (``python -m <name>``), so a
    name equal to a standard-library module (``sys``, ``json``, ``argparse``...) or to
    ``numpy`` would replace that module for the generated code and every import after it.

    Raises
    ------
    CompileError
        Naming the package and the reason, with a suggestion.

    Examples
    --------
    >>> check_package_name("snn_carrada")
    >>> check_package_name("json")
    Traceback (most recent call last):
    ir.errors.CompileError: package name 'json' would shadow the module 'json' that generated \
code imports (standard library or numpy); choose another name, e.g. 'snn_json'
    """
    str(ident(name))  # validates
    if name.startswith("_"):
        raise CompileError(f"package name {name!r} must not start with '_'")
    shadowed = {m for m in (*sys.stdlib_module_names, *sys.builtin_module_names, *_SHADOWED)
                if m.lower() == name.lower()}  # case-insensitive file systems too
    if shadowed:
        raise CompileError(f"package name {name!r} would shadow the module "
                           f"{sorted(shadowed)[0]!r} that generated code imports (standard "
                           f"library or numpy); choose another name, e.g. 'snn_{name}'")


def _target_name(program: CompiledProgram | None, networks: list[SpikingNetwork]) -> str:
    if program is not None and program.target is not None:
        return program.target.name
    metas = [n.meta for n in networks]
    return str(next((m.get("quantized_for") or m.get("target") for m in metas
                     if m.get("quantized_for") or m.get("target")), "none"))


def emit_numpy(source: SpikingNetwork | CompiledProgram | str | os.PathLike, out_dir: str | Path,
               *, name: str | None = None, arithmetic: str = "float64") -> Path:
    """Generate a standalone numpy simulator package for ``source``.

    Parameters
    ----------
    source : SpikingNetwork, CompiledProgram, or path of an artifact directory
        What to generate code for.  A program's host segments must be ops with a
        host emitter (magnitude, sum, log, window, dft, linear, threshold, cfar, output).
    out_dir : str or Path
        The directory that receives the package folder.
    name : str, optional
        Package (folder) name, a Python identifier; default ``snn_<chain slug>``.
    arithmetic : {"float64", "int64"}
        As ``backends.reference.simulate``'s (``int64`` needs a quantized network).

    Returns
    -------
    Path
        The package directory ``out_dir/name``.

    Raises
    ------
    CompileError
        An unsupported source type or host op (naming the node), or a bad ``name``.
    NetworkError, SimulationError
        If a network does not validate or is not integer under ``int64``.
    ArtifactError
        An unreadable artifact, or ``out_dir/name`` exists and is not a generated package.

    Examples
    --------
    >>> import tempfile
    >>> from compiler.snn.examples import tiny_network
    >>> net = tiny_network(kind="spike_time")  # two inputs, one neuron
    >>> with tempfile.TemporaryDirectory() as tmp:
    ...     sorted(p.name for p in emit_numpy(net, tmp).iterdir())  # doctest: +NORMALIZE_WHITESPACE
    ['__init__.py', '__main__.py', '_kernels.py', 'names.json', 'network_0.py', 'program.py',
     'stage_in.py', 'stage_out.py', 'weights.npz']

    Notes
    -----
    The generated code follows ``backends.reference`` step mode operation for
    operation, so its outputs and spike counts are identical to
    ``simulate(..., mode="step")`` / ``run_program(..., mode="step")``.
    """
    program, networks = _as_program(source)
    chain = program.graph.name if program is not None else networks[0].name
    name = name if name is not None else "snn_" + slug(chain)
    check_package_name(name)
    version = radarsnn_version()
    header = render(template("header.tmpl"), version=comment(version), chain=comment(chain, 80),
                    target=comment(_target_name(program, networks), 80))
    pkg = PackageBuilder()
    files: dict[str, Code] = {}
    integer = arithmetic == "int64"
    segments = program.segments if program is not None else [
        Segment(kind="spiking", inputs=[e.port for e in networks[0].encoders],
                outputs=[d.port for d in networks[0].decoders], network=networks[0])]
    body, imports, net_names = [], {"_kernels"}, []
    decoded: set[str] = set()  # values decoded from spikes: clipped under every policy
    types = program.graph.infer_types() if program is not None else {}
    if program is not None:
        for node in program.graph.input_ids():
            t = types[node]
            body.append(render("node = $n\nvalues[node] = _kernels.check_input(inputs, node, $s, "
                               "$c, $d)",
                               n=lit(node), s=lit(tuple(t.shape)), c=lit(bool(t.complex)),
                               d=lit(t.domain)))
        per_input = normalized_inputs(program)  # the per-input policy: run as calibrated
        if per_input:
            spec = tuple((n, tuple(types[n].names.index(a) for a in ax))
                         for n, ax in sorted(per_input.items()))
            body.append(render("peaks = _kernels.normalize_inputs(values, $spec)", spec=lit(spec)))
    else:
        body.append(render("values.update(inputs)"))
    for seg in segments:
        if seg.kind == "spiking":
            module = f"network_{len(net_names)}"
            seg.network.validate()  # the plan's per-step arrays: refuse before allocating
            check_simulation(seg.network, 1, max_time_s=None)
            plan = build_plan(seg.network, arithmetic)
            files[module + ".py"] = emit_network(pkg, plan, integer, header)
            net_names.append({"module": module, "network": seg.network.name})
            ports = tuple(e.port for e in seg.network.encoders)
            body.append(render(
                "ports = $ports\ndecoded = $decoded\n"
                "policies = _kernels.segment_policy(out_of_range, ports, decoded)\n"
                "outs, spikes = $m.simulate({p: values[p] for p in ports}, policies)\n"
                "values.update(outs)\ncounts.append(spikes)", m=ident(module), ports=lit(ports),
                decoded=lit(tuple(p for p in ports if p in decoded))))
            masks = tuple(d.port for d in seg.network.decoders
                          if d.port in types and types[d.port].domain == "mask")
            if masks:  # a decoded mask is bool, as run_program and the interpreter give it
                body.append(render("for node in $masks:\n    values[node] = values[node] != 0",
                                   masks=lit(masks)))
            decoded.update(d.port for d in seg.network.decoders)
        else:
            op = program.graph.op(seg.node)
            module = emit_host(pkg, seg.node, op, types[seg.inputs[0]])
            body.append(render("node = $n\nsources = $i\n"
                               "values[node] = $m.compute(*(values[s] for s in sources))",
                               n=lit(seg.node), m=ident(module), i=lit(tuple(seg.inputs))))
            if decoded.intersection(seg.inputs):
                decoded.add(seg.node)
        imports.add(module)
    inputs = (program.graph.input_ids() if program is not None
              else [e.port for e in networks[0].encoders])
    outputs = (program.graph.output_ids() if program is not None
               else [d.port for d in networks[0].decoders])
    if program is not None:
        units, _ = unit_plan(program, types, list(outputs))
        if units:
            body.append(render("_kernels.apply_units(values, peaks, $plan)", plan=lit(
                tuple((node, *step) for node, step in sorted(units.items())))))
    files["program.py"] = render(template("program.py.tmpl"), header=header,
                                 chain=comment(chain), imports=render(
                                     "\n$i", i=import_from(sorted(imports))),
                                 inputs=lit(tuple(inputs)), outputs=lit(tuple(outputs)),
                                 shapes=lit(tuple((n, tuple(types[n].shape)) for n in inputs)
                                            if program is not None else ()),
                                 body=indent(join(body)))
    for module in pkg.bodies:
        files[module + ".py"] = _stage_file(pkg, module, header)
    for fixed in ("__init__", "__main__", "_kernels"):
        files[fixed + ".py"] = render(template(fixed.strip("_") + ".py.tmpl"), header=header)
    names = {"package": name, "chain": chain, "target": _target_name(program, networks),
             "radarsnn_version": version, "arithmetic": arithmetic, "networks": net_names,
             **pkg.names}
    return _write(Path(out_dir) / name, files, names, pkg)


def _stage_file(pkg: PackageBuilder, module: str, header: Code) -> Code:
    code = pkg.module_code(module)
    text = str(code)
    blocks = []
    if "@functools." in text:
        blocks.append(render("import functools"))
    if "np." in text:
        blocks.append(render("import numpy as np"))
    if "_kernels." in text:
        blocks.append(render("from . import _kernels"))
    imports = render("\n$b", b=join(blocks, "\n\n")) if blocks else render("")
    return render(template("stage.py.tmpl"), header=header, node=comment(pkg.nodes[module]),
                  imports=imports, functions=code)


def _write(folder: Path, files: dict[str, Code], names: dict, pkg: PackageBuilder) -> Path:
    data = {fname: (str(code).rstrip("\n") + "\n").encode("utf-8") for fname, code in files.items()}
    data["weights.npz"] = npz_bytes(dict(sorted(pkg.arrays.items())))
    return write_package(folder, data, names)
