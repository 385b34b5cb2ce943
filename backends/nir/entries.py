r"""What an exported NIR graph carries so radarsnn can read the network back exactly.

NIR holds the dynamics; the artifact entries of :mod:`backends.artifact_codec`
hold everything (axes, shared and sparse weights, stencils, phase schedules,
codes).  The exporter puts those entries into the NIR metadata:

* a population's NIR node (its ``Input`` or spiking node): ``radarsnn_entry``
  (the population entry, JSON), ``radarsnn_index`` (its position) and
  ``radarsnn_network`` (the network's position in the graph);
* a projection's first NIR node: ``radarsnn_entry`` (the projection entry with
  its array references), ``radarsnn_index``, ``radarsnn_network`` and its arrays
  as ``radarsnn_array_<field>``, except one the node's own ``weight`` holds
  exactly (transposed), named in ``radarsnn_weight_field``;
* the graph: ``radarsnn_artifacts``, per network its name, steps, meta,
  encoders and decoders (JSON).

A projection whose dense ``(post, pre)`` matrix is over ``max_weights`` entries
is written *compact* (:func:`compact_node`): one ``Linear`` holding the shared
block ``W^T`` of a dense matrix projection (applied to every repetition), or an
empty ``Linear`` (shape ``(0, 0)``) whose weights are only in the metadata (a
sparse matrix, a stencil).  NIR has no repeated, sparse or stencil weight node,
so such a graph needs ``type_check=False`` in ``nir.read`` and a consumer that
reads the metadata; radarsnn's :func:`backends.nir.import_nir` does.

Examples
--------
>>> from compiler.snn import MatrixProjection, Population
>>> x = Population(id="x", shape={"rep": 3, "i": 2}, source=True)
>>> y = Population(id="y", shape={"rep": 3, "o": 2})
>>> w = MatrixProjection(id="w", source="x", target="y", contract=("i",), produce=("o",),
...                      weights=np.array([[1.0, 0.0], [2.0, 3.0]]))
>>> node, how = compact_node(w, x, y, max_weights=16)
>>> node.weight.tolist(), how.split(":")[0]
([[1.0, 2.0], [0.0, 3.0]], 'the shared 2 x 2 block of 3 repetitions as one Linear')
>>> meta = projection_meta(w, 0, 0, node.weight)
>>> meta["radarsnn_weight_field"], sorted(k for k in meta if k.startswith("radarsnn_array"))
('weights', [])
"""

from __future__ import annotations

import json
from typing import Any

import nir
import numpy as np

from backends.artifact_codec import population_entry, projection_entry
from backends.artifact_io import finite_json
from compiler.snn.network import Population, SpikingNetwork
from ir.errors import ArtifactError

__all__ = ["ARRAY_PREFIX", "ROUND_TRIP_VERSION", "compact_node", "network_entry",
           "population_meta", "projection_meta"]

#: Metadata key prefix of a projection's arrays.
ARRAY_PREFIX = "radarsnn_array_"
#: Version of the round-trip metadata (graph metadata ``radarsnn_round_trip``).
ROUND_TRIP_VERSION = "1"


def _json(value: Any) -> str:
    return json.dumps(value, sort_keys=True, allow_nan=False)


def population_meta(pop: Population, index: int, network: int) -> dict[str, str]:
    """Metadata of a population's NIR node: its artifact entry and positions.

    Parameters
    ----------
    pop : Population
    index, network : int
        Its position in the network, the network's in the graph.

    Returns
    -------
    dict of str to str
        ``radarsnn_entry`` (JSON), ``radarsnn_index``, ``radarsnn_network``.
    """
    return {"radarsnn_entry": _json(population_entry(pop)), "radarsnn_index": str(index),
            "radarsnn_network": str(network)}


