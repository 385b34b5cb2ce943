"""Accuracy-vs-resources sweeps: a grid of compile options × frames, run on Dask.

* :mod:`~radarsnn.sweep.spec` — the sweep file (:func:`load_spec`, :class:`SweepSpec`);
  :mod:`~radarsnn.sweep.sections` — its frames, metrics and figures sections;
  :mod:`~radarsnn.sweep.cells` — the cell ids;
* :mod:`~radarsnn.sweep.frames` — frame sources (scene simulator, ``.npy`` folder);
* :mod:`~radarsnn.sweep.metrics` — accuracy metrics (:func:`default_metrics`);
* :mod:`~radarsnn.sweep.cost` — neurons, synapses, cores, steps, spikes of a cell;
* :mod:`~radarsnn.sweep.tasks` — what a worker runs; :mod:`~radarsnn.sweep.run` —
  :func:`run_sweep` (resumable); :mod:`~radarsnn.sweep.executors` — in-process or Dask;
  :mod:`~radarsnn.sweep.results` — the results
  file and its summary; :mod:`~radarsnn.sweep.figures` — the plots;
* :mod:`~radarsnn.cli.sweep` — ``radarsnn sweep``.

See ``docs/sweeps.md``.
"""

from radarsnn.sweep.metrics import Metric, MetricRegistry, default_metrics
from radarsnn.sweep.run import SweepResult, run_sweep
from radarsnn.sweep.spec import SweepSpec, load_spec

__all__ = ["Metric", "MetricRegistry", "SweepResult", "SweepSpec", "default_metrics",
           "load_spec", "run_sweep"]
