"""Accuracy and speed of the motion parts (CME, Kalman, PSR, DDIS, switcher) at 640x480, printed as Markdown tables.

Usage: ``python benchmarks/bench_motion.py [--threads 1] [--seeds 5] [--shared ../shared]``.

1. CME model comparison: band-limited random "thermal" frames warped by a known translation, similarity, affine or
   projective camera motion, with an independently moving object (outlier matches); each estimator model is scored
   by the mean transfer error over a grid of points (pixels), as the paper compares motion models.
2. Per-module time per call (minimum and median over repeats).
3. With ``--shared``: the frame-difference trigger on the real static-camera OTB "Crossing" frames (should stay off)
   and on the same frames with a synthetic camera pan (should fire).
The machine is shared; the load average is printed with the times.
"""

from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.motion import (
    FAST_CAMERA_MOTION,
    MOTION_MODELS,
    CameraMotionEstimator,
    CameraMotionSettings,
    CameraMotionTrigger,
    ConstantVelocityKalman,
    TrackerSwitcher,
    apply_transform,
    build_motion_parts,
    max_psr,
)
from rgbt_toolkit.runtime import set_threads


def texture(h: int, w: int, seed: int, channels: int = 1) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (h, w) if channels == 1 else (h, w, channels)
    img = np.zeros(shape)
    for sigma in (2, 5, 11):
        img += cv2.GaussianBlur(rng.normal(size=shape), (0, 0), sigma) * sigma
    return ((img - img.min()) / (img.max() - img.min()) * 255).astype(np.uint8)


def true_motion(kind: str, rng: np.random.Generator) -> np.ndarray:
    t = rng.uniform(-15, 15, 2)
    if kind == "translation":
        return np.array([[1, 0, t[0]], [0, 1, t[1]], [0, 0, 1.0]])
    if kind == "similarity":
        a, s = rng.uniform(-0.05, 0.05), rng.uniform(0.95, 1.05)
        c, n = s * np.cos(a), s * np.sin(a)
        return np.array([[c, -n, t[0]], [n, c, t[1]], [0, 0, 1.0]])
    lin = np.eye(2) + rng.uniform(-0.04, 0.04, (2, 2))
    m = np.array([[*lin[0], t[0]], [*lin[1], t[1]], [0, 0, 1.0]])
    if kind == "projective":
        m[2, :2] = rng.uniform(-4e-5, 4e-5, 2)
    return m


