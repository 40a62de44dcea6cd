"""The interfaces the JMMAC pipeline is assembled from.

The pipeline takes its parts as constructor arguments (kornia's HomographyTracker style), so Algorithm 1 and the
per-frame order can be tested with small fakes while the real ECO, MFNet, CME and DDIS parts are tested on their own.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np


@dataclass
class AppearanceEstimate:
    """One appearance tracker's answer for a frame, before any model update.

    ``response`` lives on a grid shared by the RGB and T trackers (same search region, same size), so the two can
    be fused element-wise; ``box`` is where this tracker alone would put the target.
    """

    box: np.ndarray
    response: np.ndarray
    scale_factor: float  # size change relative to the previous frame's box
    peak: float
    context: object = None  # tracker-specific data needed to localise a fused response
    region: np.ndarray | None = None  # image square [x, y, side, side] the response grid covers: cell (i, j) is
    # centred at (x, y) + ((j, i) + 0.5) * side / G; MFNet's patches are cut from it so W_F lands on the right cells


class AppearanceTracker(Protocol):
    def initialize(self, frame: np.ndarray, box: np.ndarray) -> None: ...

    def predict(self, frame: np.ndarray, centre: np.ndarray, search_scales: bool = True) -> AppearanceEstimate: ...

    def locate(self, estimate: AppearanceEstimate, response: np.ndarray, scale_factor: float) -> np.ndarray: ...

    def update(self, frame: np.ndarray, box: np.ndarray) -> None: ...


class FusionWeighting(Protocol):
    def __call__(self, rgb: np.ndarray, thermal: np.ndarray, region: np.ndarray,
                 grid_shape: tuple[int, int]) -> tuple[float, np.ndarray]:
        """``(w_G, W_L)`` for the search region ``region`` (x, y, w, h) on a response grid of ``grid_shape``."""
        ...


class TemplateScorer(Protocol):
    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: np.ndarray) -> None: ...

    def __call__(self, rgb: np.ndarray, thermal: np.ndarray, box_appearance: np.ndarray,
                 box_motion: np.ndarray) -> tuple[float, float]:
        """``(s_A, s_M)`` similarities of both candidates to the first-frame template, on the paper's scale."""
        ...


class BoxRefiner(Protocol):
    def initialize(self, rgb: np.ndarray, box: np.ndarray) -> None: ...

    def refine(self, rgb: np.ndarray, box: np.ndarray) -> np.ndarray | None:
        """A tighter box around ``box`` or None when there is no confident one."""
        ...
