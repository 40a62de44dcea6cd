"""Small stand-ins for JMMAC's parts, so the pipeline's order and decisions can be tested exactly."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rgbt_toolkit.jmmac.parts import AppearanceEstimate

GRID = 31  # response grid side; one grid cell = one pixel here


def gaussian_peak(grid_centre: np.ndarray, peak_xy: np.ndarray, amplitude: float = 1.0) -> np.ndarray:
    """A response with a Gaussian bump at image point ``peak_xy`` on a grid centred at ``grid_centre``."""
    offs = np.arange(GRID) - GRID // 2
    gx, gy = np.meshgrid(grid_centre[0] + offs, grid_centre[1] + offs)
    return amplitude * np.exp(-((gx - peak_xy[0]) ** 2 + (gy - peak_xy[1]) ** 2) / (2 * 2.0**2))


@dataclass
class ScriptedTracker:
    """Sees the target wherever ``truth[frame]`` says, or at ``decoy[frame]`` when one is given for that frame."""

    truth: list[np.ndarray]
    decoys: dict[int, np.ndarray] = field(default_factory=dict)
    frame: int = 0
    updates: list[int] = field(default_factory=list)
    size: np.ndarray | None = None

    def initialize(self, frame, box):
        self.size = np.asarray(box[2:], float)
        self.frame = 0

    def predict(self, frame, centre, search_scales=True):
        self.frame += 1
        peak = self.decoys.get(self.frame, self.truth[self.frame])
        response = gaussian_peak(centre, peak)
        return AppearanceEstimate(box=np.r_[peak - (self.size - 1) / 2, self.size], response=response,
                                  scale_factor=1.0, peak=float(response.max()), context=np.asarray(centre, float))

    def locate(self, estimate, response, scale_factor):
        row, col = np.unravel_index(np.argmax(response), response.shape)
        centre = estimate.context + np.array([col, row]) - GRID // 2
        return np.r_[centre - (self.size - 1) / 2, self.size]

    def update(self, frame, box):
        self.updates.append(self.frame)


class ConstantFusion:
    """MFNet stand-in: a fixed global weight and a flat local map."""

    def __init__(self, w_g: float):
        self.w_g = w_g

    def __call__(self, rgb, thermal, region, grid_shape):
        return self.w_g, np.ones(grid_shape)


class RecordingKalman:
    """Kalman stand-in that predicts the last measurement plus the last velocity, and records its calls."""

    def __init__(self):
        self.initialized = False
        self.positions: list[np.ndarray] = []
        self.corrections = 0

    def initialize(self, pos):
        self.initialized = True
        self.positions = [np.asarray(pos, float)]

    def predict(self):
        if len(self.positions) < 2:
            return self.positions[-1]
        return 2 * self.positions[-1] - self.positions[-2]

    def correct(self, pos):
        self.corrections += 1
        self.positions.append(np.asarray(pos, float))


class FixedTemplate:
    """Template scorer returning scripted ``(s_A, s_M)`` per call."""

    def __init__(self, scores):
        self.scores = list(scores)
        self.calls = 0

    def initialize(self, rgb, thermal, box):
        pass

    def __call__(self, rgb, thermal, box_a, box_m):
        self.calls += 1
        return self.scores.pop(0) if self.scores else (20.0, 0.0)
