"""Cross-checks against the public bit-accurate models of Loihi (Lava, NengoLoihi).

:mod:`~backends.crosscheck.env` builds the Python 3.10 environment they need,
:mod:`~backends.crosscheck.chipnet` and :mod:`~backends.crosscheck.frames` are the
radarsnn-free half the workers load (registers and time line from the artifact alone),
:mod:`~backends.crosscheck.run` drives a worker and compares, :mod:`~radarsnn.cli.crosscheck`
is ``radarsnn crosscheck``.
"""
