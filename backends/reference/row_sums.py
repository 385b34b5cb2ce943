r"""Row sums with ``np.add.reduceat``'s exact bits, without its per-run inner loops.

Arithmetic of the gathering path (the one both engines share for unweighted
events): the events of one batch row, in the order given, contribute their
weight rows ``w_1, …, w_m`` and the row's current is exactly what
``np.add.reduceat`` gives for that run of rows, ``w_1 + ((w_2 + w_3) + … + w_m)``
for ``m ≤ 8`` (numpy sums the tail of a reduction from its first element, in
order, below 8 addends) and ``np.add.reduceat`` itself for longer runs.
:func:`grouped_sums` evaluates it level by level (all rows' ``k``-th events at
once) instead of one tiny reduction per row and column.

Examples
--------
>>> import numpy as np
>>> hit, sums = grouped_sums(np.array([[1.0], [2.0], [4.0]]), np.array([0, 2, 1]),
...                          np.array([3, 3, 8]))
>>> hit.tolist(), sums.tolist()
([3, 8], [[5.0], [2.0]])
"""

from __future__ import annotations

import numpy as np

__all__ = ["SEQUENTIAL_MAX", "PAIRWISE_BLOCK", "distinct_rows", "grouped_sums", "long_run_sums",
           "n_runs", "run_starts"]

#: Runs of more addends than this are summed by ``np.add.reduceat`` itself (numpy's pairwise
#: summation is sequential only below 8 tail addends).
SEQUENTIAL_MAX = 8


def run_starts(rows: np.ndarray) -> np.ndarray:
    """Positions where a run of equal values in ``rows`` (sorted) begins.

    Examples
    --------
    >>> run_starts(np.array([2, 2, 5, 7, 7, 7])).tolist()
    [0, 2, 3]
    """
    new = np.empty(rows.size, bool)
    new[:1] = True
    np.not_equal(rows[1:], rows[:-1], out=new[1:])
    return new.nonzero()[0]


