"""The radar object classifier: the float model of the ``classifier`` op and its training.

* :mod:`compiler.classifier.plan` — the layer stack as sparse matrices and neuron
  parameters (:func:`build_layer_plan`), shared by the float forward pass and the lowering;
* :mod:`compiler.classifier.forward` — the numpy forward pass (:func:`run_plan`,
  :func:`classify`), the reference semantics of the op;
* :mod:`compiler.classifier.weights` — loading and saving the ``.npz`` weights;
* :mod:`compiler.classifier.default` — the shipped stack, dataset and training settings;
* :mod:`compiler.classifier.train` — the PyTorch models (optional extra ``train``);
* :mod:`compiler.classifier.fit` — their training loop with the activity regulariser.
"""

from compiler.classifier.forward import ForwardResult, classify, run_plan
from compiler.classifier.plan import LayerPlan, build_layer_plan
from compiler.classifier.weights import load_weights, save_weights

__all__ = [
    "ForwardResult",
    "LayerPlan",
    "build_layer_plan",
    "classify",
    "load_weights",
    "run_plan",
    "save_weights",
]
