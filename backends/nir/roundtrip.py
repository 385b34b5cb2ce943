r"""Read NIR graphs back as spiking networks: radarsnn's own exports exactly, others by subset.

A graph radarsnn exported (graph metadata ``radarsnn_round_trip``) carries the
artifact entries of every population and projection (:mod:`backends.nir.entries`);
:func:`import_nir` reassembles the manifest of each network and rebuilds it with
the artifact decoder (:func:`backends.artifact_codec.network_from_manifest`), so
the network equals the exported one field for field and simulates to the same
bits.  The file's NIR nodes must be what exporting those networks gives again: a graph
edited by another tool after export is refused (strip its ``radarsnn_*`` metadata to read
it as a plain NIR graph).  Any other graph is read as the NIR subset of :mod:`backends.nir.generic`.

Examples
--------
>>> from backends.nir.export import export_network
>>> from compiler.snn import RateCode
>>> from compiler.snn.examples import tiny_network
>>> net = tiny_network(code=RateCode(), kind="count", scoped=True)
>>> [back] = import_nir(export_network(net)[0])
>>> back.projections[0].weights.tolist(), back.populations[1] == net.populations[1]
([[1.0], [1.0]], True)
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import nir
import numpy as np
from pydantic import ValidationError

from backends.artifact import PROJECTION_KINDS
from backends.artifact_codec import network_from_manifest
from backends.nir.entries import ARRAY_PREFIX
from backends.nir.generic import import_generic
from backends.nir.reading import DEFAULT_BOUNDS, ReadBounds, read_nir
from compiler.snn.network import SpikingNetwork
from ir.errors import ArtifactError, IRError, RadarSNNError

__all__ = ["import_nir"]


def _text(value: Any) -> Any:
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else value


def _json(value: Any, where: str, key: str) -> Any:
    value = _text(value)
    if not isinstance(value, str):
        raise ArtifactError(f"{where}: metadata {key!r} is not a JSON string")
    try:
        return json.loads(value)
    except ValueError as exc:
        raise ArtifactError(f"{where}: metadata {key!r} is not JSON ({exc})") from None


def _int(meta: dict, key: str, where: str) -> int:
    value = _text(meta.get(key))
    if not (isinstance(value, str) and value.isascii() and value.isdigit()):
        raise ArtifactError(f"{where}: metadata {key!r} must be a non-negative integer, "
                            f"got {value!r}")
    return int(value)


def _arrays(name: str, node: nir.NIRNode, entry: dict) -> dict[str, np.ndarray]:
    """The projection's arrays from ``node``'s metadata, keyed as its entry refers to them."""
    meta, where = node.metadata, f"NIR node {name!r}"
    refs = entry.get("arrays") if isinstance(entry, dict) else None
    if not isinstance(refs, dict):
        raise ArtifactError(f"{where}: radarsnn_entry has no `arrays` mapping")
    shared = _text(meta.get("radarsnn_weight_field"))
    out = {}
    for field, ref in refs.items():
        key = ref.get("key") if isinstance(ref, dict) else None
        if not isinstance(key, str):
            raise ArtifactError(f"{where}: array reference {field!r} has no key")
        if field == shared:
            value = np.ascontiguousarray(np.asarray(getattr(node, "weight", None)).T)
        elif ARRAY_PREFIX + field in meta:
            value = np.asarray(meta[ARRAY_PREFIX + field])
        else:
            raise ArtifactError(f"{where}: the {field!r} array ({ARRAY_PREFIX}{field}) is "
                                "missing from the metadata")
        out[key] = value
    return out


def _node_size(node: nir.NIRNode) -> int:
    """Neurons of a population's NIR node: an Input's declared shape, a neuron's arrays."""
    if isinstance(node, nir.Input):
        shape = np.asarray(node.output_type.get("output", ()), dtype=np.float64)
        return int(np.prod(shape)) if shape.size and np.all(shape >= 0) else -1
    return int(np.asarray(getattr(node, "v_threshold", ())).size)


def _from_entries(graph: nir.NIRGraph, where: str) -> list[SpikingNetwork]:
    infos = _json(graph.metadata.get("radarsnn_artifacts"), where, "radarsnn_artifacts")
    if not isinstance(infos, list) or not all(isinstance(i, dict) for i in infos):
        raise ArtifactError(f"{where}: radarsnn_artifacts must be a list of network entries")
    found: list[dict[str, dict]] = [{"populations": {}, "projections": {}} for _ in infos]
    arrays: list[dict[str, np.ndarray]] = [{} for _ in infos]
    sizes: list[dict[int, tuple[str, int]]] = [{} for _ in infos]
    for name, node in graph.nodes.items():
        meta = node.metadata if isinstance(node.metadata, dict) else {}
        if "radarsnn_entry" not in meta:
            continue
        here = f"{where}: NIR node {name!r}"
        k, index = _int(meta, "radarsnn_network", here), _int(meta, "radarsnn_index", here)
        if k >= len(infos):
            raise ArtifactError(f"{here}: network {k} is not one of the {len(infos)} listed")
        entry = _json(meta["radarsnn_entry"], here, "radarsnn_entry")
        part = "projections" if "radarsnn_projection" in meta else "populations"
        if index in found[k][part]:
            raise ArtifactError(f"{here}: a second {part[:-1]} at index {index}")
        found[k][part][index] = entry
        if part == "projections":
            arrays[k].update(_arrays(name, node, entry))
        else:
            sizes[k][index] = (name, _node_size(node))
    nets = []
    for k, info in enumerate(infos):
        lists = {}
        for part, by_index in found[k].items():
            if sorted(by_index) != list(range(len(by_index))):
                raise ArtifactError(f"{where}: network {k} has {part} at indices "
                                    f"{sorted(by_index)[:8]}, not 0..{len(by_index) - 1}")
            lists[part] = [by_index[i] for i in range(len(by_index))]
        manifest = {**info, **lists}
        try:
            net = network_from_manifest(manifest, arrays[k], PROJECTION_KINDS, Path(where))
            for index, pop in enumerate(net.populations):  # before anything is allocated
                name, size = sizes[k][index]
                if pop.size != size:
                    raise ArtifactError(f"{where}: NIR node {name!r} has {size} neurons, its "
                                        f"radarsnn entry {pop.size}", node=name)
            nets.append(net.validate())
        except ArtifactError:
            raise
        except RadarSNNError as exc:
            raise ArtifactError(f"{where}: network {k}: {exc}") from None
        except (ValidationError, KeyError, TypeError, ValueError, AttributeError) as exc:
            text = str(exc).splitlines()[0]
            raise ArtifactError(f"{where}: network {k}: the radarsnn entries do not form a "
                                f"network ({type(exc).__name__}: {text[:200]})") from None
    return nets


