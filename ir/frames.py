"""A leading frames axis on a chain's inputs: how many frames, one frame, and the stack.

A chain declares one frame (``adc: {rx: 4, chirp: 64, sample: 256}``); a recording
holds many.  Every entry point that runs a chain — :func:`ir.interpreter.evaluate`,
:func:`backends.reference.run_program`, ``radarsnn run`` — accepts inputs with one
extra *leading* axis of frames, as :func:`backends.reference.simulate` does for a
network: all inputs must then carry it, with the same length.  Each frame is run
as if given alone and the results are stacked along a new leading axis, so a framed
run equals the frames run one by one, bit for bit.

Examples
--------
>>> import numpy as np
>>> from ir.types import TensorType
>>> types = {"x": TensorType(axes={"range": 3})}
>>> n_frames(types, {"x": np.zeros(3)}) is None, n_frames(types, {"x": np.zeros((5, 3))})
(True, 5)
>>> frame({"x": np.arange(6.0).reshape(2, 3)}, 1)["x"].tolist()
[3.0, 4.0, 5.0]
>>> stack_frames([{"y": np.zeros(2)}, {"y": np.ones(2)}])["y"].shape
(2, 2)
>>> n_frames(types, {"x": np.zeros((2, 4))})  # neither one frame nor frames of one
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ir.errors import IRError
from ir.types import TensorType

__all__ = ["frame", "n_frames", "stack_frames"]


def n_frames(types: Mapping[str, TensorType], inputs: Mapping[str, object],
             where: str = "graph") -> int | None:
    """The number of frames of ``inputs``, or None when they are one frame.

    Parameters
    ----------
    types : mapping of str to TensorType
        The declared type of every input (at least those in ``inputs``).
    inputs : mapping of str to array_like
        The arrays by input node id.
    where : str
        What the inputs are for, named in errors (e.g. ``"program 'rd'"``).

    Returns
    -------
    int or None
        ``F`` when every input is shaped ``(F, *declared)``; None when none has the
        extra axis (including inputs of a wrong shape: the caller's shape check names
        them).

    Raises
    ------
    IRError
        Some inputs carry a frames axis and others do not, or the frame counts differ,
        or an input has zero frames.
    """
    counts = {}
    for node, value in inputs.items():
        t = types.get(node) if isinstance(node, str) else None
        shape = getattr(value, "shape", None)
        if t is None or shape is None:
            continue
        if len(shape) == len(t.shape) + 1 and tuple(shape[1:]) == t.shape:
            counts[node] = int(shape[0])
    if not counts:
        return None
    framed = {k for k in inputs if isinstance(k, str) and k in types}
    single = sorted(framed - set(counts))
    if single:
        raise IRError(f"{where}: inputs {sorted(counts)} have a leading frames axis but "
                      f"{single} do not; give every input the same frames axis (or one frame "
                      "each)", node=single[0])
    if len(set(counts.values())) > 1:
        raise IRError(f"{where}: the inputs' frame counts differ ({counts}); give every input "
                      "the same number of frames", node=min(counts, key=counts.get))
    (count,) = set(counts.values())
    if count == 0:
        raise IRError(f"{where}: the inputs have a frames axis of length 0; give at least one "
                      "frame", node=min(counts))
    return count


def frame(inputs: Mapping[str, object], index: int) -> dict[str, np.ndarray]:
    """Frame ``index`` of every framed input (views, no copies)."""
    return {k: np.asarray(v)[index] for k, v in inputs.items()}


def stack_frames(results: Sequence[Mapping[str, np.ndarray]]) -> dict[str, np.ndarray]:
    """Per key, the frames' arrays stacked along a new leading axis (keys of the first)."""
    return {k: np.stack([np.asarray(r[k]) for r in results]) for k in results[0]}
