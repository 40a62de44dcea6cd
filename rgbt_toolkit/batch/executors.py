"""Executors: where the per-item work of a batch runs, behind one small interface.

``Executor.map(fn, items)`` yields ``(item, Outcome)`` pairs as items finish, in any order. ``fn`` must be a
top-level (picklable) function of one item; errors inside it never escape ``map``: they come back as an
:class:`Outcome` with ``error`` set, so one bad item cannot stop the batch. ``KeyboardInterrupt`` is not caught.

* :class:`InProcessExecutor` runs items one by one in this process (debugging, profiling, tests).
* :class:`ProcessPoolExecutor` runs them on N local worker processes (the default). Each worker limits torch,
  OpenCV and BLAS to ``cores // N`` threads so N workers do not oversubscribe the cores.
* :class:`~rgbt_toolkit.batch.dask_executor.DaskExecutor` submits them to a Dask distributed cluster (an existing
  scheduler, or a local cluster it starts). Dask is an optional extra, imported only there.

Every executor runs ``fn`` through :func:`~rgbt_toolkit.batch.executor_base.call_item`, which sets the thread limits
once per process, times the call and turns an exception into text (exceptions of third-party code are not always
picklable). :func:`make_executor` picks the executor the CLI's options name.
"""

from __future__ import annotations

import collections
import itertools
import signal
from collections.abc import Callable
from typing import Any

from rgbt_toolkit.batch.executor_base import (  # re-exported: the executors' public names live here too
    THREAD_ENV_VARS, Executor, Outcome, call_item, cpu_count, limit_threads, threads_per_worker)
from rgbt_toolkit.errors import InputError

__all__ = ["THREAD_ENV_VARS", "Executor", "InProcessExecutor", "Outcome", "ProcessPoolExecutor", "call_item",
           "cpu_count", "limit_threads", "make_executor", "threads_per_worker"]


class InProcessExecutor(Executor):
    """Items one after another in this process: tracebacks, debuggers and profilers work as usual.

    ``threads`` given: :func:`rgbt_toolkit.runtime.set_threads` is called once before the first item (the process's
    environment is left alone); None leaves the caller's thread settings as they are.
    """

    name = "in-process"

    def __init__(self, threads: int | None = None) -> None:
        self.threads = threads
        self._threads_set = False

    def map(self, fn, items):
        if self.threads is not None and not self._threads_set:
            from rgbt_toolkit.runtime import set_threads

            set_threads(self.threads)
            self._threads_set = True
        for item in items:
            yield item, call_item(fn, item)


_started_queue = None  # in a pool worker: where it announces each item it starts


def _init_pool_worker(threads: int, started) -> None:
    global _started_queue
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle: it stops the workers itself
    _started_queue = started
    limit_threads(threads)


def _pool_call(fn: Callable[[Any], Any], item: Any, token: int) -> Outcome:
    if _started_queue is not None:
        _started_queue.put(token)  # SimpleQueue: written before the call, so it survives a crash inside it
    return call_item(fn, item)


_CRASH = ("BrokenProcessPool: the worker process died running this item (a crash in native code, out of memory, "
          "or os._exit)")


