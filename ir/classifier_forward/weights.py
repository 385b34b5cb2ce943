"""Loading and saving the classifier's ``.npz`` weights (no pickle, keys checked).

Examples
--------
>>> import tempfile, pathlib
>>> from ir.ops.classify import Classifier, Integrator
>>> d = pathlib.Path(tempfile.mkdtemp())
>>> op = Classifier(num_classes=2, weights=str(d / "w.npz"), layers=(Integrator(units=2),))
>>> save_weights(d / "w.npz", {"layers.0.weight": np.eye(2, 4)})
>>> load_weights(op, (1, 2, 2))["layers.0.weight"].shape
(2, 4)
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ir.ops.classify import Classifier

__all__ = ["load_weights", "save_weights"]


def load_weights(op: Classifier, input_shape: tuple[int, ...], node_id: str = "classifier",
                 path: str | Path | None = None) -> dict[str, np.ndarray]:
    """Read and check the weights named by ``op.weights`` (or ``path``).

    Parameters
    ----------
    op : Classifier
        The op; its layers say which keys and shapes to expect.
    input_shape : tuple of int
        ``(..., H, W)``: the last two entries are the ROI size along ``op.map_axes``.
    node_id : str
        Named in errors.
    path : str or Path, optional
        Read this file instead of ``op.weights`` (relative paths: current directory).

    Returns
    -------
    dict of str to ndarray (float64)

    Raises
    ------
    IRError
        If the file is missing or unreadable, or its keys or shapes do not match.
    """
    file = Path(op.weights if path is None else path)
    try:
        with np.load(file, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (OSError, ValueError) as err:
        raise op.fail(node_id, f"cannot read weights {str(file)!r}: {err}; train them with "
                               "examples/train_classifier.py or fix 'weights'") from err
    return op.check_weights(node_id, tuple(input_shape[-2:]), arrays)


def save_weights(path: str | Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Write weights as an uncompressed ``.npz`` of float32 arrays (sorted keys)."""
    np.savez(Path(path), **{k: np.asarray(arrays[k], dtype=np.float32) for k in sorted(arrays)})
