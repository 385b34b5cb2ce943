"""Blocks of a population (contiguous runs of neurons) and what each block needs from a core.

A population is cut into **blocks**, contiguous runs of its neurons in memory
(row-major) order, or of a given ascending list of its neurons (one instance of
a time-multiplexed stage).  :class:`Demand` holds the measured amounts of every
block (see :mod:`compiler.hardware.demand` for the model).

Examples
--------
>>> b = Blocks.uniform("y", 7, 2)
>>> b.edges.tolist(), b.block_of(np.arange(7)).tolist()
([0, 3, 7], [0, 0, 0, 1, 1, 1, 1])
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

__all__ = ["Blocks", "Demand"]


@dataclass(frozen=True, eq=False)
class Blocks:
    """Contiguous blocks of one population: block ``i`` holds neurons ``edges[i] … edges[i+1]-1``.

    With ``neurons`` (ascending flat indices, e.g. one instance of a time-multiplexed
    stage) the blocks cut that list instead: block ``i`` holds
    ``neurons[edges[i]:edges[i+1]]`` and the other neurons are in no block.

    Examples
    --------
    >>> b = Blocks.uniform("y", 10, 3)
    >>> b.edges.tolist(), b.sizes.tolist(), b.block_of(np.array([0, 4, 9])).tolist()
    ([0, 3, 6, 10], [3, 3, 4], [0, 1, 2])
    >>> i = Blocks.uniform("y", 4, 2, neurons=np.array([0, 1, 6, 7]))
    >>> i.block_of_neuron(np.array([1, 6, 3])).tolist(), i.flat(np.array([2, 3])).tolist()
    ([0, 1, -1], [6, 7])
    """

    population: str
    edges: np.ndarray
    neurons: np.ndarray | None = None

    @classmethod
    def uniform(cls, population: str, size: int, n_blocks: int, *,
                neurons: np.ndarray | None = None) -> Blocks:
        """``n_blocks`` blocks whose sizes differ by at most one: ``edges[i] = floor(i·size/n)``.

        ``size`` is ``len(neurons)`` when ``neurons`` is given.
        """
        return cls(population, (np.arange(n_blocks + 1, dtype=np.int64) * size) // n_blocks,
                   neurons)

    @property
    def n_neurons(self) -> int:
        """Neurons covered by the blocks."""
        return int(self.edges[-1])

    def flat(self, positions: np.ndarray) -> np.ndarray:
        """The flat neuron index of each position ``0 … n_neurons-1`` in block order."""
        return positions if self.neurons is None else self.neurons[positions]

    def block_of_neuron(self, flat: np.ndarray) -> np.ndarray:
        """The block of each flat neuron index; ``-1`` for a neuron in no block."""
        if self.neurons is None:
            return self.block_of(flat)
        pos = np.minimum(np.searchsorted(self.neurons, flat), len(self.neurons) - 1)
        return np.where(self.neurons[pos] == flat, self.block_of(pos), -1)

    @property
    def n_blocks(self) -> int:
        """Number of blocks."""
        return len(self.edges) - 1

    @property
    def sizes(self) -> np.ndarray:
        """Neurons per block."""
        return np.diff(self.edges)

    def block_of(self, positions: np.ndarray) -> np.ndarray:
        """The block index of each position (the flat index when ``neurons`` is ``None``)."""
        return np.searchsorted(self.edges, positions, side="right") - 1


class Demand:
    """What each block of one population needs (see :mod:`compiler.hardware.demand`).

    The fan-in lines may be counted on first use: with ``pending``, a function
    returning ``(fan_in, reach)``, the ``input_axons`` column of ``amounts`` and
    ``reach`` are filled in when either is first read.

    Attributes
    ----------
    blocks : Blocks
        The blocks measured.
    amounts : ndarray of int64, shape (n_blocks, 4)
        ``neurons, input_axons, output_axons, synapse_bits`` per block.
    entries : ndarray of int64
        Stored synapse entries per block.
    reach : dict of str to (ndarray, ndarray)
        Per source population: the distinct ``(block, source flat index)`` pairs.

    Examples
    --------
    >>> b = Blocks.uniform("y", 4, 2)
    >>> d = Demand(b, np.array([[2, 0, 0, 8], [2, 0, 0, 8]]), np.array([1, 1]), {},
    ...            pending=lambda: (np.array([3, 5]), {"x": (np.array([0]), np.array([7]))}))
    >>> d.counted, d.amounts_counted[:, 1].tolist()
    (False, [0, 0])
    >>> d.amounts[:, 1].tolist(), d.counted, list(d.reach)
    ([3, 5], True, ['x'])
    """

    def __init__(self, blocks: Blocks, amounts: np.ndarray, entries: np.ndarray,
                 reach: dict[str, tuple[np.ndarray, np.ndarray]], *,
                 pending: Callable[[], tuple[np.ndarray, dict]] | None = None) -> None:
        self.blocks, self.entries = blocks, entries
        self._amounts, self._reach, self._pending = amounts, reach, pending

    @property
    def counted(self) -> bool:
        """Whether the fan-in lines (and ``reach``) are known, not pending."""
        return self._pending is None

    @property
    def amounts_counted(self) -> np.ndarray:
        """``amounts`` as known now: a pending ``input_axons`` column reads 0."""
        return self._amounts

    @property
    def amounts(self) -> np.ndarray:
        """Per block ``neurons, input_axons, output_axons, synapse_bits`` (int64)."""
        self._count()
        return self._amounts

    @property
    def reach(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Per source population: the distinct ``(block, source flat index)`` pairs."""
        self._count()
        return self._reach

    def _count(self) -> None:
        if self._pending is not None:
            fan_in, self._reach = self._pending()
            self._amounts = self._amounts.copy()
            self._amounts[:, 1] = fan_in
            self._pending = None
