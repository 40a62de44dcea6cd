"""Batch jobs over folders and datasets, on this machine or a Dask cluster.

Items (sequence folders, video pairs, image pairs) are discovered by :mod:`~rgbt_toolkit.batch.items`, run by a
task of :mod:`~rgbt_toolkit.batch.tasks` on an executor of :mod:`~rgbt_toolkit.batch.executors` (in-process, a local
process pool, or Dask), and recorded in a resumable manifest (:mod:`~rgbt_toolkit.batch.manifest`) by the runner
(:mod:`~rgbt_toolkit.batch.runner`). This package imports nothing heavy: Dask, torch and the trackers are imported
only where an item needs them.
"""

from __future__ import annotations

import importlib

# Names resolved on first use, so that a pool worker importing the executor module (to unpickle its initialiser)
# loads no numpy before it has set its thread limits.
_EXPORTS = {
    "DaskExecutor": "dask_executor", "Executor": "executor_base", "Outcome": "executor_base",
    "InProcessExecutor": "executors", "ProcessPoolExecutor": "executors", "make_executor": "executors",
    "Discovery": "items", "Item": "items", "image_pair_items": "items", "track_items": "items",
    "Manifest": "manifest",
    "BatchReport": "runner", "ItemReport": "runner", "run_batch": "runner", "run_job": "runner",
    "summary_table": "runner",
}


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"rgbt_toolkit.batch.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module 'rgbt_toolkit.batch' has no attribute {name!r}")


__all__ = [
    "BatchReport",
    "DaskExecutor",
    "Discovery",
    "Executor",
    "InProcessExecutor",
    "Item",
    "ItemReport",
    "Manifest",
    "Outcome",
    "ProcessPoolExecutor",
    "image_pair_items",
    "make_executor",
    "run_batch",
    "run_job",
    "summary_table",
    "track_items",
]