#: The NIR fields compared between a file and the export of the networks read from it.
_FIELDS = ("weight", "bias", "tau", "r", "v_leak", "v_threshold", "v_reset", "tau_syn",
           "tau_mem", "w_in", "delay")


def _check_dynamics(graph: nir.NIRGraph, nets: list[SpikingNetwork], where: str,
                    bounds: ReadBounds) -> None:
    """The file's NIR nodes must be what exporting ``nets`` gives: not edited since export.

    A readable file holds no dense ``Linear`` over ``bounds.max_dataset_entries``, so the
    export is redone with ``max_weights`` at most that (a forged larger one allocates nothing).
    """
    from backends.nir.export import _export  # the exporter, to redo the export

    meta = graph.metadata
    try:
        dt_s = float(_text(meta.get("radarsnn_dt_s")))
        max_weights = min(int(_text(meta.get("radarsnn_max_weights"))), bounds.max_dataset_entries)
    except (TypeError, ValueError):
        raise ArtifactError(f"{where}: radarsnn_dt_s and radarsnn_max_weights must be "
                            "numbers") from None
    if not (np.isfinite(dt_s) and dt_s > 0):  # the export would refuse it, naming no file
        raise ArtifactError(f"{where}: radarsnn_dt_s must be a positive number of seconds, "
                            f"got {dt_s!r}")
    try:
        again, _ = _export(nets, [], dt_s, max_weights, name=nets[0].name if nets else "")
    except ArtifactError as exc:
        raise ArtifactError(f"{where}: {exc}") from None
    edited = "was edited after export; strip its radarsnn metadata to import it as a NIR graph"
    if set(again.nodes) != set(graph.nodes) or sorted(again.edges) != sorted(
            tuple(e) for e in graph.edges):
        extra = sorted(set(graph.nodes) ^ set(again.nodes))[:4]
        raise ArtifactError(f"{where}: the NIR nodes or edges differ from the radarsnn entries "
                            f"(nodes {extra}): the graph {edited}")
    for name, node in again.nodes.items():
        theirs = graph.nodes[name]
        same = type(theirs) is type(node) and all(
            np.array_equal(np.asarray(getattr(theirs, f)), np.asarray(getattr(node, f)))
            for f in _FIELDS if hasattr(node, f))
        if not same:
            raise ArtifactError(f"{where}: NIR node {name!r} differs from its radarsnn entry: "
                                f"the graph {edited}", node=name)


def import_nir(source: nir.NIRGraph | str | Path, *, dt_s: float | None = None,
               n_steps: int = 100, bounds: ReadBounds = DEFAULT_BOUNDS) -> list[SpikingNetwork]:
    """The spiking networks of a NIR graph (a radarsnn export exactly, else the subset).

    Parameters
    ----------
    source : nir.NIRGraph or path
        A graph, or a ``.nir`` file read with :func:`backends.nir.reading.read_nir`
        (within ``bounds``, ``type_check=False`` for compact projections).
    dt_s : float, optional
        Step of a graph that is not radarsnn's and has no ``radarsnn_dt_s`` metadata
        (:func:`backends.nir.generic.import_generic`); radarsnn's own exports need none.
    n_steps : int
        Steps per run of a graph that is not radarsnn's (its own exports store theirs).
    bounds : ReadBounds
        Limits of the file read.

    Returns
    -------
    list of SpikingNetwork
        Validated, in the graph's order (one for a single-network export).

    Raises
    ------
    ArtifactError
        An unreadable or hostile file (naming the node path and limit), or radarsnn
        metadata that does not form a network (naming the NIR node).
    IRError
        A graph outside the supported NIR subset (naming the NIR node).
    """
    where = str(source) if not isinstance(source, nir.NIRGraph) else "NIR graph"
    graph = source if isinstance(source, nir.NIRGraph) else read_nir(
        source, bounds=bounds, type_check=False)
    meta = graph.metadata if isinstance(graph.metadata, dict) else {}
    if "radarsnn_round_trip" in meta:
        version = _text(meta["radarsnn_round_trip"])
        if version != "1":
            raise ArtifactError(f"{where}: radarsnn round-trip metadata version {version!r}; "
                                "this radarsnn reads version '1' (export it again)")
        nets = _from_entries(graph, where)
        _check_dynamics(graph, nets, where, bounds)
        return nets
    try:
        return [import_generic(graph, dt_s=dt_s, n_steps=n_steps, name=Path(where).stem)]
    except IRError as exc:
        if isinstance(source, nir.NIRGraph):
            raise
        raise IRError(f"{where}: {exc}", node=exc.node) from None