def cme_table(seeds: int) -> str:
    grid = np.stack(np.meshgrid(np.linspace(40, 600, 8), np.linspace(40, 440, 6)), -1).reshape(-1, 2)
    estimators = {m: CameraMotionEstimator(CameraMotionSettings(model=m)) for m in MOTION_MODELS}
    fast = "affine, SIFT at 0.5x, 500 keypoints"
    estimators[fast] = CameraMotionEstimator(CameraMotionSettings(downscale=0.5, max_keypoints=500))
    estimators["affine, corner flow at 0.5x (tracker default)"] = CameraMotionEstimator(FAST_CAMERA_MOTION)
    errors = {(k, m): [] for k in MOTION_MODELS for m in estimators}
    times = {m: [] for m in estimators}
    for seed in range(seeds):
        rng = np.random.default_rng(seed)
        prev = texture(480, 640, 100 + seed)
        for kind in MOTION_MODELS:
            truth = true_motion(kind, rng)
            cur = cv2.warpPerspective(prev, truth, (640, 480), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
            cur[180:300, 260:380] = texture(120, 120, 999 + seed)  # an object moving on its own
            for model, est in estimators.items():
                start = time.process_time()
                res = est.estimate(prev, cur)
                times[model].append(time.process_time() - start)
                err = np.linalg.norm(apply_transform(res.matrix, grid) - apply_transform(truth, grid), axis=1)
                errors[(kind, model)].append(float(err.mean()) if res.valid else float("inf"))
    lines = ["| true motion \\ model | " + " | ".join(estimators) + " |", "|---" * (len(estimators) + 1) + "|"]
    for kind in MOTION_MODELS:
        cells = [f"{np.mean(errors[(kind, m)]):.2f}" for m in estimators]
        lines.append(f"| {kind} | " + " | ".join(cells) + " |")
    lines.append("| CPU time per estimate (ms, median) | " + " | ".join(
        f"{1000 * statistics.median(times[m]):.0f}" for m in estimators) + " |")
    return "\n".join(lines)


def _time(fn, repeat: int) -> tuple[float, float, float]:
    """Wall-clock minimum and median, and the median CPU time (closer to an idle machine's wall time when the
    machine is shared, since the code runs on one thread)."""
    times, cpu = [], []
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        fn()
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return 1000 * min(times), 1000 * statistics.median(times), 1000 * statistics.median(cpu)


def timing_table(repeat: int) -> str:
    rgb, thermal = texture(480, 640, 1, 3), texture(480, 640, 2)
    shifted = cv2.warpAffine(thermal, np.float32([[1, 0, 9], [0, 1, -6]]), (640, 480), borderMode=cv2.BORDER_REFLECT)
    trigger = CameraMotionTrigger()
    trigger.update(rgb, thermal)
    est = CameraMotionEstimator()
    est_half = CameraMotionEstimator(CameraMotionSettings(downscale=0.5, max_keypoints=500))
    est_flow = CameraMotionEstimator(FAST_CAMERA_MOTION)

    def fresh(e):
        e.estimate(thermal, shifted)

    previous_kps = est.keypoints(thermal)

    def consecutive():  # previous frame's keypoints kept from the last frame, as CameraMotionCompensation does
        est.estimate_keypoints(previous_kps, est.keypoints(shifted), None, (480, 640))

    kf = ConstantVelocityKalman()
    kf.initialize((320.0, 240.0))
    response = np.random.default_rng(0).random((7, 63, 63))
    deep = build_motion_parts()["template"]
    colour = build_motion_parts(features="colour")["template"]
    box = np.array([300.0, 200.0, 40.0, 80.0])
    deep.initialize(rgb, thermal, box)
    colour.initialize(rgb, thermal, box)
    switcher = TrackerSwitcher()
    rows = [
        ("frame-difference trigger (RGB + T)", lambda: trigger.update(rgb, thermal)),
        ("CME estimate, SIFT on both frames", lambda: fresh(est)),
        ("CME estimate, previous keypoints cached", consecutive),
        ("CME estimate, SIFT at 0.5x, 500 keypoints, both frames", lambda: fresh(est_half)),
        ("CME estimate, corner flow at 0.5x (tracker default)", lambda: fresh(est_flow)),
        ("Kalman predict + correct", lambda: kf.step(np.array([321.0, 241.0]))),
        ("MAX-PSR, 7 scales x 63 x 63", lambda: max_psr(response)),
        ("DDIS s_A + s_M, default deep features (crop, EfficientNet-Lite0 stride 4, 12x12)",
         lambda: deep(rgb, thermal, box, box + 3.0)),
        ("DDIS s_A + s_M, colour cells (crop, 3x3 colour cells, 16x16)",
         lambda: colour(rgb, thermal, box, box + 3.0)),
        ("switcher decision", lambda: switcher.decide(150.0, 20.0, 10.0)),
    ]
    lines = ["| module (640x480) | wall min ms | wall median ms | CPU median ms |", "|---|---|---|---|"]
    for name, fn in rows:
        fn()
        lo, med, cpu = _time(fn, repeat)
        lines.append(f"| {name} | {lo:.2f} | {med:.2f} | {cpu:.2f} |")
    return "\n".join(lines)


def real_trigger(shared: Path) -> str:
    from rgbt_toolkit.io.images import list_images, read_image

    folder = shared / "data/tracking/sequences/OTB_Crossing/img"
    frames = [read_image(p) for p in list_images(folder)]
    still = CameraMotionTrigger()
    fired = [still.update(f, f).triggered for f in frames]
    panned = CameraMotionTrigger()
    pan_fired = []
    for k, f in enumerate(frames):
        x = 4 * k % 40  # the camera pans 4 px per frame, back and forth over 40 px
        crop = f[:, x : x + 300]
        pan_fired.append(panned.update(crop, crop).triggered)
    return (f"| OTB Crossing (static camera, {len(frames)} frames) | {sum(fired[1:])} of {len(frames) - 1} |\n"
            f"| same frames, camera panning 4 px / frame | {sum(pan_fired[1:])} of {len(frames) - 1} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=20)
    parser.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared"))
    args = parser.parse_args()
    set_threads(args.threads)
    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() else "?"
    print(f"threads {args.threads}, load average {load}\n")
    print("### CME: mean transfer error (px) of each model on each true camera motion\n")
    print(cme_table(args.seeds), "\n")
    print("### Time per call\n")
    print(timing_table(args.repeat), "\n")
    shared = Path(args.shared)
    if (shared / "data/tracking/sequences/OTB_Crossing").is_dir():
        print("### Frame-difference trigger on real frames\n")
        print("| input | frames triggered |\n|---|---|")
        print(real_trigger(shared))


if __name__ == "__main__":
    main()
