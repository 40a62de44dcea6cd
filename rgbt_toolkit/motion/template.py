"""Template matching for Algorithm 1 in the modality that can still see the target.

The paper matches templates on the RGB frame. At night the RGB template stops matching anything (s_A collapses),
Algorithm 1 then hands the track to the motion tracker for good, and appearance updates stop: the tracker can never
come back. Ours matches on RGB while the visible patch is lit and on the thermal frame (against the first thermal
template) when it is dark, each with its own score calibration.
"""

from __future__ import annotations

import numpy as np


def patch_mean(image: np.ndarray, box: np.ndarray) -> float:
    """Mean grey level inside ``box`` (0 for a box outside the frame)."""
    x, y, w, h = np.round(box).astype(int)
    patch = image[max(y, 0): max(y + h, 0), max(x, 0): max(x + w, 0)]
    return float(patch.mean()) if patch.size else 0.0


def _three_channels(image: np.ndarray) -> np.ndarray:
    return np.repeat(image[:, :, None], 3, axis=2) if image.ndim == 2 else image


class ModalityAwareTemplate:
    """``TemplateScorer``: an RGB DDIS scorer, and a thermal one used when the RGB patch is darker than ``min_light``."""

    def __init__(self, rgb_scorer, thermal_scorer, min_light: float):
        self.rgb_scorer, self.thermal_scorer, self.min_light = rgb_scorer, thermal_scorer, min_light
        self.last_modality = "rgb"

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: np.ndarray) -> None:
        self.rgb_scorer.initialize(rgb, box)
        self.thermal_scorer.initialize(_three_channels(thermal), box)

    def __call__(self, rgb: np.ndarray, thermal: np.ndarray, box_appearance: np.ndarray,
                 box_motion: np.ndarray) -> tuple[float, float]:
        if patch_mean(rgb, box_appearance) >= self.min_light:
            self.last_modality = "rgb"
            return self.rgb_scorer(rgb, box_appearance, box_motion)
        self.last_modality = "t"
        return self.thermal_scorer(_three_channels(thermal), box_appearance, box_motion)