def projection_meta(proj: Any, index: int, network: int, weight: np.ndarray | None,
                    max_entries: int = 1 << 24) -> dict[str, Any]:
    """Metadata of a projection's first NIR node: entry, positions and arrays.

    Parameters
    ----------
    proj : projection
        A projection of the registry of :mod:`backends.artifact`.
    index, network : int
        Its position in the network, the network's in the graph.
    weight : ndarray or None
        The ``weight`` of the NIR node the metadata goes on: an array equal to it
        transposed is not stored twice.
    max_entries : int
        Refuse an array over this many entries (the reader's bound).

    Returns
    -------
    dict
        ``radarsnn_entry`` (JSON), ``radarsnn_index``, ``radarsnn_network``, one
        ``radarsnn_array_<field>`` per array, ``radarsnn_weight_field`` when ``weight``
        holds one.

    Raises
    ------
    ArtifactError
        For an array over ``max_entries``.
    """
    arrays: dict[str, np.ndarray] = {}
    entry = projection_entry(index, proj, arrays)
    meta: dict[str, Any] = {"radarsnn_entry": _json(entry), "radarsnn_index": str(index),
                            "radarsnn_network": str(network)}
    for name, ref in entry["arrays"].items():
        a = arrays[ref["key"]]
        if a.size > max_entries:
            raise ArtifactError(f"projection {proj.id!r}: its {name} array has {a.size} "
                                f"entries, over the {max_entries} a NIR file may hold per "
                                "dataset; export fewer repetitions", node=proj.id)
        if (weight is not None and "radarsnn_weight_field" not in meta and a.ndim == 2
                and weight.shape == a.T.shape and weight.dtype == a.dtype
                and np.array_equal(weight, a.T)):
            meta["radarsnn_weight_field"] = name
        else:
            meta[ARRAY_PREFIX + name] = a
    return meta


def compact_node(proj: Any, src: Population, tgt: Population, max_weights: int
                 ) -> tuple[nir.Linear, str]:
    """The one NIR node of a projection whose dense matrix is too large, and its wording.

    Parameters
    ----------
    proj : projection
    src, tgt : Population
        Its source and target.
    max_weights : int
        The largest block written as a ``Linear``.

    Returns
    -------
    node : nir.Linear
        ``Linear(W^T)`` of a dense matrix projection whose block fits ``max_weights`` (the
        block shared by its repetitions); else an empty ``Linear`` (weights in metadata only).
    detail : str
        The export report's sentence.
    """
    weights = getattr(proj, "weights", None)
    if weights is not None and weights.size <= max_weights:
        n_in, n_out = weights.shape
        reps = src.size // n_in
        return nir.Linear(weight=np.ascontiguousarray(weights.T)), (
            f"the shared {n_out} x {n_in} block of {reps} repetitions as one Linear: NIR "
            "has no repeated Linear (radarsnn_entry names the axes)")
    what = type(proj).__name__  # MatrixProjection (sparse here) or StencilProjection
    return nir.Linear(weight=np.zeros((0, 0))), (
        f"a {what} over {src.size} -> {tgt.size} neurons has no NIR node short of a dense "
        f"Linear over max_weights={max_weights}: an empty Linear, weights in metadata")


def network_entry(net: SpikingNetwork) -> dict[str, Any]:
    """The network's name, steps, meta, encoders and decoders (graph ``radarsnn_artifacts``).

    Examples
    --------
    >>> from compiler.snn import RateCode, Encoder
    >>> net = SpikingNetwork(name="n", n_steps=4, populations=[Population(id="x",
    ...     shape={"i": 2}, source=True)], encoders=[Encoder(port="x", population="x",
    ...     code=RateCode())])
    >>> entry = network_entry(net)
    >>> entry["network"], entry["encoders"][0]["port"]
    ({'name': 'n', 'n_steps': 4, 'meta': {}}, 'x')
    """
    return {"network": {"name": net.name, "n_steps": int(net.n_steps), "meta": net.meta},
            "encoders": [finite_json(e.model_dump(mode="json")) for e in net.encoders],
            "decoders": [finite_json(d.model_dump(mode="json")) for d in net.decoders]}