def distinct_rows(rows: np.ndarray, n_rows: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(rows, return_inverse=True)`` for ints in ``[0, n_rows)``, linear when dense.

    When ``rows`` holds at least an eighth as many entries as there are rows, a
    presence mask and its running count replace the sort (``O(rows + n_rows)``
    instead of ``O(rows log rows)``: the closed form delivers every frame's
    events in one call); otherwise ``np.unique``.  Both give the same arrays.

    Examples
    --------
    >>> hit, local = distinct_rows(np.array([5, 1, 5, 3]), n_rows=6)
    >>> hit.tolist(), local.tolist()
    ([1, 3, 5], [2, 0, 2, 1])
    """
    if rows.size * 8 < n_rows:
        hit, local = np.unique(rows, return_inverse=True)
        return hit, local.ravel()
    present = np.zeros(n_rows, bool)
    present[rows] = True
    position = np.cumsum(present, dtype=np.int64)
    position -= 1
    return np.flatnonzero(present), position[rows]


def n_runs(rows: np.ndarray) -> int:
    """Number of runs of equal values in ``rows`` (sorted)."""
    return int(np.count_nonzero(rows[1:] != rows[:-1])) + 1 if rows.size else 0


def grouped_sums(
    table: np.ndarray, index: np.ndarray, rows: np.ndarray, scale: np.ndarray | None = None,
    workspace: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Sum the table rows ``table[index[i]]`` (times ``scale[i]``) over each run of equal ``rows``.

    Bit for bit what ``np.add.reduceat(table[index] * scale[:, None], run starts,
    axis=0)`` returns, without its per-run, per-column inner loops: a run of
    ``m ≤ 8`` addends ``w_1 … w_m`` is ``w_1 + (((w_2 + w_3) + w_4) + …)``
    (numpy's reduction starts from the first element and adds the tail in order
    below 8 tail addends); longer runs go through ``np.add.reduceat``.  The run
    heads ``w_1`` are gathered in run order; the tails are summed level by level
    (the ``j``-th addend of every run at once, runs ordered by decreasing length
    so that each level is one contiguous slice) and added to their heads.

    Parameters
    ----------
    table : ndarray
        ``(n_table, n_out)`` rows to gather (float64 or int64).
    index : ndarray of int
        Table row per addend.
    rows : ndarray of int
        Output row per addend, sorted ascending (equal values form a run).
    scale : ndarray, optional
        Factor per addend (of the table's dtype).
    workspace : ndarray, optional
        A ``(≥ rows.size, n_out)`` array of the table's dtype to gather into
        (reused across calls: fresh large arrays cost page faults); ``sums`` is
        then a view of it.

    Returns
    -------
    hit : ndarray
        The distinct ``rows``, ascending.
    sums : ndarray
        ``(hit.size, n_out)`` sums.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.array([[1.0, 2.0], [10.0, 20.0], [100.0, 200.0]])
    >>> hit, sums = grouped_sums(t, np.array([0, 1, 2, 2]), np.array([3, 5, 5, 5]))
    >>> hit.tolist(), sums.tolist()
    ([3, 5], [[1.0, 2.0], [210.0, 420.0]])
    >>> r = np.random.default_rng(0).standard_normal((12, 3))
    >>> rows = np.repeat([0, 1, 2], [1, 5, 6])
    >>> bool(np.all(grouped_sums(r, np.arange(12), rows)[1]
    ...             == np.add.reduceat(r, [0, 1, 6], axis=0)))
    True
    """
    def gather(at: np.ndarray, offset: int | None = None) -> np.ndarray:
        """``table[index[at]] * scale[at]``, into the workspace from ``offset`` if given."""
        got = np.take(table, index[at], axis=0, out=None if workspace is None or offset is None
                      else workspace[offset:offset + at.size])
        if scale is not None:
            np.multiply(got, scale[at][:, None], out=got)
        return got

    starts = run_starts(rows) if rows.size else rows
    sums = gather(starts, 0)  # the run heads
    if starts.size == rows.size:  # one addend per run
        return rows, sums
    counts = np.empty_like(starts)
    counts[:-1] = starts[1:] - starts[:-1]
    counts[-1] = rows.size - starts[-1]
    multi = (counts > 1).nonzero()[0]
    order = np.argsort(-counts[multi], kind="stable")  # longest runs first
    owner = multi[order]  # the run (index into sums) of each tail
    length, first = counts[owner], starts[owner]
    depth = min(int(length[0]), SEQUENTIAL_MAX)
    level = np.arange(1, depth)
    # n_at[j - 1]: runs with more than j addends; tail addends taken level by level
    n_at = np.count_nonzero(length[None, :] > level[:, None], axis=1)
    tails = gather((first[:, None] + level).T[level[:, None] < length[None, :]], starts.size)
    ends = np.cumsum(n_at)
    tail = tails[:n_at[0]]
    for j in range(1, depth - 1):
        tail[:n_at[j]] += tails[ends[j - 1]:ends[j]]
    sums[owner] += tail
    deep = int(np.count_nonzero(length > SEQUENTIAL_MAX))
    if deep:  # long runs: numpy's own pairwise order
        sums[owner[:deep]] = long_run_sums(gather, first[:deep], length[:deep])
    return rows[starts], sums


#: Tail addends numpy's pairwise sum adds without splitting (its ``PW_BLOCKSIZE``).
PAIRWISE_BLOCK = 128


def long_run_sums(gather, first: np.ndarray, length: np.ndarray) -> np.ndarray:
    r"""The sums of runs of more than :data:`SEQUENTIAL_MAX` addends, bit for bit as
    ``np.add.reduceat`` adds them, vectorised over the runs.

    ``gather(at)`` returns the addend rows at positions ``at``; run ``i`` holds the
    addends ``first[i] … first[i] + length[i] − 1``.  numpy adds a run's head ``w_1`` to
    the pairwise sum of its tail of ``n ≥ 8`` addends: eight partial sums
    ``r_j = t_j + t_{j+8} + t_{j+16} + …`` over the whole blocks of eight,
    ``((r_0 + r_1) + (r_2 + r_3)) + ((r_4 + r_5) + (r_6 + r_7))``, then the ``n mod 8`` last
    addends one by one.  Each step is done for every run at once (runs needing it).  A
    tail over :data:`PAIRWISE_BLOCK` (numpy then splits it recursively) goes through
    ``np.add.reduceat`` itself.

    Examples
    --------
    >>> import numpy as np
    >>> w = np.random.default_rng(1).standard_normal((40, 3))
    >>> first, length = np.array([0, 12]), np.array([12, 28])
    >>> ref = np.add.reduceat(w, [0, 12], axis=0)
    >>> bool(np.array_equal(long_run_sums(lambda at: w[at], first, length), ref))
    True
    """
    n = length - 1
    if int(n.max()) > PAIRWISE_BLOCK:
        begin = np.cumsum(length) - length
        run = np.repeat(first - begin, length) + np.arange(int(length.sum()))
        return np.add.reduceat(gather(run), begin, axis=0)
    base = first + 1
    eight = np.arange(8)
    whole = n - n % 8
    part = gather((base[:, None] + eight).ravel()).reshape(first.size, 8, -1)
    for block in range(1, int(whole.max()) // 8):
        more = np.flatnonzero(whole > 8 * block)
        part[more] += gather((base[more, None] + 8 * block + eight).ravel()).reshape(
            more.size, 8, -1)
    r = [part[:, j] for j in range(8)]
    out = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    rest = n % 8
    for q in range(int(rest.max())):
        more = np.flatnonzero(rest > q)
        out[more] += gather(base[more] + whole[more] + q)
    return gather(first) + out
