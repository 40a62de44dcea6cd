"""ECO as the pipeline's ``AppearanceTracker`` part (one per modality, sharing one search grid)."""

from __future__ import annotations

import numpy as np

from rgbt_toolkit.eco import EcoParams, EcoTracker
from rgbt_toolkit.eco.tracker import TrackResult
from rgbt_toolkit.jmmac.parts import AppearanceEstimate


def grid_square(origin: np.ndarray, step: float, cells: int) -> np.ndarray:
    """The image square ``[x, y, side, side]`` covered by a ``cells`` x ``cells`` grid: index ``(i, j)`` sits at
    ``origin + (j, i) * step``, so each cell spans ``step`` pixels around that point."""
    x, y = np.asarray(origin, dtype=float) - step / 2
    return np.array([x, y, cells * step, cells * step])


def grid_region(pred: TrackResult) -> np.ndarray:
    """The image square covered by ``pred.response``."""
    return grid_square(pred.grid_origin, pred.grid_step, pred.response.shape[0])


class EcoAppearance:
    """Wraps :class:`~rgbt_toolkit.eco.EcoTracker`: responses on the documented grid, fused-peak localisation.

    Two instances built from the same parameters and initial box search the same square region on the same grid,
    and the pipeline always updates both with the same box, so their grids stay aligned frame after frame.
    """

    def __init__(self, params: EcoParams):
        self.eco = EcoTracker(params)
        self._size = np.zeros(2)

    def initialize(self, frame: np.ndarray, box: np.ndarray) -> None:
        self.eco.initialize(frame, box)
        self._size = np.asarray(box[2:], dtype=float)

    def predict(self, frame: np.ndarray, centre: np.ndarray, search_scales: bool = True) -> AppearanceEstimate:
        before = self.eco.scale
        pred = self.eco.predict(frame, centre, search_scales=search_scales)
        return AppearanceEstimate(box=pred.box, response=pred.response, scale_factor=float(pred.scale / before),
                                  peak=pred.peak, context=pred, region=grid_region(pred))

    def search_grid(self, centre: np.ndarray) -> tuple[np.ndarray, tuple[int, int]]:
        """``(region, grid_shape)`` that :meth:`predict` at ``centre`` will cover, known before searching (the
        pipeline computes MFNet's weights meanwhile); ``region`` equals the estimate's :func:`grid_region`."""
        grid = self.eco.geom.grid
        return grid_square(*self.eco.response_grid(centre), grid), (grid, grid)

    def locate(self, estimate: AppearanceEstimate, response: np.ndarray, scale_factor: float) -> np.ndarray:
        """Box at the fused response's peak, sized by the (fused) scale change from the last frame's box."""
        box = self.eco.localize_from_response(estimate.context, response)
        centre = box[:2] + (box[2:] - 1) / 2
        size = self._size * scale_factor
        return np.concatenate([centre - (size - 1) / 2, size])

    def update_reads_frame(self, frame: np.ndarray, box: np.ndarray) -> bool:
        """Whether :meth:`update` would read the frame's pixels (else it reuses the search's sample)."""
        return self.eco.update_reads_frame(frame, box)

    def update(self, frame: np.ndarray, box: np.ndarray) -> None:
        self.eco.update(frame, box)
        self._size = np.asarray(box[2:], dtype=float)
