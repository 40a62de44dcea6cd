"""Discovering the items of a batch: sequence folders, paired videos, paired images.

An :class:`Item` is what one task call gets: a unique key (names its outputs and its manifest line), a kind and
the input paths. Items hold only paths and strings so they pickle cheaply to worker processes and cluster nodes.

Pairs are matched by name. Videos (or images in one folder) pair as ``<stem>_<rgb tag>.<ext>`` with
``<stem>_<thermal tag>.<ext>``, the tag after the last ``_`` or ``-``; images in two folders pair by stem.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from pathlib import Path

from rgbt_toolkit.errors import InputError, MissingFileError
from rgbt_toolkit.io.images import natural_key

RGB_TAGS = ("rgb", "visible", "vis", "color", "colour", "v")
T_TAGS = ("t", "ir", "thermal", "infrared", "tir", "lwir", "i")
VIDEO_EXTS = (".mp4", ".avi", ".mkv", ".mov", ".webm", ".m4v", ".mpg", ".mpeg")
IMAGE_EXTS = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")

_TAGGED = re.compile(r"^(?P<stem>.+?)[_\-](?P<tag>[A-Za-z]+)$")


@dataclass(frozen=True)
class Item:
    """One unit of batch work: ``kind`` is 'sequence', 'video_pair', 'image_pair' or 'triple'; ``paths`` its inputs;
    ``tags`` small labels the task passes through (a fused image's source stem and method)."""

    key: str
    kind: str
    paths: tuple[Path, ...]
    tags: tuple[str, ...] = ()


@dataclass(frozen=True)
class Discovery:
    """Items found in a folder, the files that looked like inputs but had no partner, and the folders left out for
    another reason (all reported, not run)."""

    items: tuple[Item, ...]
    unpaired: tuple[Path, ...] = ()
    notes: tuple[str, ...] = ()  # other things found and left out, one line each


def _files(folder: Path, exts: tuple[str, ...]) -> list[Path]:
    return sorted((p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in exts),
                  key=lambda p: natural_key(p.name))


def _split_tag(path: Path) -> tuple[str, str] | None:
    """``x_rgb.mp4`` -> ('x', 'rgb'); None when the name carries no modality tag."""
    match = _TAGGED.match(path.stem)
    if match is None:
        return None
    tag = match["tag"].lower()
    if tag in RGB_TAGS:
        return match["stem"], "rgb"
    if tag in T_TAGS:
        return match["stem"], "t"
    return None


def pair_by_tag(folder: str | os.PathLike, exts: tuple[str, ...], kind: str) -> Discovery:
    """Pair ``<stem>_<rgb tag>`` with ``<stem>_<t tag>`` files of ``folder`` (extensions may differ)."""
    folder = Path(folder)
    found: dict[str, dict[str, list[Path]]] = {}
    unpaired: list[Path] = []
    for path in _files(folder, exts):
        split = _split_tag(path)
        if split is None:
            unpaired.append(path)
            continue
        found.setdefault(split[0], {}).setdefault(split[1], []).append(path)
    items = []
    for stem in sorted(found, key=natural_key):
        sides = found[stem]
        if len(sides.get("rgb", ())) == 1 and len(sides.get("t", ())) == 1:
            items.append(Item(stem, kind, (sides["rgb"][0], sides["t"][0])))
        else:  # a missing partner, or two candidates for one side (x_rgb.mp4 and x_vis.mp4): ambiguous
            unpaired.extend(p for paths in sides.values() for p in paths)
    return Discovery(tuple(items), tuple(sorted(unpaired, key=lambda p: natural_key(p.name))))


def track_items(dataset_dir: str | os.PathLike) -> Discovery:
    """Every sequence folder (any layout ``rgbt`` reads) and every paired video directly in ``dataset_dir``.

    Raises
    ------
    MissingFileError
        ``dataset_dir`` does not exist.
    InputError
        Nothing to track was found, or two items would write the same result name.
    """
    from rgbt_toolkit.io.sequences import list_sequences

    dataset_dir = Path(dataset_dir)
    if not dataset_dir.is_dir():
        raise MissingFileError(f"{dataset_dir}: no such dataset folder")
    sequences = [Item(path.name, "sequence", (path,)) for path in list_sequences(dataset_dir)]
    videos = pair_by_tag(dataset_dir, VIDEO_EXTS, "video_pair")
    items = sequences + list(videos.items)
    if not items:
        raise InputError(f"{dataset_dir}: no sequence folders (GTOT, RGBT234, LasHeR, VTUAV or VOT-RGBT layout) and "
                         f"no video pairs named like x_rgb.mp4 / x_t.mp4 were found")
    _check_unique(items, dataset_dir)
    return Discovery(tuple(items), videos.unpaired, _untrackable(dataset_dir, {p.paths[0] for p in sequences}))


def _untrackable(dataset_dir: Path, sequences: set[Path]) -> tuple[str, ...]:
    """Folders with a sequence's two frame folders but no box file to start from, which would go unnoticed."""
    from rgbt_toolkit.io.sequences import LAYOUTS

    notes = []
    for child in sorted((p for p in dataset_dir.iterdir() if p.is_dir()), key=lambda p: natural_key(p.name)):
        if child in sequences:
            continue
        if any((child / s.rgb_dir).is_dir() and (child / s.t_dir).is_dir() for s in LAYOUTS):
            notes.append(f"{child}: no init.txt/groundTruth; skipped")
    return tuple(notes)


def image_pair_items(vis: str | os.PathLike, ir: str | os.PathLike | None = None) -> Discovery:
    """Image pairs for fusion: two folders paired by file stem, or one folder of ``x_vis.png`` / ``x_ir.png``.

    A stem present in only one folder is reported in ``unpaired``. Raises :class:`InputError` when nothing pairs.
    """
    vis = Path(vis)
    if not vis.is_dir():
        raise MissingFileError(f"{vis}: no such image folder")
    if ir is None:
        found = pair_by_tag(vis, IMAGE_EXTS, "image_pair")
    else:
        ir = Path(ir)
        if not ir.is_dir():
            raise MissingFileError(f"{ir}: no such image folder")
        vis_files, ir_files = _by_stem(vis), _by_stem(ir)
        common = sorted(vis_files.keys() & ir_files.keys(), key=natural_key)
        only = [vis_files[s] for s in vis_files.keys() - ir_files.keys()] + \
               [ir_files[s] for s in ir_files.keys() - vis_files.keys()]
        found = Discovery(tuple(Item(s, "image_pair", (vis_files[s], ir_files[s])) for s in common),
                          tuple(sorted(only, key=lambda p: natural_key(p.name))))
    if not found.items:
        where = f"{vis} and {ir}" if ir is not None else str(vis)
        raise InputError(f"{where}: no image pairs found (pair two folders by file stem, or name files "
                         f"x_vis.png / x_ir.png in one folder)")
    return found


def _by_stem(folder: Path) -> dict[str, Path]:
    """The images of ``folder`` by stem; two images sharing a stem (a.png, a.jpg) are refused, not one dropped."""
    found: dict[str, Path] = {}
    for path in _files(folder, IMAGE_EXTS):
        if path.stem in found:
            raise InputError(f"{found[path.stem]} and {path}: two images with the stem '{path.stem}' in one folder "
                             f"would both be fused into {path.stem}; rename or move one of them")
        found[path.stem] = path
    return found


def _check_unique(items: list[Item], where: Path) -> None:
    seen: dict[str, Item] = {}
    for item in items:
        if item.key in seen:
            raise InputError(f"{where}: '{item.key}' is both a {seen[item.key].kind.replace('_', ' ')} and a "
                             f"{item.kind.replace('_', ' ')}; rename one so their results do not collide")
        seen[item.key] = item
