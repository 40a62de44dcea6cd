"""Training pairs for MFNet from annotated RGB-T benchmark sequences (GTOT, RGBT234, LasHeR, ... any layout
:mod:`rgbt_toolkit.io.sequences` reads).

Paper: "training pairs within an interval of 5 frames". A pair is an init frame ``i`` (the tracker learns the target
at its ground-truth box) and a search frame ``j`` with ``1 <= j - i <= max_gap``; frames whose box is NaN (not
annotated) or of zero size are skipped. Both frames are cropped around the target's position in the init frame (where
a tracker would search) and rescaled so the target's side ``sqrt(w h)`` becomes a random size in
``[target_min, target_max]`` of the ``patch`` x ``patch`` crop, as for the image-pair samples
(:mod:`rgbt_toolkit.fusion.trainset`). Each modality is cropped around its own ground truth when the benchmark has
one per camera, so the target sits at the same patch position in both.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.fusion.trainset import Sample, SampleSettings
from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.io.sequences import Sequence, read_sequence

KIND = "sequence"


def _valid(gt: np.ndarray | None, n: int) -> np.ndarray:
    if gt is None:
        return np.ones(n, bool)
    gt = np.asarray(gt, dtype=float)[:n]
    ok = np.isfinite(gt).all(axis=1) & (gt[:, 2] > 0) & (gt[:, 3] > 0)
    return np.pad(ok, (0, n - len(ok)))


def usable_frames(seq: Sequence) -> np.ndarray:
    """Indices of the frames of ``seq`` whose boxes (both cameras, where given) are finite and of positive size."""
    n = len(seq)
    if seq.gt_rgb is None and seq.gt_t is None:
        return np.zeros(0, int)
    return np.flatnonzero(_valid(seq.gt_rgb, n) & _valid(seq.gt_t, n))


def search_frames(usable: np.ndarray, i: int, max_gap: int) -> np.ndarray:
    """Usable frames 1..``max_gap`` frames after ``i`` (``usable`` sorted)."""
    return usable[np.searchsorted(usable, i, side="right") : np.searchsorted(usable, i + max_gap, side="right")]


def frame_pairs(seq: Sequence, max_gap: int) -> list[tuple[int, int]]:
    """All (init, search) frame index pairs of ``seq`` 1..``max_gap`` frames apart with usable boxes in both."""
    usable = usable_frames(seq)
    return [(int(i), int(j)) for i in usable for j in search_frames(usable, i, max_gap)]


def crop_scaled(img: np.ndarray, cx: float, cy: float, scale: float, p: int) -> np.ndarray:
    """``p`` x ``p`` float32 patch of ``img`` centred at (cx, cy), magnified by ``scale`` (borders replicated).

    Image pixel ``x`` maps to patch pixel ``(x - cx) * scale + p / 2``; only the needed region is touched, and it is
    low-pass filtered first when shrinking so the patch does not alias.
    """
    h, w = img.shape[:2]
    half = p / (2 * scale)
    x0, y0 = int(np.floor(cx - half)) - 2, int(np.floor(cy - half)) - 2
    x1, y1 = int(np.ceil(cx + half)) + 3, int(np.ceil(cy + half)) + 3
    xa, ya, xb, yb = min(max(x0, 0), w - 1), min(max(y0, 0), h - 1), max(min(x1, w), 1), max(min(y1, h), 1)
    region = img[ya:yb, xa:xb].astype(np.float32)
    region = cv2.copyMakeBorder(region, ya - y0 if y0 < ya else 0, max(y1 - yb, 0), xa - x0 if x0 < xa else 0,
                                max(x1 - xb, 0), cv2.BORDER_REPLICATE)
    if scale < 1.0:
        region = cv2.GaussianBlur(region, (0, 0), 0.5 * np.sqrt(1.0 / scale**2 - 1.0))
    m = np.array([[scale, 0, (x0 - cx) * scale + p / 2], [0, scale, (y0 - cy) * scale + p / 2]], np.float32)
    return cv2.warpAffine(region, m, (p, p), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def _to_patch(box: np.ndarray, centre: np.ndarray, scale: float, p: int) -> np.ndarray:
    return np.array([(box[0] - centre[0]) * scale + p / 2, (box[1] - centre[1]) * scale + p / 2,
                     box[2] * scale, box[3] * scale], dtype=np.float64)


def _u8(patch: np.ndarray) -> np.ndarray:
    return np.clip(patch + 0.5, 0, 255).astype(np.uint8)


class SequenceSource:
    """Sample source over benchmark sequence folders (``draw(k, rng) -> Sample``, kind ``"sequence"``).

    A draw picks a sequence uniformly (so long sequences do not dominate), then an init frame that has a usable
    search frame, then one of those search frames. Frames are read when drawn; only the ground truth and the usable
    frame indices are kept in memory.
    """

    def __init__(self, folders: list[Path], s: SampleSettings = SampleSettings()):
        self.settings = s
        self.sequences, self.usable, self.starts = [], [], []
        for folder in folders:
            seq = read_sequence(folder)
            usable = usable_frames(seq)
            starts = np.array([i for i in usable if len(search_frames(usable, i, s.max_gap))], dtype=int)
            if len(starts):
                self.sequences.append(seq)
                self.usable.append(usable)
                self.starts.append(starts)
        if not self.sequences:
            names = ", ".join(str(f) for f in folders[:3]) + (" ..." if len(folders) > 3 else "")
            raise InputError(f"{names}: no two annotated frames within {s.max_gap} frames of each other; "
                             "training needs ground-truth boxes")

    def draw(self, k: int, rng: np.random.Generator) -> Sample:
        a = int(rng.integers(len(self.sequences)))
        i = int(self.starts[a][int(rng.integers(len(self.starts[a])))])
        after = search_frames(self.usable[a], i, self.settings.max_gap)
        return self.sample(self.sequences[a], i, int(after[int(rng.integers(len(after)))]), rng)

    def sample(self, seq: Sequence, i: int, j: int, rng: np.random.Generator) -> Sample:
        """The training pair (init frame ``i``, search frame ``j``) of ``seq``."""
        s, p = self.settings, self.settings.patch
        gt_rgb = seq.gt_rgb if seq.gt_rgb is not None else seq.gt_t
        gt_t = seq.gt_t if seq.gt_t is not None else seq.gt_rgb
        box = gt_rgb[i]
        side = rng.uniform(s.target_min, s.target_max)
        scale = min(side / np.sqrt(box[2] * box[3]), 0.5 * p / max(box[2], box[3]))
        patches, boxes = {}, {}
        for name, frames, gt, grey in (("rgb", seq.rgb_frames, gt_rgb, False), ("t", seq.t_frames, gt_t, True)):
            centre = gt[i, :2] + gt[i, 2:] / 2
            for tag, f in (("init", i), ("search", j)):
                img = read_image(frames[f], grey=grey)
                if tag == "init":  # a box partly outside the frame: search around its visible part
                    centre = np.clip(centre, 0, np.array(img.shape[1::-1]) - 1)
                if not grey and img.ndim == 2:
                    img = np.repeat(img[:, :, None], 3, axis=2)
                patches[name, tag] = _u8(crop_scaled(img, centre[0], centre[1], scale, p))
                if name == "rgb":
                    boxes[tag] = _to_patch(gt[f], centre, scale, p)
        return Sample(patches["rgb", "init"], patches["t", "init"], patches["rgb", "search"], patches["t", "search"],
                      boxes["init"], boxes["search"], KIND)
