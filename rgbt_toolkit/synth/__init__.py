"""Synthetic paired RGB-T scenes with exact ground truth for both cameras.

The generator exists so every part of JMMAC can be tested and benchmarked without third-party data: each challenge
the paper targets (occlusion, camera motion, low light, thermal crossover, fast motion, scale change, distractors,
sensor degradations), and what real footage adds (gimbal jumps, a target leaving the view or hidden for seconds,
real sensor artefacts, small far targets in the sky), can be switched on by name, and the output records the truth
(boxes in both cameras, the RGB->T homography, per-frame challenge flags and absence).
"""

from rgbt_toolkit.synth.config import CHALLENGES, SceneConfig
from rgbt_toolkit.synth.render import RenderedFrame, SceneRenderer
from rgbt_toolkit.synth.writer import generate_scene, write_scene_sequence, write_scene_videos

__all__ = [
    "CHALLENGES",
    "RenderedFrame",
    "SceneConfig",
    "SceneRenderer",
    "generate_scene",
    "write_scene_sequence",
    "write_scene_videos",
]
