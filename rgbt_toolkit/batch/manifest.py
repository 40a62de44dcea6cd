"""The resumable record of a batch: one JSON line per finished item.

A line is appended (``O_APPEND``, one ``write`` call, then ``fsync``) only after the item's outputs have been
renamed into place, so a run killed at any moment leaves a manifest naming only items whose outputs are complete.
A line cut short by the kill has no newline and is ignored on reading. Each line carries the job's signature (task
and its settings): re-running the same job skips the items recorded, a different job (another preset, say) redoes
them. An item whose recorded outputs were deleted since is redone too. A ``start`` line notes each job that began
writing here, so outputs an interrupted item left behind are known to be that job's (and may be redone), while
outputs in a folder the job never wrote to are someone else's.
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from rgbt_toolkit.errors import FileFormatError

MANIFEST_NAME = ".rgbt-batch.jsonl"


@dataclass(frozen=True)
class ManifestEntry:
    """One finished item: its key, the job it was made by, its output files and how long it took."""

    key: str
    job: str
    outputs: tuple[str, ...] = ()
    seconds: float = 0.0
    finished: str = ""
    inputs: dict | None = None  # input file -> [size, mtime_ns] when the item ran; None: not recorded

    def inputs_match(self, inputs: dict | None) -> bool:
        """True unless both stamps are known and differ (an input file was replaced, grown or touched since)."""
        return inputs is None or self.inputs is None or self.inputs == inputs

    def outputs_exist(self) -> bool:
        return all(Path(p).exists() for p in self.outputs)


def input_stamps(paths: Iterable[str | os.PathLike]) -> dict[str, list[int]]:
    """Size and modification time (ns) of each input *file*, so a replaced input makes its item run again.

    Folders (sequence folders) are not stamped: their own time changes with unrelated files.
    """
    stamps = {}
    for path in paths:
        try:
            stat = os.stat(path)
        except OSError:
            continue
        if not os.path.isdir(path):
            stamps[str(path)] = [stat.st_size, stat.st_mtime_ns]
    return stamps


class Manifest:
    """Append-only JSON-lines record of finished items at ``path`` (created with its folder on first write)."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._entries: dict[str, ManifestEntry] = {}
        self.jobs: set[str] = set()  # signatures of the jobs that have run with this manifest
        self._load()

    def _load(self) -> None:
        if not self.path.exists():
            return
        if not self.path.is_file():
            raise FileFormatError(f"{self.path}: the batch manifest is not a file; remove it or choose --manifest")
        text = self.path.read_text(encoding="utf-8", errors="replace")
        lines = text.split("\n")
        # the last piece is '' after a final newline, or a line cut short by a kill: either way not a record
        for line in lines[:-1]:
            line = line.strip()
            if not line:
                continue
            try:
                record = json.loads(line)
                if "start" in record:
                    self.jobs.add(str(record["start"]))
                    continue
                stamps = record.get("inputs")
                entry = ManifestEntry(str(record["key"]), str(record["job"]), tuple(record.get("outputs", ())),
                                      float(record.get("seconds", 0.0)), str(record.get("finished", "")),
                                      {str(k): list(v) for k, v in stamps.items()} if isinstance(stamps, dict)
                                      else None)
            except (ValueError, KeyError, TypeError):
                continue  # a damaged line only costs redoing its item
            self._entries[entry.key] = entry

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, key: str) -> bool:
        return key in self._entries

    def get(self, key: str) -> ManifestEntry | None:
        return self._entries.get(key)

    def is_done(self, key: str, job: str, inputs: dict | None = None) -> bool:
        """True when ``key`` was finished by this same ``job`` from the same ``inputs`` (see :func:`input_stamps`)
        and its outputs are still there."""
        entry = self._entries.get(key)
        return entry is not None and entry.job == job and entry.inputs_match(inputs) and entry.outputs_exist()

    def record(self, key: str, job: str, outputs: tuple[str, ...] | list[str] = (), seconds: float = 0.0,
               inputs: dict | None = None) -> None:
        """Append the line for a finished item and flush it to disk."""
        entry = ManifestEntry(key, job, tuple(str(p) for p in outputs), round(float(seconds), 4),
                              time.strftime("%Y-%m-%dT%H:%M:%S%z"), inputs)
        record = {"key": entry.key, "job": entry.job, "outputs": list(entry.outputs), "seconds": entry.seconds,
                  "finished": entry.finished}
        if inputs is not None:
            record["inputs"] = inputs
        self._append(record)
        self._entries[key] = entry

    def record_start(self, job: str) -> None:
        """Note that ``job`` starts writing here, so its own half-finished outputs are later known as its own."""
        if job not in self.jobs:
            self._append({"start": job, "time": time.strftime("%Y-%m-%dT%H:%M:%S%z")})
            self.jobs.add(job)

    def _append(self, record: dict) -> None:
        line = json.dumps(record, ensure_ascii=False) + "\n"
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
        try:
            if os.fstat(fd).st_size and not self._ends_with_newline():
                line = "\n" + line  # close a line cut short by an earlier kill, so this one stays whole
            os.write(fd, line.encode("utf-8"))
            os.fsync(fd)
        finally:
            os.close(fd)

    def _ends_with_newline(self) -> bool:
        with open(self.path, "rb") as handle:
            handle.seek(-1, os.SEEK_END)
            return handle.read(1) == b"\n"
