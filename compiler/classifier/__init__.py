"""The radar object classifier: the float model of the ``classifier`` op and its training.

* :mod:`ir.classifier_forward.layers` — the layer stack as sparse matrices and neuron
  parameters (:func:`build_layer_plan`), shared by the float forward pass and the lowering;
* :mod:`ir.classifier_forward.forward` — the numpy forward pass (:func:`run_plan`,
  :func:`classify`), the reference semantics of the op;
* :mod:`ir.classifier_forward.weights` — loading and saving the ``.npz`` weights;
* :mod:`compiler.classifier.default` — the shipped stack, dataset and training settings;
* :mod:`compiler.classifier.train` — the PyTorch models (optional extra ``train``);
* :mod:`compiler.classifier.fit` — their training loop with the activity regulariser.
"""

from ir.classifier_forward.forward import ForwardResult, classify, run_plan
from ir.classifier_forward.layers import LayerPlan, build_layer_plan
from ir.classifier_forward.weights import load_weights, save_weights

__all__ = [
    "ForwardResult",
    "LayerPlan",
    "build_layer_plan",
    "classify",
    "load_weights",
    "run_plan",
    "save_weights",
]
