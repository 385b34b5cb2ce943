"""Accuracy-vs-resources sweeps: a grid of compile options × frames, run on Dask.

* :mod:`~compiler.sweep.spec` — the sweep file (:func:`load_spec`, :class:`SweepSpec`);
* :mod:`~compiler.sweep.frames` — frame sources (scene simulator, ``.npy`` folder);
* :mod:`~compiler.sweep.metrics` — accuracy metrics (:func:`default_metrics`);
* :mod:`~compiler.sweep.cost` — neurons, synapses, cores, steps, spikes of a cell;
* :mod:`~compiler.sweep.tasks` — what a worker runs; :mod:`~compiler.sweep.run` —
  :func:`run_sweep` (resumable); :mod:`~compiler.sweep.executors` — in-process or Dask;
  :mod:`~compiler.sweep.results` — the results
  file and its summary; :mod:`~compiler.sweep.figures` — the plots;
* :mod:`~compiler.sweep.command` — ``radarsnn sweep``.

See ``docs/sweeps.md``.
"""

from compiler.sweep.metrics import Metric, MetricRegistry, default_metrics
from compiler.sweep.run import SweepResult, run_sweep
from compiler.sweep.spec import SweepSpec, load_spec

__all__ = ["Metric", "MetricRegistry", "SweepResult", "SweepSpec", "default_metrics",
           "load_spec", "run_sweep"]
