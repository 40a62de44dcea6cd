"""Benchmark ground truth and challenge attributes, read from a benchmark's ground-truth folder.

``GT_DIR`` may be the benchmark root (``gt/RGBT234``, holding ``rgbt234_gt/`` and ``attr_txt/``) or the folder of
per-sequence ground truth itself (``gt/RGBT234/rgbt234_gt``); list and attribute files are looked up in both.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.evaluation.benchmarks import AttributeSource, OpeBenchmark
from rgbt_toolkit.evaluation.results import check_no_gaps
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.images import natural_key


@dataclass(frozen=True)
class SequenceTruth:
    """Ground truth of one sequence: one (N, 4) ``x, y, w, h`` array per modality (visible first)."""

    name: str
    boxes: tuple[np.ndarray, ...]

    @property
    def n_frames(self) -> int:
        return min(len(b) for b in self.boxes)


@dataclass
class GroundTruth:
    """A benchmark's ground truth: sequences in benchmark order, attribute membership, and what was skipped."""

    benchmark: OpeBenchmark
    sequences: dict[str, SequenceTruth]
    attributes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    warnings: list[str] = field(default_factory=list)
    source: Path | None = None


def _first_existing(folders: list[Path], names: tuple[str, ...]) -> Path | None:
    for name in names:
        for folder in folders:
            if (folder / name).is_file():
                return folder / name
    return None


def _read_names(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8-sig")
    return [line.strip() for line in text.replace(",", "\n").splitlines() if line.strip()]


def _sequence_root(gt_dir: Path, bench: OpeBenchmark) -> Path:
    """The folder holding per-sequence ground truth: a known sub-folder of ``gt_dir``, else ``gt_dir`` itself."""
    for sub in bench.sequence_roots:
        if sub != "." and (gt_dir / sub).is_dir():
            return gt_dir / sub
    return gt_dir


def load_groundtruth(gt_dir: str | os.PathLike, bench: OpeBenchmark) -> GroundTruth:
    """Read every sequence's ground truth (and attributes when present) for ``bench`` from ``gt_dir``.

    Raises
    ------
    MissingFileError
        ``gt_dir`` does not exist.
    InputError
        No sequence with ground truth in the benchmark's layout was found (wrong folder or wrong benchmark).
    """
    gt_dir = Path(gt_dir)
    if not gt_dir.is_dir():
        raise MissingFileError(f"{gt_dir}: no such ground-truth folder")
    root = _sequence_root(gt_dir, bench)
    aux = [gt_dir, root, root.parent]
    warnings: list[str] = []
    list_file = _first_existing(aux, bench.sequence_lists)
    if list_file is not None:
        names = _read_names(list_file)
    else:
        names = sorted({_name_from_layout(p, root, bench) for p in root.iterdir()} - {None}, key=natural_key)
    sequences: dict[str, SequenceTruth] = {}
    lacking = []
    for name in names:
        paths = [root / pattern.format(seq=name) for pattern in bench.gt_files]
        if not all(p.is_file() for p in paths):
            lacking.append(name)
            continue
        for path in paths:
            check_no_gaps(path)
        boxes = tuple(read_boxes(p, fmt=bench.gt_format) for p in paths)
        n_nan = max(int(np.isnan(b).any(axis=1).sum()) for b in boxes)
        if n_nan:
            warnings.append(f"{name}: {n_nan} ground-truth box(es) are NaN; those frames count as failed")
        if min(len(b) for b in boxes) == 0:
            raise FileFormatError(f"{paths[0]}: empty ground-truth file")
        if len({len(b) for b in boxes}) > 1:
            warnings.append(f"{name}: the modalities' ground truths differ in length "
                            f"({', '.join(str(len(b)) for b in boxes)}); scoring the common frames")
        sequences[name] = SequenceTruth(name, boxes)
    if not sequences:
        expected = " + ".join(bench.gt_files)
        raise InputError(f"{gt_dir}: no {bench.title} ground truth found (expected {expected} under it or under "
                         f"{'/'.join(s for s in bench.sequence_roots if s != '.')}); is this the right folder and "
                         f"--benchmark?")
    if lacking:
        shown = ", ".join(lacking[:5]) + (", ..." if len(lacking) > 5 else "")
        warnings.append(f"{len(lacking)} listed sequence(s) have no ground truth in {root} and are left out: {shown}")
    truth = GroundTruth(bench, sequences, warnings=warnings, source=gt_dir)
    if bench.attributes is not None:
        truth.attributes = load_attributes(aux, bench.attributes, list(sequences))
    return truth


def _name_from_layout(path: Path, root: Path, bench: OpeBenchmark) -> str | None:
    """Sequence name when ``path`` (a child of ``root``) holds the benchmark's first ground-truth file."""
    pattern = bench.gt_files[0]
    if pattern.startswith("{seq}/"):
        return path.name if path.is_dir() and (path / pattern[len("{seq}/"):]).is_file() else None
    suffix = pattern[len("{seq}"):]
    return path.name[: -len(suffix)] if path.is_file() and path.name.endswith(suffix) else None


def load_attributes(folders: list[Path], source: AttributeSource, sequences: list[str]) -> dict[str, tuple[str, ...]]:
    """Attribute name -> the sequences (of ``sequences``, in that order) that carry it; ``{}`` when absent."""
    base = next((f / source.folder for f in folders if (f / source.folder).is_dir()), None)
    if base is None:
        return {}
    members: dict[str, list[str]] = {}
    if source.kind == "table":
        order_path = base / source.order_file
        if not order_path.is_file():
            return {}
        order = _read_names(order_path)
        for attr_file in sorted(base.glob("*.txt")):
            if attr_file.name == source.order_file:
                continue
            flags = read_flags(attr_file)
            if len(flags) != len(order):
                raise FileFormatError(f"{attr_file}: {len(flags)} flags for {len(order)} sequences in {order_path}")
            on = {seq for seq, flag in zip(order, flags) if flag}
            members[attr_file.stem] = [s for s in sequences if s in on]
    elif source.kind == "per_sequence":
        names_path = next((f / source.order_file for f in folders if (f / source.order_file).is_file()), None)
        names = _read_names(names_path) if names_path is not None else list(source.names)
        members = {n: [] for n in names}
        for seq in sequences:
            path = base / f"{seq}.txt"
            if not path.is_file():
                continue
            flags = read_flags(path)
            if len(flags) != len(names):
                raise FileFormatError(f"{path}: {len(flags)} attribute flags, expected {len(names)} ({', '.join(names)})")
            for n, flag in zip(names, flags):
                if flag:
                    members[n].append(seq)
    else:  # pragma: no cover - guarded by the benchmark table
        raise InputError(f"unknown attribute source kind '{source.kind}'")
    return {k: tuple(v) for k, v in members.items() if v}


def read_flags(path: Path) -> list[bool]:
    """0/1 flags separated by commas, spaces or newlines."""
    tokens = path.read_text(encoding="utf-8-sig").replace(",", " ").split()
    try:
        return [float(t) != 0 for t in tokens]
    except ValueError:
        raise FileFormatError(f"{path}: attribute flags must be 0 or 1") from None
