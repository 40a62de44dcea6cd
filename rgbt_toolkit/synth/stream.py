"""A low-bit-rate stream's skipped blocks (skip_blocks challenge).

The Halmstad clips of ``../shared/data/tracking/real/`` refresh the whole picture only every 128 frames; between
refreshes a median of 1-30 % of the 16x16 blocks change per frame (0.2 % of the pixels on the thermal drone
clips), the rest repeat the last frame bit for bit. A small or slow target therefore moves in jumps, and the block
it left can keep a stale copy of it until the next refresh (svan_ir_bird_003: docs/benchmarks_real.md). Per-frame
JPEG blocking (``real_sensor``) renders none of that: every pixel of it changes on every frame.

The model here is conditional replenishment, the skip decision of an inter-frame encoder without motion vectors: a
block is sent again only when it differs from what the viewer last saw by more than a mean absolute difference of
``threshold`` grey levels, above what sensor noise alone gives (about 3.4 levels at the noise sigma of 3 used here).
"""

from __future__ import annotations

import numpy as np

GOP_FRAMES = 128  # a full refresh (intra frame) every 128 frames, as in the Halmstad clips
BLOCK = 16  # macroblock side in pixels
SKIP_THRESHOLD = 8.0  # mean absolute difference (grey levels) a block needs before it is sent again


class SkipBlockStream:
    """What a viewer of the stream sees, frame after frame, for one camera.

    Feed the camera's frames in order with :meth:`frame`; frame ``index`` with ``index % gop == 0`` is shown whole.
    The state is the picture last shown, so frames must come in order: the renderer replays from the last refresh
    when asked for another one.
    """

    def __init__(self, gop: int = GOP_FRAMES, block: int = BLOCK, threshold: float = SKIP_THRESHOLD) -> None:
        if gop < 1 or block < 1 or threshold < 0:
            raise ValueError(f"gop and block must be positive and threshold non-negative, got {gop}, {block}, "
                             f"{threshold}")
        self.gop, self.block, self.threshold = gop, block, threshold
        self.shown: np.ndarray | None = None
        self.index = -1

    def follows(self, index: int) -> bool:
        """True when frame ``index`` can be shown from the current state (the next frame, or a refresh)."""
        return index % self.gop == 0 or (self.shown is not None and index == self.index + 1)

    def frame(self, image: np.ndarray, index: int) -> np.ndarray:
        """The picture shown for camera frame ``index`` whose full content is ``image`` (uint8, 2-D or H x W x C)."""
        if not self.follows(index):
            raise ValueError(f"frame {index} does not follow frame {self.index}; replay from frame "
                             f"{index - index % self.gop}")
        if index % self.gop == 0 or self.shown is None or self.shown.shape != image.shape:
            shown = image.copy()
        else:
            shown = self.shown.copy()
            sent = self.changed_blocks(image, shown)
            mask = np.kron(sent, np.ones((self.block, self.block), dtype=bool))[:image.shape[0], :image.shape[1]]
            shown[mask] = image[mask]
        self.shown, self.index = shown, index
        return shown.copy()

    def changed_blocks(self, image: np.ndarray, shown: np.ndarray) -> np.ndarray:
        """(rows, cols) bool: blocks whose mean absolute difference from the shown picture exceeds the threshold.

        Edge blocks are partial; their mean is over the pixels they have.
        """
        diff = np.abs(image.astype(np.int16) - shown.astype(np.int16)).astype(np.float32)
        if diff.ndim == 3:
            diff = diff.mean(axis=2)
        h, w = diff.shape
        b = self.block
        rows, cols = -(-h // b), -(-w // b)
        padded = np.zeros((rows * b, cols * b), np.float32)
        padded[:h, :w] = diff
        count = np.zeros_like(padded)
        count[:h, :w] = 1
        sums = padded.reshape(rows, b, cols, b).sum(axis=(1, 3))
        counts = count.reshape(rows, b, cols, b).sum(axis=(1, 3))
        return sums / counts > self.threshold
