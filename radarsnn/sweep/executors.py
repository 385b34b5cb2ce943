"""Where a sweep's tasks run: in this process, or on a Dask cluster.

Both executors have the same three methods: ``submit(fn, *args, key=)`` returns a
future (arguments that are futures are passed as their results),
``as_completed(futures)`` yields them as they finish, ``close()`` releases the
cluster.  :class:`SyncExecutor` computes lazily in submission order (tests,
debugging, ``--scheduler sync``); :class:`DaskExecutor` wraps
``distributed.Client`` (a ``LocalCluster`` of ``workers`` single-threaded
processes by default — Dask's nanny sets ``OMP_NUM_THREADS=1`` in them).

Examples
--------
>>> ex = SyncExecutor()
>>> a = ex.submit(lambda: 2)
>>> b = ex.submit(lambda x, y: x * y, a, 5)
>>> [f.result() for f in ex.as_completed([b, a])]
[10, 2]
"""

from __future__ import annotations

__all__ = ["SyncExecutor", "DaskExecutor"]


class _Lazy:
    """A future of the synchronous scheduler: computed (once) when its result is asked."""

    def __init__(self, fn, args):
        self._fn, self._args, self._done, self._value = fn, args, False, None

    def result(self):
        if not self._done:
            args = [a.result() if isinstance(a, _Lazy) else a for a in self._args]
            self._value, self._done, self._fn, self._args = self._fn(*args), True, None, None
        return self._value


class SyncExecutor:
    """Runs each task in this process when its result is first needed, in submission order."""

    def submit(self, fn, *args, key=None):
        """A future of ``fn(*args)`` (``key`` is ignored: nothing is shared by name)."""
        return _Lazy(fn, args)

    def as_completed(self, futures):
        """Compute and yield ``futures`` in the order given."""
        for f in futures:
            f.result()
            yield f

    def close(self):
        """Nothing to release."""


#: glibc's trim threshold for the LocalCluster's worker processes (bytes).
_MALLOC_TRIM_THRESHOLD = 1 << 30


class DaskExecutor:
    """A Dask client: of a new LocalCluster (``scheduler=None``) or of a running scheduler."""

    def __init__(self, scheduler: str | None, workers: int | None, processes: bool):
        from distributed import Client, LocalCluster

        self.cluster = None
        if scheduler is None:
            import dask

            # distributed's default (64 kB) makes glibc hand every freed large array back to
            # the OS, so each simulation step page-faults its buffers afresh: ~30 % of a
            # sweep's time went to the kernel (benchmarks/sweep_fig7.py)
            trim = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_":
                    _MALLOC_TRIM_THRESHOLD}
            with dask.config.set(trim):
                self.cluster = LocalCluster(n_workers=workers or 2, threads_per_worker=1,
                                            processes=processes, dashboard_address=":0")
            self.client = Client(self.cluster)
        else:
            self.client = Client(scheduler)

    def submit(self, fn, *args, key=None):
        """``client.submit`` under the Dask key ``key`` (futures in ``args`` are resolved)."""
        return self.client.submit(fn, *args, key=key, pure=False)

    def as_completed(self, futures):
        """``distributed.as_completed``: futures in the order they finish."""
        from distributed import as_completed

        return as_completed(futures)

    def close(self):
        """Close the client and the LocalCluster it started (running tasks are cancelled)."""
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()
