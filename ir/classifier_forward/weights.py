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

from ir.errors import RadarConfigError
from ir.ops.classify import Classifier
from radar.readers import read_npz_arrays

__all__ = ["MAX_WEIGHT_BYTES", "load_weights", "save_weights"]


#: Most bytes a classifier's weights file may declare: 256 MiB (the shipped classifier's
#: ``examples/classifier/snn_default.npz`` is 23 KB).
MAX_WEIGHT_BYTES = 256 << 20


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
    try:  # every member's header checked before it is inflated (no pickle, no forged sizes)
        arrays = read_npz_arrays(file, max_bytes=MAX_WEIGHT_BYTES)
    except RadarConfigError as err:
        raise op.fail(node_id, f"cannot read weights {str(file)!r}: {err}; train them with "
                               "examples/train_classifier.py or fix 'weights'") from None
    return op.check_weights(node_id, tuple(input_shape[-2:]), arrays)


def save_weights(path: str | Path, arrays: Mapping[str, np.ndarray]) -> None:
    """Write weights as an uncompressed ``.npz`` of float32 arrays (sorted keys)."""
    np.savez(Path(path), **{k: np.asarray(arrays[k], dtype=np.float32) for k in sorted(arrays)})
