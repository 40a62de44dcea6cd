"""Does target motion prediction (Kalman + Algorithm 1 + our calibration) help where it should, and not hurt elsewhere?

Usage: ``python benchmarks/bench_tmp.py [--seeds 2] [--fusion average] [--challenges occlusion,low_light,...]``.

Runs the assembled JMMAC tracker (``rgbt_toolkit.jmmac.api.build_tracker``) on generated aligned RGB-T scenes, once
as ``+CME`` (no TMP) and once as ``+TMP`` (same parts plus Kalman, MAX-PSR, DDIS and the switcher), box refinement
off, and prints the mean IoU, the success rate at IoU 0.5 and the share of frames in motion mode. ``average`` fusion
keeps the run independent of MFNet's weights; ``--fusion mfnet`` uses the shipped network.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from rgbt_toolkit.jmmac import api
from rgbt_toolkit.jmmac.config import preset
from rgbt_toolkit.runtime import set_threads
from rgbt_toolkit.synth import SceneConfig, SceneRenderer

CHALLENGES = ("occlusion", "low_light", "thermal_crossover", "scale_change", "fast_motion", "camera_motion",
              "appearance_change", "skip_blocks")


def iou(a: np.ndarray, b: np.ndarray) -> float:
    x1, y1 = max(a[0], b[0]), max(a[1], b[1])
    x2, y2 = min(a[0] + a[2], b[0] + b[2]), min(a[1] + a[3], b[1] + b[3])
    inter = max(0.0, x2 - x1) * max(0.0, y2 - y1)
    return inter / (a[2] * a[3] + b[2] * b[3] - inter)


def run(challenge: str, seed: int, variant: str, fusion: str) -> tuple[float, float, float]:
    cfg = SceneConfig.aligned(challenges=frozenset({challenge}), seed=seed, duration=4.0)
    scene = SceneRenderer(cfg)
    tracker = api.build_tracker(preset(variant, fusion=fusion, refine=False))
    ious, motion = [], 0
    for k in range(cfg.rgb_frame_count):
        t = k / cfg.rgb_fps
        rgb, thermal = scene.render(t, "rgb", k), scene.render(t, "t", k)
        if k == 0:
            result = tracker.initialize(rgb.image, thermal.image, rgb.box)
        else:
            result = tracker.track(rgb.image, thermal.image)
            ious.append(iou(result.box, rgb.box))
            motion += result.mode == "motion"
    ious = np.asarray(ious)
    return float(ious.mean()), float((ious > 0.5).mean()), motion / len(ious)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--fusion", default="average")
    parser.add_argument("--challenges", default=",".join(CHALLENGES))
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    set_threads(args.threads)
    start = time.perf_counter()
    print(f"fusion {args.fusion}, {args.seeds} seeds per challenge, 60 frames each, refinement off\n")
    print("| challenge | +CME mean IoU | +TMP mean IoU | +CME success | +TMP success | motion-mode frames |")
    print("|---|---|---|---|---|---|")
    for challenge in args.challenges.split(","):
        cme = np.array([run(challenge, s, "+CME", args.fusion) for s in range(args.seeds)])
        tmp = np.array([run(challenge, s, "+TMP", args.fusion) for s in range(args.seeds)])
        print(f"| {challenge} | {cme[:, 0].mean():.3f} | {tmp[:, 0].mean():.3f} | {cme[:, 1].mean():.2f} | "
              f"{tmp[:, 1].mean():.2f} | {100 * tmp[:, 2].mean():.0f} % |", flush=True)
    print(f"\n({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
