"""Single-modality OpenCV baselines for ``rgbt batch track --tracker csrt``.

Papers compare RGB-T trackers with strong single-modality trackers run on either camera; CSRT (discriminative
correlation filter with channel and spatial reliability, OpenCV contrib) is the usual CPU one. It also gives the batch
benchmark a real, CPU-bound per-item workload that needs no network weights.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import InputError

#: Presets: which camera CSRT runs on. Benchmark sequence folders are registered, so boxes share coordinates.
CSRT_PRESETS = {"rgb": "visible camera", "t": "thermal camera"}


def csrt_sequence(seq_dir: str | os.PathLike, preset: str = "rgb") -> np.ndarray:
    """Track a benchmark sequence folder with OpenCV CSRT on one camera; (N, 4) float ``x, y, w, h`` boxes.

    The first box is the sequence's initial box (``init.txt`` or the first ground-truth row of that camera); frames
    where CSRT reports a loss repeat the last box, as the benchmark toolkits expect a box on every frame.
    """
    import cv2

    from rgbt_toolkit.io.images import read_image
    from rgbt_toolkit.io.sequences import read_sequence

    if preset not in CSRT_PRESETS:
        raise InputError(f"unknown CSRT preset '{preset}'; choose one of {', '.join(CSRT_PRESETS)}")
    seq = read_sequence(Path(seq_dir))
    frames = seq.rgb_frames if preset == "rgb" else seq.t_frames
    gt = seq.gt_rgb if preset == "rgb" else seq.gt_t
    init = seq.init_box if preset == "rgb" or gt is None else gt[0]
    if init is None or not np.all(np.isfinite(init)) or init[2] <= 0 or init[3] <= 0:
        raise InputError(f"{seq_dir}: no usable initial box (init.txt or a first ground-truth row)")
    tracker = cv2.TrackerCSRT.create()
    box = np.asarray(init, dtype=float)
    boxes = [box]
    for index, path in enumerate(frames):
        image = cv2.cvtColor(read_image(path), cv2.COLOR_RGB2BGR)  # CSRT's colour features expect OpenCV order
        if index == 0:
            tracker.init(image, tuple(int(round(v)) for v in box))
            continue
        found, new_box = tracker.update(image)
        if found:
            box = np.asarray(new_box, dtype=float)
        boxes.append(box)
    return np.array(boxes)
