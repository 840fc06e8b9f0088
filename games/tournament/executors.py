"""Where a tournament's games run: a local process pool, or a Dask cluster.

    with open_executor("local", jobs=2) as ex:
        for i, row in ex.run(play_match, games): ...

- ``local``: a ``spawn`` process pool on this machine, ``jobs`` games at a
  time (one PyBullet world per process; a worker is replaced every few
  games so a long tournament does not grow);
- ``dask``: Dask distributed (the ``tournament`` extra, ``pip install
  rll-bt[tournament]``): ``address`` is a running scheduler
  (``dask scheduler``, then ``dask worker tcp://HOST:PORT`` on each
  machine, with this project installed); without ``address`` a local
  cluster of ``jobs`` worker processes is started for the run.

Why Dask and not Ray (docs/tournaments.md): a game is one plain Python
call on plain data, which is what Dask's futures are; the ``distributed``
wheel is pure Python (its scheduler and workers are two commands that
start in about a second on loopback, no daemon, no object store, no
dashboard process), where Ray brings a native runtime of several hundred MB
that starts a GCS server, raylets and an object store per node.  Both would
run the same function; the project needs nothing Ray adds.

Games are deterministic for their seed, so whatever runs them gives the
same rows.  ``run`` yields ``(index, row)`` as games finish; a game whose
worker was lost yields a row with ``error``.
"""
from __future__ import annotations

import multiprocessing as mp
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

EXECUTORS = ("local", "dask")


class ExecutorUnavailable(RuntimeError):
    """The executor cannot be used here (extra not installed, scheduler not reachable)."""


class LocalExecutor:
    def __init__(self, jobs: int = 1):
        self.jobs = max(1, int(jobs))
        # a fresh process per game (bounded memory); not more games per worker: Python 3.11-3.13's
        # ProcessPoolExecutor stops for good once workers with max_tasks_per_child > 1 reach their limit
        # with games still queued (CPython gh-115634: 2 workers x 4 played 8 games of a 40-game
        # tournament, then waited forever)
        self.pool = ProcessPoolExecutor(self.jobs, mp_context=mp.get_context("spawn"), max_tasks_per_child=1)
        self.workers = self.jobs

    def run(self, fn: Callable[[dict], dict], items: list[dict]) -> Iterator[tuple[int, dict]]:
        futures = {self.pool.submit(fn, item): i for i, item in enumerate(items)}
        try:
            pending = set(futures)
            while pending:
                done, pending = wait(pending, return_when=FIRST_COMPLETED)
                for f in done:
                    yield futures[f], _result(f.result, items[futures[f]])
        finally:
            for f in futures:
                f.cancel()

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class DaskExecutor:
    def __init__(self, address: str | None = None, jobs: int = 1, timeout: float = 10.0):
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ExecutorUnavailable("--executor dask needs Dask distributed: pip install 'rll-bt[tournament]' "
                                      "(or pip install distributed)") from None
        self.cluster = None
        try:
            if address:
                self.client = Client(address if "://" in address else f"tcp://{address}", timeout=timeout)
            else:
                self.cluster = LocalCluster(n_workers=max(1, int(jobs)), threads_per_worker=1, processes=True,
                                            dashboard_address=None)
                self.client = Client(self.cluster)
        except (OSError, TimeoutError) as exc:
            if self.cluster is not None:
                self.cluster.close()
            raise ExecutorUnavailable(f"no Dask scheduler at {address}: {exc}") from None
        self.workers = len(self.client.scheduler_info().get("workers", {}))

    def run(self, fn: Callable[[dict], dict], items: list[dict]) -> Iterator[tuple[int, dict]]:
        from distributed import as_completed
        keys = [f"rll-bt-game-{i}-{item.get('seed')}-{abs(hash(repr(item))):x}" for i, item in enumerate(items)]
        futures = self.client.map(fn, items, key=keys, pure=False, retries=1)
        index = {f.key: i for i, f in enumerate(futures)}
        try:
            for f in as_completed(futures):
                i = index[f.key]
                yield i, _result(f.result, items[i])
        finally:
            self.client.cancel([f for f in futures if not f.done()])

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _result(get: Callable[[], dict], item: dict) -> dict:
    """The row a finished future holds, or an error row for a game its worker lost."""
    try:
        return get()
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:
        from .schedule import Match
        m = Match.from_dict(item)
        return {"key": m.key, "cyan": m.cyan, "magenta": m.magenta, "seed": m.seed,
                "error": f"the worker lost the game: {type(exc).__name__}: {exc}"}


def open_executor(kind: str, *, jobs: int = 1, address: str | None = None):
    """An executor of :data:`EXECUTORS` (``ExecutorUnavailable`` when it cannot run here)."""
    if kind == "local":
        if address:
            raise ValueError("--address names a cluster's scheduler: give --executor dask")
        return LocalExecutor(jobs)
    if kind == "dask":
        return DaskExecutor(address, jobs)
    raise ValueError(f"executor must be one of {', '.join(EXECUTORS)}, not {kind!r}")
