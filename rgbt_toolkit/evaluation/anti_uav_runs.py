"""Anti-UAV folders: read a ground-truth folder of labelled sequences and a tracker's result folder, and score them.

Ground truth: ``GT_DIR/<seq>/IR_label.json`` for every sequence, plus ``GT_DIR/<seq>/RGB_label.json`` in the RGB-T
editions. Results: ``DIR/<seq>_IR.json`` or ``DIR/<seq>_IR.txt`` (``<seq>.json`` / ``<seq>.txt`` also count as IR,
as the Anti-UAV410 toolkit names them) and ``DIR/<seq>_RGB.*``, scored against ``RGB_label.json``.

Where the official code would be silently wrong this refuses with one line naming the file: a result whose frame
count differs from its label (the official ``zip`` scores the common frames and drops the rest), two result files
for one sequence, an RGB result without an RGB label. A sequence without a result scores 0 in every frame, with a
warning, as ``rgbt eval`` treats missing sequences on the other benchmarks.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.evaluation.anti_uav import AntiUavScores, failed_states, frame_states, sequence_score
from rgbt_toolkit.evaluation.benchmarks import AntiUavBenchmark
from rgbt_toolkit.io.anti_uav import ABSENT_HINT, TargetFrames, read_anti_uav_label, read_anti_uav_result
from rgbt_toolkit.io.images import natural_key


@dataclass
class AntiUavTruth:
    """Labels by modality and sequence (sequences in folder order), their files, and what was noticed on the way."""

    benchmark: AntiUavBenchmark
    labels: dict[str, dict[str, TargetFrames]]
    paths: dict[str, dict[str, Path]]
    warnings: list[str] = field(default_factory=list)

    @property
    def sequences(self) -> list[str]:
        return list(self.labels[self.benchmark.modalities[0]])


def load_anti_uav_groundtruth(gt_dir: str | os.PathLike, bench: AntiUavBenchmark) -> AntiUavTruth:
    """Read every sequence's labels from ``gt_dir`` (sub-folders holding a label file are sequences).

    Raises
    ------
    MissingFileError
        ``gt_dir`` does not exist, or a sequence has another modality's label but not ``IR_label.json``.
    InputError
        No sequence folder with a label file (wrong folder or wrong ``--benchmark``).
    FileFormatError
        A malformed label file (named in the message).
    """
    gt_dir = Path(gt_dir)
    if not gt_dir.is_dir():
        raise MissingFileError(f"{gt_dir}: no such ground-truth folder")
    first = bench.modalities[0]
    names = {m: bench.label_file.format(modality=m) for m in bench.modalities}
    folders = sorted((p for p in gt_dir.iterdir() if p.is_dir() and any((p / n).is_file() for n in names.values())),
                     key=lambda p: natural_key(p.name))
    if not folders:
        raise InputError(f"{gt_dir}: no {bench.title} ground truth found (expected <seq>/{names[first]} under it); "
                         f"is this the right folder and --benchmark?")
    labels: dict[str, dict[str, TargetFrames]] = {m: {} for m in bench.modalities}
    paths: dict[str, dict[str, Path]] = {m: {} for m in bench.modalities}
    warnings: list[str] = []
    for folder in folders:
        if not (folder / names[first]).is_file():
            raise MissingFileError(f"{folder / names[first]}: missing label file (the sequence has "
                                   f"{', '.join(n for n in names.values() if (folder / n).is_file())})")
        for modality, name in names.items():
            path = folder / name
            if path.is_file():
                labels[modality][folder.name] = read_anti_uav_label(path)
                paths[modality][folder.name] = path
                warnings.extend(_label_notes(folder.name, path, labels[modality][folder.name], first))
    return AntiUavTruth(bench, labels, paths, warnings)


def _label_notes(seq: str, path: Path, label: TargetFrames, first: str) -> list[str]:
    notes = []
    if len(label) == 0:
        raise FileFormatError(f"{path}: empty label (no frames)")
    boxless = int((label.present & np.isnan(label.boxes).any(axis=1)).sum())
    if boxless:
        notes.append(f"{seq}: {boxless} frame(s) of {path.name} have exist = 1 but no box; left out of the scores "
                     f"(as the Anti-UAV410 toolkit does)")
    return notes


def find_anti_uav_results(folder: str | os.PathLike, truth: AntiUavTruth) -> dict[str, dict[str, Path]]:
    """Modality -> sequence -> result file in ``folder``.

    Raises
    ------
    MissingFileError
        ``folder`` does not exist, or a result exists for a modality whose label the sequence lacks.
    InputError
        Two candidate files for one sequence and modality, or no result file at all.
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such results folder")
    bench = truth.benchmark
    found: dict[str, dict[str, Path]] = {m: {} for m in bench.modalities}
    for seq in truth.sequences:
        for modality in bench.modalities:
            candidates = [folder / f"{stem.format(seq=seq, modality=modality)}{ext}"
                          for stem in _stems(bench, modality) for ext in (".json", ".txt")]
            existing = [c for c in candidates if c.is_file()]
            if len(existing) > 1:
                raise InputError(f"{folder}: several {modality} results for {seq} "
                                 f"({', '.join(p.name for p in existing)}); keep one")
            if existing:
                if seq not in truth.labels[modality]:
                    label = truth.paths[bench.modalities[0]][seq].parent / bench.label_file.format(modality=modality)
                    raise MissingFileError(f"{label}: missing label file, needed to score {existing[0]}")
                found[modality][seq] = existing[0]
    if not any(found.values()):
        seqs = truth.sequences
        raise InputError(f"{folder}: no result file for any of the {len(seqs)} sequences (expected "
                         f"<seq>_{bench.modalities[0]}.json or .txt, e.g. {seqs[0]}_{bench.modalities[0]}.txt); "
                         f"is this the right folder and --benchmark?")
    return found


