"""The usage error of the ``radarsnn`` command line (exit status 2).

A :class:`UsageError` says the command line itself is malformed — argparse's
complaints, and values whose *form* is wrong (``--motif dft`` instead of
``NODE_OR_OP=MOTIF``, ``--option headroom`` instead of ``KEY=VALUE``).  It is not a
:class:`~ir.errors.RadarSNNError`: those are runtime errors (exit status 1) about
what the command was given — a chain that does not verify, a file that cannot be
read, a program that does not fit.

Examples
--------
>>> from ir.errors import RadarSNNError
>>> isinstance(UsageError("--motif 'dft' is not NODE_OR_OP=MOTIF"), RadarSNNError)
False
"""

from __future__ import annotations

__all__ = ["UsageError"]


class UsageError(Exception):
    """A bad command line, reported as one ``error: …`` line with exit status 2."""