class ProcessPoolExecutor(Executor):
    """N local worker processes (spawned, so no state or threads are inherited from the parent).

    A worker that dies (a crash in native code, running out of memory, ``os._exit``) breaks a Python process pool
    and fails every unfinished item with it. Here each worker announces the items it starts, so after a break the
    items that were running are rerun one at a time on a fresh pool (which tells the culprit from its neighbours:
    only the culprit is reported) and the items still queued simply go on in the fresh pool.
    """

    name = "process pool"

    def __init__(self, workers: int | None = None, threads: int | None = None) -> None:
        workers = cpu_count() if workers is None else workers
        if workers < 1:
            raise InputError(f"--workers must be at least 1, got {workers}")
        self.workers = workers
        self.threads = threads_per_worker(workers) if threads is None else threads
        self._pool = None
        self._started = None
        self._tokens = itertools.count()

    def _get_pool(self):
        if self._pool is None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor as _Pool

            context = multiprocessing.get_context("spawn")
            self._started = context.SimpleQueue()  # a fresh one per pool: a dead worker may hold the old one's lock
            self._pool = _Pool(max_workers=self.workers, mp_context=context, initializer=_init_pool_worker,
                               initargs=(self.threads, self._started))
        return self._pool

    def _started_tokens(self) -> set[int]:
        tokens = set()
        while self._started is not None and not self._started.empty():
            tokens.add(self._started.get())
        return tokens

    def map(self, fn, items):
        from concurrent.futures import FIRST_COMPLETED, wait
        from concurrent.futures.process import BrokenProcessPool

        queue = collections.deque(items)
        window = 2 * self.workers  # items in flight: enough to keep every worker busy, few to cancel or redo
        while queue:
            pool = self._get_pool()
            futures, tokens, pending, broken, started = {}, {}, set(), [], set()
            try:
                while queue or pending:
                    while queue and not broken and len(pending) < window:
                        item, token = queue[0], next(self._tokens)
                        try:
                            future = pool.submit(_pool_call, fn, item, token)
                        except BrokenProcessPool:
                            break
                        queue.popleft()
                        futures[future], tokens[future] = item, token
                        pending.add(future)
                    if not pending:
                        break
                    done, pending = wait(pending, return_when=FIRST_COMPLETED)
                    started |= self._started_tokens()  # drained as we go: a full pipe would block the workers
                    for future in done:
                        try:
                            outcome = future.result()
                        except BrokenProcessPool:
                            broken.append(future)
                            continue
                        started.discard(tokens[future])
                        yield futures[future], outcome
            except (KeyboardInterrupt, SystemExit):
                # left queued for abort(): cancelling them first makes Python 3.11's pool thread fail on them
                # (InvalidStateError traceback) when it finds the terminated workers
                pending = set()
                raise
            finally:
                for future in pending:
                    future.cancel()
            if broken:
                started |= self._started_tokens()
                self._discard_pool()
                running = [f for f in broken if tokens[f] in started] or broken  # none announced: isolate all
                queue.extendleft(reversed([futures[f] for f in broken if f not in running]))
                for future in running:
                    yield futures[future], self._run_alone(fn, futures[future])

    def _run_alone(self, fn, item) -> Outcome:
        from concurrent.futures.process import BrokenProcessPool

        try:
            return self._get_pool().submit(_pool_call, fn, item, next(self._tokens)).result()
        except BrokenProcessPool:
            self._discard_pool()
            return Outcome(error=_CRASH, attempts=2)  # it crashed beside others, then alone: retried already

    def _discard_pool(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
            self._started = None

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
            self._started = None

    def abort(self) -> None:
        if self._pool is not None:
            # concurrent.futures has no public way to stop running calls before Python 3.14 (terminate_workers)
            processes = list(getattr(self._pool, "_processes", {}).values())
            for process in processes:
                process.terminate()
            for process in processes:  # dead before the caller removes the temporary files they were writing
                process.join(timeout=5)
            self._discard_pool()


def make_executor(workers: int | None = None, in_process: bool = False, scheduler: str | None = None,
                  dask_local: int | None = None, threads: int | None = None) -> Executor:
    """The executor the CLI options name: Dask when a scheduler or local cluster is given, else in-process or pool."""
    if scheduler is not None or dask_local is not None:
        if in_process:
            raise InputError("--in-process cannot be combined with --scheduler or --dask-local")
        from rgbt_toolkit.batch.dask_executor import DaskExecutor

        return DaskExecutor(scheduler, dask_local, threads)
    if in_process:
        return InProcessExecutor(threads_per_worker(1) if threads is None else threads)
    return ProcessPoolExecutor(workers, threads)
