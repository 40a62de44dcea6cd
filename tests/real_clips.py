"""Loading the real tracking clips of ``../shared/data/tracking/real`` for the tests that use them (they take the
``shared_dir`` fixture, which skips them when the data are absent)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def real_clip(shared_dir: Path, name: str, frames: int | None = None, folder: str = "real"
              ) -> tuple[list[np.ndarray], np.ndarray]:
    """A real clip's frames as ``rgbt track-single`` decodes them, and its labels (one row per frame); ``folder``:
    the set under ``data/tracking`` (``real`` or ``real_more``)."""
    from rgbt_toolkit.io.frames import open_frames

    folder = shared_dir / "data/tracking" / folder / name
    video = next(p for p in folder.iterdir() if p.stem == "video")
    images = [f for f, _ in open_frames(video)][:frames]
    return images, np.loadtxt(folder / "groundtruth.txt", delimiter=",")[: len(images)]
