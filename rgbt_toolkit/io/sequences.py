"""Benchmark sequence folders as paired (RGB, T) frame lists with per-modality ground truth.

Each layout is a small spec (folder and file names, box format), so adding a benchmark adds data, not branches.
Detection tries the specs in order and takes the first whose folders and box files are present.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import InputError, MissingFileError
from rgbt_toolkit.io.boxes import read_boxes, read_vot_groundtruth
from rgbt_toolkit.io.images import list_images


@dataclass(frozen=True)
class LayoutSpec:
    """Where one benchmark keeps frames and boxes inside a sequence folder."""

    name: str
    rgb_dir: str
    t_dir: str
    rgb_boxes: tuple[str, ...]  # candidate box files for the RGB camera, first existing wins
    t_boxes: tuple[str, ...]  # for the thermal camera; the same file when the benchmark has one
    box_format: str = "xywh"  # as understood by read_boxes, or "vot" for polygon files with markers
    annotation_step: int = 1  # VTUAV annotates every 10th frame
    required: tuple[str, ...] = ()  # files that must exist for the layout to match


LAYOUTS: tuple[LayoutSpec, ...] = (
    LayoutSpec("gtot", "v", "i", ("groundTruth_v.txt",), ("groundTruth_i.txt",), "xyxy",
               required=("groundTruth_v.txt", "groundTruth_i.txt")),
    LayoutSpec("rgbt234", "visible", "infrared", ("visible.txt",), ("infrared.txt",),
               required=("visible.txt", "infrared.txt")),
    LayoutSpec("vtuav", "rgb", "ir", ("rgb.txt",), ("ir.txt",), annotation_step=10, required=("rgb.txt", "ir.txt")),
    LayoutSpec("vot-rgbt", "color", "ir", ("groundtruth.txt",), ("groundtruth.txt",), "vot",
               required=("groundtruth.txt",)),
    # LasHeR and RGBT210 keep one box file for both cameras
    LayoutSpec("lasher", "visible", "infrared", ("init.txt", "groundtruth.txt"), ("init.txt", "groundtruth.txt")),
)
LAYOUT_NAMES = tuple(spec.name for spec in LAYOUTS)


@dataclass
class Sequence:
    """A paired RGB-T sequence. Boxes are float (N, 4) x, y, w, h; rows of NaN where a frame is not annotated."""

    name: str
    layout: str
    root: Path
    rgb_frames: list[Path]
    t_frames: list[Path]
    gt_rgb: np.ndarray | None
    gt_t: np.ndarray | None
    init_box: np.ndarray | None = None  # from init.txt when present, else the first ground-truth row
    extra: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.rgb_frames)


def detect_layout(folder: str | os.PathLike) -> LayoutSpec:
    """The layout of a sequence folder; :class:`InputError` listing what was looked for when none fits."""
    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such sequence folder")
    for spec in LAYOUTS:
        if not ((folder / spec.rgb_dir).is_dir() and (folder / spec.t_dir).is_dir()):
            continue
        if all((folder / name).is_file() for name in spec.required):
            if spec.required or _first_existing(folder, spec.rgb_boxes) is not None:
                return spec
    expected = "; ".join(f"{s.name}: {s.rgb_dir}/ + {s.t_dir}/" for s in LAYOUTS)
    raise InputError(f"{folder}: unknown sequence layout (expected one of {expected})")


def read_sequence(folder: str | os.PathLike, layout: str | None = None) -> Sequence:
    """Read one benchmark sequence folder; ``layout`` forces a layout name instead of detecting it."""
    folder = Path(folder)
    spec = detect_layout(folder) if layout is None else _spec_by_name(layout)
    rgb_frames = list_images(folder / spec.rgb_dir)
    t_frames = list_images(folder / spec.t_dir)
    if not rgb_frames or not t_frames:
        raise InputError(f"{folder}: {spec.rgb_dir}/ has {len(rgb_frames)} images and {spec.t_dir}/ has "
                         f"{len(t_frames)}; both need frames")
    if len(rgb_frames) != len(t_frames):
        raise InputError(f"{folder}: {spec.rgb_dir}/ has {len(rgb_frames)} frames but {spec.t_dir}/ has "
                         f"{len(t_frames)}; a paired sequence needs equal counts")
    gt_rgb = _read_gt(folder, spec, spec.rgb_boxes, len(rgb_frames))
    gt_t = _read_gt(folder, spec, spec.t_boxes, len(t_frames))
    init_box = None
    if (folder / "init.txt").is_file():
        boxes = read_boxes(folder / "init.txt")
        if len(boxes) == 0:
            raise InputError(f"{folder / 'init.txt'}: empty; it needs the first frame's box x,y,w,h")
        init_box = boxes[0]
    elif gt_rgb is not None:
        if len(gt_rgb) == 0:
            raise InputError(f"{_first_existing(folder, spec.rgb_boxes)}: empty; it needs the first frame's box "
                             "x,y,w,h")
        init_box = gt_rgb[0]
    name = folder.name if folder.name not in ("", ".", "..") else folder.resolve().name  # `rgbt track .`
    return Sequence(name, spec.name, folder, rgb_frames, t_frames, gt_rgb, gt_t, init_box)


def list_sequences(dataset: str | os.PathLike) -> list[Path]:
    """Sequence folders directly below ``dataset`` (or ``dataset`` itself when it is one), naturally sorted."""
    from rgbt_toolkit.io.images import natural_key

    dataset = Path(dataset)
    if not dataset.is_dir():
        raise MissingFileError(f"{dataset}: no such dataset folder")
    try:
        detect_layout(dataset)
        return [dataset]
    except InputError:
        pass
    found = []
    for child in sorted(dataset.iterdir(), key=lambda p: natural_key(p.name)):
        if child.is_dir():
            try:
                detect_layout(child)
            except InputError:
                continue
            found.append(child)
    return found


def _spec_by_name(name: str) -> LayoutSpec:
    for spec in LAYOUTS:
        if spec.name == name.lower():
            return spec
    if name.lower() == "rgbt210":
        return _spec_by_name("lasher")
    raise InputError(f"unknown layout '{name}'; choose one of {', '.join(LAYOUT_NAMES)}")


def _first_existing(folder: Path, names: tuple[str, ...]) -> Path | None:
    for name in names:
        if (folder / name).is_file():
            return folder / name
    return None


def _read_gt(folder: Path, spec: LayoutSpec, names: tuple[str, ...], n_frames: int) -> np.ndarray | None:
    path = _first_existing(folder, names)
    if path is None:
        return None
    if spec.box_format == "vot":
        boxes = np.asarray(read_vot_groundtruth(path), dtype=float)
    else:
        boxes = read_boxes(path, fmt=spec.box_format)
    if spec.annotation_step > 1:
        dense = np.full((n_frames, 4), np.nan)
        rows = np.arange(len(boxes)) * spec.annotation_step
        keep = rows < n_frames
        dense[rows[keep]] = boxes[keep]
        return dense
    if path.name == "init.txt" and len(boxes) == 1:
        return None  # an init file alone is no ground truth
    return boxes
