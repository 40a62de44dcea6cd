"""ECO benchmark: success AUC against OpenCV's CSRT and TrackerNano, speed at 640x480, colour-names comparison.

Usage::

    python benchmarks/bench_eco.py [--shared ../shared] [--deep] [--out docs/benchmarks_eco.md]

All trackers run on the same frames in the same process with one thread each (``set_threads(1)``). Success AUC is
the mean over IoU thresholds 0, 0.05, ..., 1 of the fraction of frames (after the first) whose IoU exceeds the
threshold. Timings are wall clock and, because the machine is shared, also process CPU time (the figure that does
not depend on other jobs); ``/proc/loadavg`` is printed with them.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.eco import EcoTracker, preset
from rgbt_toolkit.runtime import set_threads

THRESHOLDS = np.linspace(0, 1, 21)


def iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """IoU of (N, 4) x, y, w, h boxes (continuous coordinates)."""
    x1 = np.maximum(a[:, 0], b[:, 0])
    y1 = np.maximum(a[:, 1], b[:, 1])
    x2 = np.minimum(a[:, 0] + a[:, 2], b[:, 0] + b[:, 2])
    y2 = np.minimum(a[:, 1] + a[:, 3], b[:, 1] + b[:, 3])
    inter = np.clip(x2 - x1, 0, None) * np.clip(y2 - y1, 0, None)
    return inter / (a[:, 2] * a[:, 3] + b[:, 2] * b[:, 3] - inter)


def success_auc(pred: np.ndarray, gt: np.ndarray) -> float:
    o = iou(pred[1:], gt[1:])
    return float(np.mean([(o > t).mean() for t in THRESHOLDS]))


class EcoRunner:
    def __init__(self, name: str, params):
        self.name, self.params = name, params
        self.stages = {"features": 0.0, "detection": 0.0, "update": 0.0}

    def start(self, frame, box):
        self.t = EcoTracker(self.params)
        self.t.initialize(frame, box)

    def step(self, frame):
        r = self.t.track(frame)
        for k in self.stages:
            self.stages[k] += r.timings.get(k, 0.0)
        return r.box


class CvRunner:
    def __init__(self, name: str, factory):
        self.name, self.factory, self.stages = name, factory, {}

    @staticmethod
    def _bgr(frame):
        return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else frame[..., ::-1].copy()

    def start(self, frame, box):
        self.t = self.factory()
        self.t.init(self._bgr(frame), tuple(int(round(v)) for v in box))
        self.last = np.asarray(box, float)

    def step(self, frame):
        ok, b = self.t.update(self._bgr(frame))
        if ok:
            self.last = np.asarray(b, float)
        return self.last


def run(runner, frames, init):
    """Boxes, wall seconds and CPU seconds over the frames after the first."""
    runner.start(frames[0], init)
    boxes = [np.asarray(init, float)]
    w0, c0 = time.perf_counter(), time.process_time()
    for f in frames[1:]:
        boxes.append(runner.step(f))
    return np.array(boxes), time.perf_counter() - w0, time.process_time() - c0


def load_crossing(shared: Path):
    from rgbt_toolkit.io.images import list_images, read_image

    seq = shared / "data/tracking/sequences/OTB_Crossing"
    frames = [read_image(p) for p in list_images(seq / "img")]
    gt = np.loadtxt(seq / "groundtruth_rect.txt")
    gt[:, :2] -= 1  # OTB files are 1-based
    return frames, gt


def generated(challenge: str | None, modality: str, seed: int = 1):
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig(challenges=frozenset([challenge] if challenge else []), seed=seed)
    r = SceneRenderer(cfg)
    n, fps = (cfg.rgb_frame_count, cfg.rgb_fps) if modality == "rgb" else (cfg.t_frame_count, cfg.t_fps)
    rendered = [r.render(i / fps, modality, i) for i in range(n)]
    return [f.image for f in rendered], np.array([f.box for f in rendered])


def runners(shared: Path, deep: bool, fdsst: bool = False):
    nano = cv2.TrackerNano_Params()
    nano.backbone = str(shared / "models/nanotrack_backbone_sim.onnx")
    nano.neckhead = str(shared / "models/nanotrack_head_sim.onnx")
    out = [EcoRunner("ECO-hc", preset("hc"))]
    if fdsst:
        out.append(EcoRunner("ECO-hc+fDSST", preset("hc").with_(scale_filter=True)))
    if deep:
        out.append(EcoRunner("ECO-deep", preset("deep")))
    out += [CvRunner("CSRT", cv2.TrackerCSRT_create), CvRunner("Nano", lambda: cv2.TrackerNano_create(nano))]
    return out


def accuracy_table(shared: Path, deep: bool, challenges: list[str], fdsst: bool = False) -> list[str]:
    seqs = [("OTB_Crossing (rgb)",) + load_crossing(shared)]
    for ch in challenges:
        for mod in ("rgb", "t"):
            seqs.append((f"synth {ch or 'plain'} ({mod})",) + generated(ch, mod))
    rs = runners(shared, deep, fdsst)
    lines = ["| sequence | frames | " + " | ".join(r.name for r in rs) + " |",
             "|---|---:|" + "---:|" * len(rs)]
    totals = np.zeros(len(rs))
    for name, frames, gt in seqs:
        aucs = [success_auc(run(r, frames, gt[0])[0], gt) for r in rs]
        totals += aucs
        lines.append(f"| {name} | {len(frames)} | " + " | ".join(f"{a:.3f}" for a in aucs) + " |")
        print(lines[-1], flush=True)
    lines.append("| **mean** | | " + " | ".join(f"**{t / len(seqs):.3f}**" for t in totals) + " |")
    return lines


def speed_table(shared: Path, deep: bool, n_frames: int = 60, fdsst: bool = False) -> list[str]:
    frames, gt = load_crossing(shared)
    sx, sy = 640 / frames[0].shape[1], 480 / frames[0].shape[0]
    big = [cv2.resize(f, (640, 480), interpolation=cv2.INTER_LINEAR) for f in frames[:n_frames]]
    init = gt[0] * [sx, sy, sx, sy]
    rs = runners(shared, deep, fdsst)
    rows, csrt = [], None
    for r in rs:
        _, wall, cpu = run(r, big, init)
        n = len(big) - 1
        # stage timers are wall clock; scaled by CPU/wall they estimate the CPU ms of each stage
        stages = ", ".join(f"{k} {1000 * v / n * cpu / wall:.1f}" for k, v in r.stages.items()) if r.stages else ""
        rows.append((r.name, n / wall, n / cpu, stages))
        if r.name == "CSRT":
            csrt = (n / wall, n / cpu)
    lines = ["| tracker | frames/s (wall) | frames/s (CPU time) | vs CSRT (CPU) | CPU ms/frame by stage |",
             "|---|---:|---:|---:|---|"]
    for name, fw, fc, st in rows:
        lines.append(f"| {name} | {fw:.1f} | {fc:.1f} | {fc / csrt[1]:.2f}x | {st} |")
        print(lines[-1], flush=True)
    return lines


def colour_names_table(shared: Path) -> list[str]:
    from scipy.io import loadmat

    from rgbt_toolkit.features.colornames import own_table, table_index

    ref_path = shared / "models/colornames_tables/CNnorm.mat"
    ref = loadmat(ref_path)["CNnorm"].astype(np.float64)
    frames, gt = load_crossing(shared)
    synth_frames = generated(None, "rgb")[0] + generated("low_light", "rgb")[0]

    def r2(idx):
        a = np.c_[own_table()[idx], np.ones(idx.size)]
        coef = np.linalg.lstsq(a, ref[idx], rcond=None)[0]
        res = ref[idx] - a @ coef
        return 1 - (res**2).sum() / ((ref[idx] - ref[idx].mean(0)) ** 2).sum()

    all_idx = np.arange(ref.shape[0])
    cross_idx = np.concatenate([table_index(f).ravel() for f in frames[::10]])
    syn_idx = np.concatenate([table_index(f).ravel() for f in synth_frames[::10]])
    lines = ["| comparison with CNnorm.mat | value |", "|---|---:|",
             f"| R^2 of the best linear map own -> CNnorm, all 32768 table cells | {r2(all_idx):.3f} |",
             f"| same, weighted by the pixels of OTB_Crossing (every 10th frame) | {r2(cross_idx):.3f} |",
             f"| same, generated RGB frames (plain + low light) | {r2(syn_idx):.3f} |"]
    user = preset("hc").with_(colour_table=str(ref_path))
    own_auc = success_auc(run(EcoRunner("own", preset("hc")), frames, gt[0])[0], gt)
    ref_auc = success_auc(run(EcoRunner("ref", user), frames, gt[0])[0], gt)
    fhog_only = success_auc(run(EcoRunner("fhog", preset("hc").with_(features=("fhog",))), frames, gt[0])[0], gt)
    lines += [f"| ECO-hc success AUC on OTB_Crossing with the own table | {own_auc:.3f} |",
              f"| ECO-hc success AUC on OTB_Crossing with CNnorm.mat (user table) | {ref_auc:.3f} |",
              f"| ECO with fHOG only (no colour feature) | {fhog_only:.3f} |"]
    for ln in lines[2:]:
        print(ln, flush=True)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared")
    ap.add_argument("--deep", action="store_true", help="also run the deep preset")
    ap.add_argument("--fdsst", action="store_true", help="also run ECO-hc with the fDSST scale filter")
    ap.add_argument("--quick", action="store_true", help="only OTB_Crossing and the plain generated scene")
    ap.add_argument("--out", type=Path, default=None, help="write the tables as markdown here")
    args = ap.parse_args()
    set_threads(1)
    from rgbt_toolkit.synth import CHALLENGES

    challenges = [None] + ([] if args.quick else list(CHALLENGES))
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
    print("load average", " ".join(load), flush=True)
    acc = accuracy_table(args.shared, args.deep, challenges, args.fdsst)
    spd = speed_table(args.shared, args.deep, fdsst=args.fdsst)
    load_after = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
    cn = colour_names_table(args.shared)
    if args.out:
        from rgbt_toolkit._atomic import write_text_atomic

        text = "\n".join(["## Success AUC (same frames, same init)", "", *acc, "",
                          f"## Speed at 640x480, one thread (load average before/after: {' '.join(load)} / "
                          f"{' '.join(load_after)} on 2 cores)", "", *spd, "",
                          "## Own colour names vs the original table", "", *cn, ""])
        write_text_atomic(args.out, text)


if __name__ == "__main__":
    main()
