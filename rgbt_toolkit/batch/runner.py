"""Run a task over items with an executor: skip finished items, retry failures once, record, summarise.

Failures the library raised on purpose (:class:`~rgbt_toolkit.errors.RgbtError`: a corrupt file, a bad box) are not
retried: the same input fails the same way.

The runner owns the batch's bookkeeping and nothing else: where items run is the executor's business, what they do is
the task's. A failed item never stops the others; after the first pass the failures are run again (``retries``
times), and those that still fail are reported with their error. ``KeyboardInterrupt`` stops the batch at once; the
manifest then holds every item finished so far, so re-running the same command does only what is missing.
"""

from __future__ import annotations

import glob
import re
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rgbt_toolkit._atomic import check_folder, write_text_atomic
from rgbt_toolkit.batch.executors import Executor
from rgbt_toolkit.batch.items import Item
from rgbt_toolkit.batch.manifest import Manifest, input_stamps
from rgbt_toolkit.errors import InputError

DONE, SKIPPED, FAILED = "done", "skipped", "failed"


@dataclass(frozen=True)
class ItemReport:
    """Final state of one item: done now, skipped (finished by an earlier run) or failed after its retries."""

    key: str
    status: str
    attempts: int = 0
    seconds: float = 0.0  # of the last attempt
    error: str | None = None
    details: str | None = None  # traceback of the last failure
    outputs: tuple[str, ...] = ()
    cpu_seconds: float = 0.0  # CPU time of the last attempt (all threads of the process that ran it)
    warnings: tuple[str, ...] = ()  # raised by the last attempt, one line each


@dataclass
class BatchReport:
    """Everything a batch did, in the items' order."""

    items: list[ItemReport]
    executor: str
    seconds: float
    manifest: Path
    extra: dict[str, Any] = field(default_factory=dict)

    def count(self, status: str) -> int:
        return sum(1 for r in self.items if r.status == status)

    @property
    def failed(self) -> list[ItemReport]:
        return [r for r in self.items if r.status == FAILED]

    @property
    def ok(self) -> bool:
        return not self.failed


def conflicting_outputs(job: Any, items: Sequence[Item], manifest: Manifest) -> list[Path]:
    """Outputs the batch would overwrite that no earlier run of this same job wrote.

    Existing files are conflicts when this job never ran with this manifest (the folder holds someone else's
    results) or when the manifest says another job (another tracker or preset) made them. Outputs of this job's items
    that were cut off mid-way are not conflicts: redoing them is what resuming means.
    """
    signature = job.signature()
    conflicts = []
    for item in items:
        if manifest.is_done(item.key, signature, input_stamps(item.paths)):
            continue
        entry = manifest.get(item.key)
        ours = entry.job == signature if entry is not None else signature in manifest.jobs
        if not ours:
            conflicts.extend(p for p in job.expected_outputs(item) if p.exists())
    return conflicts


def run_batch(
    task: Callable[[Item], Any],
    items: Sequence[Item],
    executor: Executor,
    manifest: Manifest,
    signature: str,
    retries: int = 1,
    on_item: Callable[[ItemReport], None] | None = None,
) -> BatchReport:
    """Run ``task`` over the items not yet finished, record each success in ``manifest``, return the report.

    Parameters
    ----------
    task : callable
        Top-level (picklable) function of one :class:`Item`, returning the list of paths it wrote.
    items : sequence of Item
        All items of the batch; those the manifest records as finished by ``signature`` are skipped.
    executor : Executor
        Where the items run.
    manifest : Manifest
        The resumable record, appended as items finish.
    signature : str
        The job's identity (task and settings); items finished by another job are redone.
    retries : int
        How many more times a failed item is run (after all others had their first try).
    on_item : callable, optional
        Called with each item's final :class:`ItemReport` as it is known (skipped ones first): progress bars.
    """
    if retries < 0:
        raise InputError(f"retries must be 0 or more, got {retries}")
    keys = [item.key for item in items]
    if len(set(keys)) != len(keys):
        raise InputError("batch items must have unique keys")
    start = time.perf_counter()
    reports: dict[str, ItemReport] = {}
    todo = []
    stamps = {item.key: input_stamps(item.paths) for item in items}  # before the items run
    for item in items:
        if manifest.is_done(item.key, signature, stamps[item.key]):
            entry = manifest.get(item.key)
            reports[item.key] = ItemReport(item.key, SKIPPED, 0, entry.seconds, outputs=entry.outputs)
            if on_item:
                on_item(reports[item.key])
        else:
            todo.append(item)
    attempts = {item.key: 0 for item in todo}
    while todo:  # each round adds at least one attempt to every item in it, so this ends after retries + 1 rounds
        failed_now = []
        for item, outcome in executor.map(task, todo):
            attempts[item.key] += outcome.attempts
            if outcome.ok:
                outputs = tuple(str(p) for p in (outcome.value or ()))
                manifest.record(item.key, signature, outputs, outcome.seconds, stamps[item.key])
                report = ItemReport(item.key, DONE, attempts[item.key], outcome.seconds, outputs=outputs,
                                    cpu_seconds=outcome.cpu_seconds, warnings=outcome.warnings)
            elif attempts[item.key] <= retries and not outcome.final:
                failed_now.append(item)
                continue
            else:
                report = ItemReport(item.key, FAILED, attempts[item.key], outcome.seconds, outcome.error,
                                    outcome.details, cpu_seconds=outcome.cpu_seconds, warnings=outcome.warnings)
            reports[item.key] = report
            if on_item:
                on_item(report)
        order = {key: i for i, key in enumerate(keys)}
        todo = sorted(failed_now, key=lambda it: order[it.key])
    return BatchReport([reports[key] for key in keys], executor.describe(), time.perf_counter() - start,
                       manifest.path)