def _stems(bench: AntiUavBenchmark, modality: str) -> list[str]:
    """File stems that hold ``modality``; a stem without ``{modality}`` belongs to the ranked modality only."""
    return [s for s in bench.result_stems if "{modality}" in s or modality == bench.modalities[0]]


def evaluate_anti_uav_folder(truth: AntiUavTruth, folder: str | os.PathLike, name: str) -> AntiUavScores:
    """Score one tracker's result folder: every labelled sequence of every modality the tracker has results for."""
    bench = truth.benchmark
    files = find_anti_uav_results(folder, truth)
    warnings: list[str] = []
    modalities = {}
    for modality, results in files.items():
        if not results and modality != bench.modalities[0]:
            continue  # the ranked modality is always scored; another only when the tracker has results for it
        scores = {}
        for seq, label in truth.labels[modality].items():
            path = results.get(seq)
            if path is None:
                warnings.append(f"{seq}: no {modality} result for this sequence; scored 0 in every frame")
                scores[seq] = sequence_score(seq, failed_states(label), bench, missing=True)
                continue
            pred = read_anti_uav_result(path)
            if len(pred) != len(label):
                raise FileFormatError(
                    f"{path}: {len(pred)} frames, but {truth.paths[modality][seq]} has {len(label)}; give one entry "
                    f"per frame ({ABSENT_HINT}; in text results every line is a frame)")
            zero = int((pred.present & ((pred.boxes[:, 2] <= 0) | (pred.boxes[:, 3] <= 0))).sum())
            if zero:
                warnings.append(f"{seq}: {zero} {modality} box(es) of zero or negative size score as boxes, not as "
                                f"'target absent' (as the official code scores them); {ABSENT_HINT}")
            scores[seq] = sequence_score(seq, frame_states(pred, label, bench.miss_iou), bench)
        modalities[modality] = scores
    return AntiUavScores(name, bench, modalities, warnings)
