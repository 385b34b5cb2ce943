"""A :class:`~compiler.snn.SpikingNetwork` as manifest entries plus a table of arrays.

The encoders here turn populations and projections into strict-JSON entries of the
manifest described in :mod:`backends.artifact`; every projection array is moved into
a table (stored as ``arrays.npz``) and replaced by a reference
``{"file": "arrays.npz", "key": k, "dtype": "<f8", "shape": [...]}`` (little-endian,
C order).  :func:`network_from_manifest` inverts them, instantiating projection
classes only from the registry it is given, and refuses arrays that are missing,
unreferenced, or of the wrong dtype or shape.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from backends.artifact_io import ARRAYS_FILE, finite_json, plain_json
from compiler.snn import Decoder, Encoder, Population, SpikingNetwork
from ir.errors import ArtifactError

__all__ = ["network_from_manifest", "population_entry", "projection_entry"]


def _array_ref(key: str, array: np.ndarray, arrays: dict[str, np.ndarray]) -> dict:
    a = np.asarray(array)
    a = np.ascontiguousarray(a.astype(a.dtype.newbyteorder("<")))
    arrays[key] = a
    return {"file": ARRAYS_FILE, "key": key, "dtype": a.dtype.str, "shape": list(a.shape)}


def population_entry(pop: Population) -> dict:
    """The manifest entry of a population: its fields, ``shape`` as ordered pairs.

    Parameters
    ----------
    pop : Population

    Returns
    -------
    dict
        Strict JSON (non-finite floats as ``"NaN"``/``"±Infinity"``); ``shape`` is a
        list of ``[axis, size]`` pairs in memory order.

    Examples
    --------
    >>> population_entry(Population(id="in", shape={"z": 2, "a": 3}, source=True))["shape"]
    [['z', 2], ['a', 3]]
    """
    data = finite_json(pop.model_dump(mode="json"))
    data["shape"] = [[axis, size] for axis, size in pop.shape.items()]  # order is memory order
    return data


def projection_entry(index: int, proj: Any, arrays: dict[str, np.ndarray]) -> dict:
    """The manifest entry of projection number ``index``; its arrays go into ``arrays``.

    Parameters
    ----------
    index : int
        Position in ``network.projections`` (array keys are ``projections.<index>.<field>``).
    proj : projection dataclass
        A :class:`~compiler.snn.MatrixProjection` or :class:`~compiler.snn.StencilProjection`.
    arrays : dict of str to ndarray
        The array table, updated in place with little-endian contiguous copies.

    Returns
    -------
    dict
        Plain fields (tuples as lists, ``None`` omitted) and ``"arrays"``: field -> reference.

    Raises
    ------
    ArtifactError
        If a non-array field is not plain JSON.

    Examples
    --------
    >>> from compiler.snn import MatrixProjection
    >>> proj = MatrixProjection(id="w", source="in", target="out", contract=("i",),
    ...                         produce=("o",), weights=np.ones((2, 1)))
    >>> table = {}
    >>> projection_entry(0, proj, table)["arrays"]["weights"]["shape"], sorted(table)
    ([2, 1], ['projections.0.weights'])
    """
    data: dict[str, Any] = {"arrays": {}}
    for f in dataclasses.fields(proj):
        value = getattr(proj, f.name)
        if isinstance(value, np.ndarray):
            key = f"projections.{index}.{f.name}"
            data["arrays"][f.name] = _array_ref(key, value, arrays)
        elif value is not None:
            data[f.name] = plain_json(list(value) if isinstance(value, tuple) else value,
                                       f"projection {proj.id!r} field {f.name!r}")
    return data


def _take_array(ref: Any, arrays: dict[str, np.ndarray], used: set[str], where: str) -> np.ndarray:
    if not isinstance(ref, dict) or ref.get("file") != ARRAYS_FILE:
        raise ArtifactError(f"{where}: array reference {ref!r} must name file {ARRAYS_FILE!r}")
    key = ref.get("key")
    if key not in arrays:
        raise ArtifactError(f"{where}: array {key!r} is missing from {ARRAYS_FILE}")
    array = arrays[key]
    if array.dtype.str != ref.get("dtype") or list(array.shape) != ref.get("shape"):
        raise ArtifactError(f"{where}: array {key!r} in {ARRAYS_FILE} has dtype {array.dtype.str} "
                            f"and shape {list(array.shape)}, the manifest declares "
                            f"{ref.get('dtype')} and {ref.get('shape')}")
    used.add(key)
    return array


def _projection(data: dict, arrays: dict, used: set[str], kinds: Mapping[str, type],
                where: str) -> Any:
    cls = kinds.get(data.get("kind"))
    if cls is None:
        raise ArtifactError(f"{where}: unknown projection kind {data.get('kind')!r}; this "
                            f"radarsnn knows {sorted(kinds)}")
    fields = {f.name for f in dataclasses.fields(cls)}
    refs = data.get("arrays", {})
    unknown = (set(data) - {"arrays"} | set(refs)) - fields
    if unknown:
        raise ArtifactError(f"{where}: fields {sorted(unknown)} are not fields of {cls.__name__}")
    kwargs = {k: v for k, v in data.items() if k != "arrays"}
    kwargs.update({k: _take_array(r, arrays, used, f"{where}.{k}") for k, r in refs.items()})
    return cls(**kwargs)


def network_from_manifest(manifest: dict, arrays: dict, kinds: Mapping[str, type],
                          path: Path) -> SpikingNetwork:
    """Rebuild the network from a checked manifest and its array table (not yet validated).

    Parameters
    ----------
    manifest : dict
        A manifest as :func:`backends.artifact.read_manifest` returns it.
    arrays : dict of str to ndarray
        The members of ``arrays.npz``.
    kinds : mapping of str to type
        Projection registry: the only classes instantiated.
    path : Path
        The manifest's path (for messages).

    Returns
    -------
    SpikingNetwork
        Call ``validate()`` on it.

    Raises
    ------
    ArtifactError
        For a repeated population axis, an unknown projection kind or field, or an
        array that is missing, unreferenced, or of the wrong dtype/shape.
    pydantic.ValidationError, KeyError, TypeError, ValueError
        For entries that do not parse (:func:`backends.artifact.load` wraps these).

    Examples
    --------
    >>> entry = population_entry(Population(id="in", shape={"i": 2}, source=True))
    >>> manifest = {"populations": [entry], "projections": [], "encoders": [],
    ...             "decoders": [], "network": {"name": "n", "n_steps": 4, "meta": {}}}
    >>> network_from_manifest(manifest, {}, {}, Path("m.json")).populations[0].shape
    {'i': 2}
    """
    used: set[str] = set()
    populations = []
    for data in manifest["populations"]:
        pairs = data["shape"]
        shape = dict(pairs)
        if len(shape) != len(pairs):
            raise ArtifactError(f"{path}: population {data.get('id')!r} repeats an axis in {pairs}")
        populations.append(Population.model_validate({**data, "shape": shape}))
    projections = [_projection(d, arrays, used, kinds, f"{path}: projections[{i}]")
                   for i, d in enumerate(manifest["projections"])]
    if set(arrays) - used:
        raise ArtifactError(f"{path.with_name(ARRAYS_FILE)}: holds arrays the manifest does not "
                            f"refer to: {sorted(set(arrays) - used)}")
    info = manifest["network"]
    return SpikingNetwork(
        name=info["name"], n_steps=info["n_steps"], meta=info["meta"],
        populations=populations, projections=projections,
        encoders=[Encoder.model_validate(e) for e in manifest["encoders"]],
        decoders=[Decoder.model_validate(d) for d in manifest["decoders"]])