def summary_table(report: BatchReport, all_items: bool | None = None, width: int = 70) -> str:
    """Plain-text summary: one row per item (or per failed item for long batches), then the totals.

    ``all_items`` None lists every item up to 40 of them, and only the failed ones beyond that.
    """
    if all_items is None:
        all_items = len(report.items) <= 40
    rows = [r for r in report.items if all_items or r.status == FAILED]
    lines = []
    if rows:
        name_w = max(4, *(len(r.key) for r in rows))
        lines.append(f"{'item':<{name_w}}  {'status':<7}  {'tries':>5}  {'seconds':>8}  error")
        for r in rows:
            error = (r.error or "")[:width]
            seconds = f"{r.seconds:8.2f}" if r.status != SKIPPED else f"{'-':>8}"
            lines.append(f"{r.key:<{name_w}}  {r.status:<7}  {r.attempts:>5}  {seconds}  {error}".rstrip())
    done, skipped, failed = report.count(DONE), report.count(SKIPPED), report.count(FAILED)
    rate = done / report.seconds if report.seconds > 0 else 0.0
    lines.append(f"{done} done, {skipped} skipped (finished before), {failed} failed; {report.seconds:.1f} s on "
                 f"{report.executor}, {rate:.2f} items/s")
    return "\n".join(lines)


def write_error_log(report: BatchReport, path: str | Path) -> Path | None:
    """Write the tracebacks of the failed items to ``path`` (atomically); None when nothing failed."""
    if report.ok:
        return None
    parts = [f"== {r.key} ({r.attempts} {'try' if r.attempts == 1 else 'tries'}): {r.error}\n{r.details or ''}"
             for r in report.failed]
    write_text_atomic(path, "\n".join(parts))
    return Path(path)


def check_outputs(job: Any, items: Sequence[Item], manifest_path: str | Path | None = None,
                  overwrite: bool = False) -> Manifest:
    """Open the job's manifest (default ``<out_dir>/.rgbt-batch.jsonl``) and refuse outputs it must not overwrite.

    Raises
    ------
    InputError
        Unless ``overwrite``: outputs exist that this job did not write (see :func:`conflicting_outputs`).
    """
    from rgbt_toolkit.batch.manifest import MANIFEST_NAME

    check_folder(job.out_dir, "outputs")
    if manifest_path is not None:
        check_folder(Path(manifest_path).parent, "manifest")
    manifest = Manifest(manifest_path if manifest_path is not None else Path(job.out_dir) / MANIFEST_NAME)
    if not overwrite:
        conflicts = conflicting_outputs(job, items, manifest)
        if conflicts:
            more = f" and {len(conflicts) - 1} more" if len(conflicts) > 1 else ""
            raise InputError(f"{conflicts[0]}{more} already exist and were not written by this job (see "
                             f"{manifest.path.name}); choose another output folder or pass --overwrite")
    return manifest


def remove_stale_temporaries(job: Any, items: Sequence[Item]) -> list[Path]:
    """Delete the hidden temporary files (``.<stem>.<8 random chars><suffix>``, see :func:`atomic_path`) that workers
    killed mid-write left beside the job's outputs; return what was deleted.

    A worker stopped by Ctrl-C or a crash never reaches the clean-up of its temporary file, and nothing else would
    ever remove it: a re-run writes new ones under other random names.
    """
    removed = []
    for item in items:
        for target in job.expected_outputs(item):
            target = Path(target)
            if not target.parent.is_dir():
                continue
            pattern = re.compile(rf"\.{re.escape(target.stem)}\.[a-z0-9_]{{8}}{re.escape(target.suffix)}")
            for path in target.parent.glob(f".{glob.escape(target.stem)}.*"):
                if pattern.fullmatch(path.name) and path.is_file():
                    path.unlink(missing_ok=True)
                    removed.append(path)
    return removed


def run_job(
    task_fn: Callable[..., Any],
    job: Any,
    items: Sequence[Item],
    executor: Executor,
    manifest_path: str | Path | None = None,
    overwrite: bool = False,
    retries: int = 1,
    on_item: Callable[[ItemReport], None] | None = None,
) -> BatchReport:
    """The whole of a batch command: bind the job, check for outputs it must not overwrite, run, log failures.

    ``task_fn(item, job)`` is a top-level task of :mod:`rgbt_toolkit.batch.tasks`; ``job`` has ``out_dir``,
    ``signature()`` and ``expected_outputs(item)``. The manifest defaults to ``<out_dir>/.rgbt-batch.jsonl``; the
    tracebacks of failed items go to ``<manifest stem>.errors.log`` (``report.extra["error_log"]``).
    """
    from functools import partial

    manifest = check_outputs(job, items, manifest_path, overwrite)
    remove_stale_temporaries(job, items)
    if any(not manifest.is_done(item.key, job.signature(), input_stamps(item.paths)) for item in items):
        manifest.record_start(job.signature())
    report = run_batch(partial(task_fn, job=job), items, executor, manifest, job.signature(), retries, on_item)
    log = write_error_log(report, manifest.path.with_suffix(".errors.log"))
    if log is not None:
        report.extra["error_log"] = log
    return report
