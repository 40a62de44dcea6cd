"""Cheap deterministic trackers for the batch tests (top-level, so they pickle to pool and Dask workers).

Each call leaves a file in ``<dataset>/../calls/`` so tests can count which items were computed, in any process.
"""

from __future__ import annotations

import os
import time
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.io.boxes import read_boxes, write_boxes
from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.io.sequences import read_sequence


def calls_dir(item_path: Path) -> Path:
    return Path(item_path).parent.parent / "calls"


def _count_call(item_path: Path, key: str) -> None:
    folder = calls_dir(item_path)
    folder.mkdir(exist_ok=True)
    (folder / f"{key}.{os.getpid()}.{time.monotonic_ns()}").touch()


def count_calls(dataset: Path) -> dict[str, int]:
    """How many times each item was computed, from the files the trackers leave."""
    folder = calls_dir(dataset / "x")
    counts: dict[str, int] = {}
    for path in folder.glob("*") if folder.is_dir() else ():
        key = path.name.split(".")[0]
        counts[key] = counts.get(key, 0) + 1
    return counts


def template_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """Track by normalised cross-correlation of the first-frame RGB template over each whole frame.

    When ``<dataset>/../interrupt_after`` holds k, the call after k finished items raises ``KeyboardInterrupt``
    (Ctrl-C in the middle of a batch).
    """
    stop_file = calls_dir(seq_dir).parent / "interrupt_after"
    if stop_file.is_file() and sum(count_calls(Path(seq_dir).parent).values()) >= int(stop_file.read_text()):
        raise KeyboardInterrupt
    _count_call(seq_dir, Path(seq_dir).name)
    seq = read_sequence(seq_dir)
    box = np.round(seq.init_box).astype(int)
    x, y, w, h = box
    first = read_image(seq.rgb_frames[0], grey=True)
    template = first[y:y + h, x:x + w]
    boxes = [seq.init_box.astype(float)]
    for frame_path in seq.rgb_frames[1:]:
        frame = read_image(frame_path, grey=True)
        score = cv2.matchTemplate(frame, template, cv2.TM_CCOEFF_NORMED)
        _, _, _, (bx, by) = cv2.minMaxLoc(score)
        boxes.append(np.array([bx, by, w, h], dtype=float))
    out = np.array(boxes)
    if preset == "shifted":
        out[:, :2] += 1.5
    return out


def flaky_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """Fails the first time it sees a sequence whose name ends in 'flaky', succeeds on the retry."""
    name = Path(seq_dir).name
    if name.endswith("flaky") and count_calls(Path(seq_dir).parent).get(name, 0) == 0:
        _count_call(seq_dir, name)
        raise RuntimeError("transient failure")
    return template_tracker(seq_dir, preset)


def crashing_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """Kills its worker process outright on sequences named '*crash' (a segfault stand-in)."""
    if Path(seq_dir).name.endswith("crash"):
        _count_call(seq_dir, Path(seq_dir).name)
        os._exit(3)
    return template_tracker(seq_dir, preset)


def video_tracker(rgb_path: Path, t_path: Path, out_dir: Path, preset: str = "full") -> dict[str, Path]:
    """Writes the pair's RGB box file back, as a tracker of video pairs would write its boxes."""
    _count_call(rgb_path, Path(rgb_path).stem.rsplit("_", 1)[0])
    boxes = read_boxes(Path(rgb_path).with_suffix(".boxes.txt"))
    target = Path(out_dir) / "boxes_rgb.txt"
    write_boxes(target, boxes)
    return {"boxes_rgb": target}


def slow_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """:func:`template_tracker` taking at least 0.4 s, so a test can kill the batch between two items."""
    time.sleep(0.4)
    return template_tracker(seq_dir, preset)


def thread_report(item) -> dict:
    """The thread limits a worker runs under (no torch import: that alone costs seconds per worker)."""
    from threadpoolctl import threadpool_info

    return {"omp": os.environ.get("OMP_NUM_THREADS"), "rgbt": os.environ.get("RGBT_THREADS"),
            "cv2": cv2.getNumThreads(), "blas": sorted({pool["num_threads"] for pool in threadpool_info()}),
            "pid": os.getpid()}


def wrong_shape_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """Returns one box per frame as a flat vector: not the (N, 4) the batch writes."""
    return np.zeros(12)


def warning_tracker(seq_dir: Path, preset: str = "full") -> np.ndarray:
    """:func:`template_tracker` that warns on sequences named '*warn', as a tracker skipping a corrupt frame does."""
    import warnings

    if Path(seq_dir).name.endswith("warn"):
        warnings.warn(f"{seq_dir}: frame 2 skipped\nsecond line", RuntimeWarning, stacklevel=1)
    return template_tracker(seq_dir, preset)
