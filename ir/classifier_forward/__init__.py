"""The golden meaning of the ``classifier`` op: its LIF layer stack run in numpy.

The op (:class:`ir.ops.classify.Classifier`) declares a stack of spiking layers; its
reference semantics is that stack run step by step on float arrays — what
:func:`ir.evaluate` computes for a ``classifier`` node and what the compiled spiking
network is checked against.  It lives in the IR so the interpreter needs nothing of
the compiler (``tests/test_layers.py``):

* :mod:`ir.classifier_forward.layers` — the stack as sparse matrices and per-layer
  dynamics (:func:`build_layer_plan`), shared with the lowering
  (:mod:`compiler.lowering.classifier` turns the dynamics into neuron parameters);
* :mod:`ir.classifier_forward.forward` — the forward pass (:func:`run_plan`,
  :func:`classify`);
* :mod:`ir.classifier_forward.weights` — loading and saving the ``.npz`` weights.
"""

from ir.classifier_forward.forward import ForwardResult, classify, run_plan
from ir.classifier_forward.layers import LayerDynamics, LayerPlan, build_layer_plan
from ir.classifier_forward.weights import load_weights, save_weights

__all__ = ["ForwardResult", "LayerDynamics", "LayerPlan", "build_layer_plan", "classify",
           "load_weights", "run_plan", "save_weights"]
