"""Accuracy and speed of bounding-box refinement, printed as Markdown tables.

Usage: ``python benchmarks/bench_refinement.py [--threads 1] [--seeds 3] [--shared ../shared]``.

1. Regressor accuracy: generated scenes (several challenges, ``--seeds`` seeds each, 320x240); the regressor is
   trained on frame 1, then on 20 later frames the true box is perturbed (three strengths, directions alternating)
   and refined. Reported: mean IoU with the truth before (= the identity refiner) and after, the share of frames
   improved, and how often the sanity limits refused the correction.
2. With ``--shared``: the same on the real OTB "Crossing" sequence (a pedestrian, 120 frames), for the regressor
   and for FastestDet (frame-1 gating off, since the authors' rule turns it off there); and ECO on the visible
   stream alone (the B-RGB variant of the pipeline) with no refinement, the regressor, and FastestDet.
3. Speed: frame-1 training and per-frame refinement at 320x240 and 640x480 (wall median and CPU time per call);
   with ``--shared``, the FastestDet refiner per frame on a VIFB image.
The machine is shared; the load average is printed with the times.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np

from rgbt_toolkit.refinement import DetectorRefiner, OnnxYoloDetector, RegressionRefiner
from rgbt_toolkit.refinement.boxes import centres, from_centres, iou
from rgbt_toolkit.runtime import set_threads
from rgbt_toolkit.synth import SceneConfig, SceneRenderer

# (name, centre shift as a fraction of the size, side scale, aspect change)
PERTURBATIONS = [("strong: 15%, x1.3, aspect x1.15", 0.15, 1.3, 1.15), ("mild: 5%, x1.1, aspect x1.05", 0.05, 1.1, 1.05),
                 ("none (exact box)", 0.0, 1.0, 1.0)]
CHALLENGES = ["scale_change", "fast_motion", "distractor_color", "degradation"]


def perturb(box: np.ndarray, k: int, shift: float, scale: float, aspect: float) -> np.ndarray:
    sign = np.array([1, -1]) if k % 2 else np.array([-1, 1])
    s = scale if (k // 2) % 2 else 1 / scale
    a = aspect if (k // 4) % 2 else 1 / aspect
    size = box[2:] * s * np.array([np.sqrt(a), 1 / np.sqrt(a)])
    return from_centres(centres(box) + shift * sign * box[2:], size)


def accuracy(seeds: int) -> None:
    print("| scene | perturbation | IoU before | IoU after | improved | refused | enabled |")
    print("|---|---|---|---|---|---|---|")
    totals: dict[str, list[np.ndarray]] = {p[0]: [] for p in PERTURBATIONS}
    for challenge in CHALLENGES:
        rows = {p[0]: [[], [], 0] for p in PERTURBATIONS}
        enabled = 0
        for seed in range(1, seeds + 1):
            r = SceneRenderer(SceneConfig(seed=seed, challenges=frozenset({challenge})))
            f0 = r.render(0.0, "rgb", 0)
            ref = RegressionRefiner(seed=0)
            ref.initialize(f0.image, f0.box)
            enabled += ref.enabled
            for k in range(3, r.config.rgb_frame_count, 3):
                f = r.render(k / r.config.rgb_fps, "rgb", k)
                for name, shift, scale, aspect in PERTURBATIONS:
                    box = perturb(f.box, k, shift, scale, aspect)
                    out = ref.refine(f.image, box)
                    before = iou(box, f.box)
                    rows[name][0].append(before)
                    rows[name][1].append(iou(out, f.box) if out is not None else before)
                    rows[name][2] += out is None
        for name, (b, a, refused) in rows.items():
            b, a = np.array(b), np.array(a)
            totals[name].append(np.stack([b, a]))
            print(f"| {challenge} | {name} | {b.mean():.3f} | {a.mean():.3f} | {np.mean(a > b):.0%} | "
                  f"{refused / len(b):.0%} | {enabled}/{seeds} |")
    for name, parts in totals.items():
        b, a = np.concatenate(parts, axis=1)
        print(f"| **all** | {name} | **{b.mean():.3f}** | **{a.mean():.3f}** | {np.mean(a > b):.0%} | | |")


def crossing(shared: Path) -> None:
    from rgbt_toolkit.io.images import list_images, read_image
    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.jmmac.config import preset
    from rgbt_toolkit.refinement import DetectorRefinerSettings

    folder = shared / "data/tracking/sequences/OTB_Crossing"
    frames = [read_image(f) for f in list_images(folder / "img")]
    truth = np.loadtxt(folder / "groundtruth_rect.txt", delimiter=None)
    truth[:, :2] -= 1  # OTB files are 1-based
    model = shared / "models/FastestDet.onnx"

    def refiners():
        return {"regressor": RegressionRefiner(seed=0),
                "FastestDet": DetectorRefiner(OnnxYoloDetector(model),
                                              DetectorRefinerSettings(require_initial_detection=False))}

    print("\n| OTB Crossing | perturbation | IoU before | IoU after | improved | refused |")
    print("|---|---|---|---|---|---|")
    for name, ref in refiners().items():
        ref.initialize(frames[0], truth[0])
        for pname, shift, scale, aspect in PERTURBATIONS:
            b, a, refused = [], [], 0
            for k in range(2, len(frames), 3):
                box = perturb(truth[k], k, shift, scale, aspect)
                out = ref.refine(frames[k], box)
                b.append(iou(box, truth[k]))
                a.append(iou(out, truth[k]) if out is not None else b[-1])
                refused += out is None
            b, a = np.array(b), np.array(a)
            print(f"| {name} | {pname} | {b.mean():.3f} | {a.mean():.3f} | {np.mean(a > b):.0%} | "
                  f"{refused / len(b):.0%} |")
    print("\n| OTB Crossing, ECO on RGB (B-RGB) | mean IoU | frames refined |")
    print("|---|---|---|")
    for name, ref in [("no refinement", None), *refiners().items()]:
        tracker = build_tracker(preset("B-RGB", refine=ref is not None))
        tracker.refiner = ref
        tracker.initialize(frames[0], frames[0][:, :, 0], truth[0])
        results = [tracker.track(f, f[:, :, 0]) for f in frames[1:]]
        ious = [iou(r.box, t) for r, t in zip(results, truth[1:])]
        print(f"| {name} | {np.mean(ious):.3f} | {sum(r.refined for r in results)}/{len(results)} |")


def timed(fn, repeats: int) -> tuple[float, float]:
    """(median wall ms, mean CPU ms) of ``fn()``."""
    walls = []
    c0 = time.process_time()
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        walls.append(time.perf_counter() - t)
    return statistics.median(walls) * 1e3, (time.process_time() - c0) / repeats * 1e3


def speed(shared: Path | None) -> None:
    print(f"\nload average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; torch threads "
          f"{__import__('torch').get_num_threads()}\n")
    print("| refiner | frame | step | wall median (ms) | CPU (ms) |")
    print("|---|---|---|---|---|")
    for size in ((320, 240), (640, 480)):
        r = SceneRenderer(SceneConfig(seed=1, rgb_size=size, challenges=frozenset({"scale_change"})))
        f0, f1 = r.render(0.0, "rgb", 0), r.render(0.5, "rgb", 7)
        ref = RegressionRefiner(seed=0)
        ref.initialize(f0.image, f0.box)  # warm-up (backbone load)
        wall, cpu = timed(lambda: ref.initialize(f0.image, f0.box), 3)
        print(f"| regressor | {size[0]}x{size[1]} | frame-1 training | {wall:.0f} | {cpu:.0f} |")
        box = perturb(f1.box, 1, 0.15, 1.3, 1.15)
        wall, cpu = timed(lambda: ref.refine(f1.image, box), 50)
        print(f"| regressor | {size[0]}x{size[1]} | refine | {wall:.1f} | {cpu:.1f} |")
    if shared is not None:
        from rgbt_toolkit.io.images import read_image

        image = read_image(shared / "data/fusion/vifb/VI/running.jpg")
        person = np.array([41.0, 135.0, 22.0, 54.0])
        ref = DetectorRefiner(OnnxYoloDetector(shared / "models/FastestDet.onnx"))
        ref.initialize(image, person)
        wall, cpu = timed(lambda: ref.refine(image, person + [3, -4, 2, 2]), 30)
        h, w = image.shape[:2]
        print(f"| FastestDet (352x352) | {w}x{h} | refine | {wall:.1f} | {cpu:.1f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--shared", type=Path, default=None, help="../shared, for the FastestDet timing")
    args = ap.parse_args()
    set_threads(args.threads)
    accuracy(args.seeds)
    if args.shared is not None:
        crossing(args.shared)
    speed(args.shared)


if __name__ == "__main__":
    main()
