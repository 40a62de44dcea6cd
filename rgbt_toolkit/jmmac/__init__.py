"""The JMMAC RGB-T tracker: two ECO appearance trackers fused by MFNet, camera motion estimation, target motion
prediction with the Algorithm-1 switcher, and bounding-box refinement, in the paper's per-frame order."""

from rgbt_toolkit.jmmac.config import PRESETS, JmmacConfig, preset
from rgbt_toolkit.jmmac.pipeline import FrameResult, JmmacTracker

__all__ = ["PRESETS", "FrameResult", "JmmacConfig", "JmmacTracker", "preset"]
