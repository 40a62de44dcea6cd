"""What ``rgbt train-mfnet --data DIR`` accepts, and the sample source built from it.

A data folder is one of

- aligned image pairs: ``DIR/vi`` and ``DIR/ir`` paired by stem (:class:`~rgbt_toolkit.fusion.trainset.PairSource`);
- a benchmark sequence folder, or a dataset folder of sequences, in any layout ``rgbt`` reads (GTOT, RGBT234,
  LasHeR, VTUAV, VOT-RGBT; :class:`~rgbt_toolkit.fusion.seqset.SequenceSource`).

The folders are expanded into *units* (one image pair, or one sequence folder), which is also the granularity of the
train / validation split: the same image or sequence never feeds both.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol, Sequence, Union

import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.pairs import find_pairs
from rgbt_toolkit.fusion.trainset import PairSource, Sample, SampleSettings
from rgbt_toolkit.io.sequences import LAYOUT_NAMES, list_sequences

Unit = Union[tuple[Path, Path], Path]  # an aligned (vis, ir) pair, or a sequence folder


class SampleSource(Protocol):
    def draw(self, k: int, rng: np.random.Generator) -> Sample: ...


def unique_folders(folders: Sequence[str | Path]) -> list[Path]:
    """``folders`` without repeats (the same folder given twice, also under another spelling), order kept."""
    seen, out = set(), []
    for folder in map(Path, folders):
        key = folder.resolve()
        if key not in seen:
            seen.add(key)
            out.append(folder)
    return out


def collect_units(folders: Sequence[str | Path]) -> list[Unit]:
    """Image pairs and sequence folders of every ``--data`` folder, in argument order, each unit once.

    A folder given twice, or a sequence folder that is also inside a dataset folder given, counts once: a repeated
    unit would be drawn twice as often and could land on both sides of the train / validation split.
    """
    units: list[Unit] = []
    seen: set = set()
    for unit in _all_units(unique_folders(folders)):
        key = tuple(p.resolve() for p in unit) if isinstance(unit, tuple) else Path(unit).resolve()
        if key not in seen:
            seen.add(key)
            units.append(unit)
    return units


def _all_units(folders: list[Path]) -> list[Unit]:
    units: list[Unit] = []
    for folder in folders:
        if (folder / "vi").is_dir() and (folder / "ir").is_dir():
            units.extend(find_pairs(folder / "vi", folder / "ir").pairs)  # matched by stem, first of a clash
            continue
        sequences = list_sequences(folder)
        if not sequences:
            raise InputError(f"{folder}: neither aligned pairs (vi/ + ir/) nor RGB-T sequence folders "
                             f"(layouts: {', '.join(LAYOUT_NAMES)}) found")
        units.extend(sequences)
    return units


def split_units(units: list[Unit], val_fraction: float, rng: np.random.Generator) -> tuple[list[Unit], list[Unit]]:
    """Random train / validation split by unit (at least one held out when there are two or more)."""
    order = rng.permutation(len(units))
    n_val = max(1, int(round(val_fraction * len(units)))) if len(units) > 1 else 0
    return [units[i] for i in order[n_val:]], [units[i] for i in order[:n_val]]


class MixedSource:
    """Round-robin over several sources, so each data kind gets an equal share of the samples."""

    def __init__(self, parts: list[SampleSource]):
        self.parts = parts

    def draw(self, k: int, rng: np.random.Generator) -> Sample:
        return self.parts[k % len(self.parts)].draw(k // len(self.parts), rng)


def make_source(units: list[Unit], s: SampleSettings = SampleSettings()) -> SampleSource:
    """The sample source over ``units``: image pairs, sequences, or both (round-robin)."""
    pairs = [u for u in units if isinstance(u, tuple)]
    sequences = [u for u in units if not isinstance(u, tuple)]
    parts: list[SampleSource] = []
    if pairs:
        parts.append(PairSource(pairs, s))
    if sequences:
        from rgbt_toolkit.fusion.seqset import SequenceSource

        parts.append(SequenceSource(sequences, s))
    if not parts:
        raise InputError("no training data: pass --data with aligned pairs or RGB-T sequence folders")
    return parts[0] if len(parts) == 1 else MixedSource(parts)


def count_units(units: list[Unit]) -> dict[str, int]:
    """How many image pairs and sequences ``units`` holds (for the weight file's metadata)."""
    n_pairs = sum(isinstance(u, tuple) for u in units)
    return {"images": n_pairs, "sequences": len(units) - n_pairs}
