"""Benchmark scoring from Python: :func:`evaluate`, the call behind ``rgbt eval``."""

from __future__ import annotations

import os
from collections.abc import Mapping

from rgbt_toolkit.errors import InputError


def evaluate(benchmark: str, gt: str | os.PathLike, results: str | os.PathLike | Mapping[str, str | os.PathLike],
             *, prefix: str | None = None):
    """Score trackers' result folders on a benchmark with its own conventions (published numbers reproduced).

    Parameters
    ----------
    benchmark : str
        ``gtot``, ``rgbt234``, ``rgbt210``, ``lasher``, ``vot-rgbt`` or ``anti-uav``.
    gt : path
        The benchmark's ground-truth folder (see ``docs/evaluation.md``).
    results : path or mapping
        One tracker's result folder (named after the folder), or ``{tracker name: folder}``.
    prefix : str, optional
        One-pass benchmarks: result files are exactly ``<prefix><seq>.txt``.

    Returns
    -------
    rgbt_toolkit.evaluation.EvaluationReport
        ``trackers`` (name -> scores), ``to_dict()`` as plain data; ``print(report)`` shows ``rgbt eval``'s table.
    """
    from rgbt_toolkit.evaluation.api import evaluate as evaluate_folders

    if isinstance(results, Mapping):
        if not results:
            raise InputError("give at least one results folder")
        named = [f"{name}={os.fspath(folder)}" for name, folder in results.items()]
    elif isinstance(results, (str, os.PathLike)):
        named = [os.fspath(results)]
    else:
        raise InputError(f"results: a folder or a mapping of tracker name -> folder, not {type(results).__name__}")
    return evaluate_folders(benchmark, gt, named, prefix=prefix)
