"""Single-camera trackers on real footage: ECO-hc, ECO-hc+cnn, ECO-deep against OpenCV CSRT, KCF and Nano.

Usage::

    python benchmarks/bench_real.py [--shared ../shared] [--sets real,real_more] [--jobs 2] [--trackers ECO-hc,...]
                                    [--folds] [--tune-folds 0,1] [--in-folds 2,3] [--only tune|aside]
                                    [--cache DIR] [--out docs/benchmarks_real.md]

Every sequence in ``../shared/data/tracking/real/`` and ``real_more/`` (116 clips; ``--sets`` picks the folders; the
script exits with a note when one is absent) is decoded with the project's own reader, as ``rgbt track-single``
reads it, and every tracker starts from the ground-truth box of the first frame whose target is present, on the
same frames, one thread each (``--jobs`` processes side by side).

Scores per sequence, over the frames after the initial one whose target is present (``0,0,0,0`` rows are left
out): success AUC (mean over IoU thresholds 0, 0.05, ..., 1 of the fraction of frames whose IoU exceeds the
threshold, in percent), precision at 20 px (centre error <= 20 px, percent) and the size error, the median of
``|log(area_est / area_true)|`` (0.1 is about a 10 % area error).

Every clip belongs to one of 4 folds, fixed by its name and stratified by class (modality x target kind; the rule
is in ``real_folds.py``). The report gives the mean over all clips, over each fold, over each folder and over each
class, and the clips where ECO-hc collapses against ECO-deep. A change tuned on some folds is named with
``--tune-folds``, and the report then gives those folds and the others apart; ``--in-folds`` runs only some folds'
clips, ``--folds`` prints the summary tables without the per-clip ones.

``HELD_ASIDE`` names 9 clips of ``real/`` that were never looked at while tuning on the first 34 clips; ``--only
tune|aside`` runs the 25 others or these 9 (the commands in decisions.md use it), and the report gives their mean.

``--trackers JMMAC,JMMAC+TMP,JMMAC+CME,JMMAC-hc+cnn`` adds `rgbt track`'s tracker (presets default, +TMP, +CME;
the default with ``--features hc+cnn``) with each clip given as both cameras (``run_jmmac``), scored like ours
against the best peer; ``--jmmac JSON`` sets JmmacConfig fields for them (e.g. ``'{"sample_area": [22500,
22500]}'``). Cached boxes are keyed by the tracker's name only (ECO's also by ``--eco``, JMMAC's by ``--jmmac``): use
a fresh ``--cache`` directory after changing the code.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import machine
from real_folds import (COLLAPSE_FLOOR, COLLAPSE_RATIO, class_table, clip_class, collapse_table, folds, group_table,
                        groups, parse_folds)
from rgbt_toolkit.evaluation.metrics import centre_error, iou_continuous

THRESHOLDS = np.linspace(0, 1, 21)
# a few of each kind in real/ (Anti-UAV thermal, Halmstad thermal and visible, each class), chosen by name before
# any run; the 34-clip protocol's held-aside set
HELD_ASIDE = ("antiuav_ir_09", "svan_ir_drone_006", "svan_ir_bird_005", "svan_ir_airplane_003",
              "svan_ir_helicopter_003", "svan_v_drone_006", "svan_v_bird_004", "svan_v_airplane_003",
              "svan_v_helicopter_003")
# the folders under data/tracking/ read by default: the first 34 clips and the 82 more of the same kinds
SETS = ("real", "real_more")
TRACKERS = ("ECO-hc", "ECO-hc+cnn", "ECO-deep", "CSRT", "KCF", "Nano")
# without re-acquisition (rgbt track-single --no-reacquire), and `rgbt track`'s JMMAC with a preset, given the clip
# as both cameras (the real set has no RGB-T pairs; see run_jmmac)
JMMAC_PRESETS = {"JMMAC": "default", "JMMAC+TMP": "+TMP", "JMMAC+CME": "+CME", "JMMAC-hc+cnn": "default"}
# `rgbt track --features F`: the ECO preset of both trackers where it is not the default's hc
JMMAC_FEATURES = {"JMMAC-hc+cnn": "hc+cnn"}
OPTIONAL = ("ECO-hc-noRA", "ECO-hc+cnn-noRA", "ECO-deep-noRA", *JMMAC_PRESETS)


def ours(name: str) -> bool:
    """The project's trackers (scored against the best of the others, the peers)."""
    return name.startswith(("ECO", "JMMAC"))


# --- scores ------------------------------------------------------------------------------------------------------
def scores(pred: np.ndarray, gt: np.ndarray, start: int) -> dict:
    """Success AUC, precision at 20 px (both percent) and median size error over present frames after ``start``."""
    keep = np.arange(len(gt)) > start
    keep &= np.any(gt != 0, axis=1)
    p, g = pred[keep], gt[keep]
    o = iou_continuous(p, g)
    err = centre_error(p, g)
    size = np.abs(np.log(np.maximum(p[:, 2] * p[:, 3], 1e-6) / (g[:, 2] * g[:, 3])))
    return {"success": 100 * float(np.mean([(o > t).mean() for t in THRESHOLDS])),
            "precision": 100 * float((err <= 20).mean()), "size": float(np.median(size))}


# --- trackers ------------------------------------------------------------------------------------------------------
def _bgr(frame: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.cvtColor(frame, cv2.COLOR_GRAY2BGR) if frame.ndim == 2 else np.ascontiguousarray(frame[..., ::-1])


def run_opencv(name: str, frames: list, init: np.ndarray, shared: Path) -> np.ndarray:
    """Boxes of an OpenCV tracker (its last good box held where it reports a failure)."""
    import cv2

    if name == "Nano":
        prm = cv2.TrackerNano_Params()
        prm.backbone = str(shared / "models/nanotrack_backbone_sim.onnx")
        prm.neckhead = str(shared / "models/nanotrack_head_sim.onnx")
        tracker = cv2.TrackerNano_create(prm)
    else:
        tracker = {"CSRT": cv2.TrackerCSRT_create, "KCF": cv2.TrackerKCF_create}[name]()
    tracker.init(_bgr(frames[0]), tuple(int(round(v)) for v in init))
    boxes, last = [init.astype(float)], init.astype(float)
    for f in frames[1:]:
        ok, b = tracker.update(_bgr(f))
        if ok:
            last = np.asarray(b, float)
        boxes.append(last)
    return np.array(boxes)


def run_eco(name: str, frames: list, init: np.ndarray, overrides: dict) -> np.ndarray:
    """Boxes of ``rgbt track-single``'s loop (the library's ``track_frames``) with the named preset; re-acquisition on
    (as ``rgbt track-single`` runs by default) unless the name ends in ``-noRA``."""
    from rgbt_toolkit.eco.params import preset
    from rgbt_toolkit.eco.run import track_frames

    from rgbt_toolkit.eco.reacquire import ReacquireParams

    params = preset(name.removeprefix("ECO-").removesuffix("-noRA"))  # "ECO-hc+cnn" runs the "hc+cnn" preset
    if overrides:
        params = params.with_(**overrides)
    return track_frames(frames, init, params, reacquire=None if name.endswith("-noRA") else ReacquireParams()).boxes


def run_jmmac(name: str, frames: list, init: np.ndarray, config: dict | None = None) -> np.ndarray:
    """Boxes of `rgbt track`'s tracker (the library's JMMAC) with the named preset, given one real clip as both
    cameras: its frames as the visible stream (grey ones repeated on three channels) and their grey copy as the
    thermal one. Fusion has nothing to choose between then, but the motion parts (camera motion, Kalman and
    Algorithm 1, re-acquisition) meet real footage; the visible boxes are scored. ``config``: JmmacConfig
    overrides (``--jmmac``)."""
    import cv2

    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.jmmac.config import preset

    def pair(frame: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        if frame.ndim == 2:
            return cv2.cvtColor(frame, cv2.COLOR_GRAY2RGB), frame
        return frame, cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)

    features = JMMAC_FEATURES.get(name)
    tracker = build_tracker(preset(JMMAC_PRESETS[name], **({"eco_preset": features} if features else {}),
                                   **(config or {})))
    boxes = [tracker.initialize(*pair(frames[0]), init).box]
    boxes += [tracker.track(*pair(f)).box for f in frames[1:]]
    return np.array(boxes, dtype=float)


def load_sequence(folder: Path) -> tuple[list, np.ndarray]:
    """Frames as ``rgbt track-single`` decodes them, and the ground truth (one row per frame)."""
    from rgbt_toolkit.io.frames import open_frames

    video = next(p for p in sorted(folder.iterdir()) if p.stem == "video")
    frames = [f for f, _ in open_frames(video)]
    gt = np.loadtxt(folder / "groundtruth.txt", delimiter=",", ndmin=2)
    n = min(len(frames), len(gt))
    return frames[:n], gt[:n]


def initial_box(gt: np.ndarray, start: int, how: str = "first") -> np.ndarray:
    """The box every tracker starts from: the first label (``first``, the issue's protocol) or, as a diagnostic of
    the labels' own convention, the first label's centre with the median size of the next 10 labels
    (``next-labels``: on some clips the first label is tighter than all that follow, e.g. antiuav_ir_05 9x6 then
    15x10)."""
    box = gt[start].astype(float)
    if how == "first":
        return box
    later = gt[start + 1:][np.any(gt[start + 1:] != 0, axis=1)][:10]
    if not len(later):
        return box
    w, h = np.median(later[:, 2]), np.median(later[:, 3])
    cx, cy = box[0] + box[2] / 2, box[1] + box[3] / 2
    return np.array([cx - w / 2, cy - h / 2, w, h])


def _job(args: tuple) -> tuple[str, str, np.ndarray, float, int]:
    """One sequence through the given trackers in one process: ``(seq, tracker, boxes, seconds, start)`` each."""
    folder, names, shared, overrides, init, jmmac = args
    from rgbt_toolkit.runtime import set_threads

    set_threads(1)
    frames, gt = load_sequence(folder)
    start = int(np.flatnonzero(np.any(gt != 0, axis=1))[0])
    box = initial_box(gt, start, init)
    out = []
    for name in names:
        t0 = time.process_time()
        if name.startswith("ECO"):
            boxes = run_eco(name, frames[start:], box, overrides)
        elif name in JMMAC_PRESETS:
            boxes = run_jmmac(name, frames[start:], box, jmmac)
        else:
            boxes = run_opencv(name, frames[start:], box, shared)
        boxes = np.concatenate([np.repeat(gt[start][None], start, 0), boxes])
        out.append((folder.name, name, boxes, time.process_time() - t0, start))
    return out


# --- table ---------------------------------------------------------------------------------------------------------
def table(results: dict, names: list[str], seqs: list[str], fold_of: dict[str, int],
          rows: list[tuple[str, list[str]]]) -> list[str]:
    """Markdown rows: one per sequence (with its fold), then one mean row per group of ``rows``."""
    peers = [n for n in names if not ours(n)]
    own = [n for n in names if ours(n)]
    head = "| sequence | fold | " + " | ".join(f"{n} succ | {n} prec | {n} size" for n in names)
    head += "".join(f" | {n} ≥ best peer" for n in own) + " |"
    lines = [head, "|---|---:|" + "---:|" * (3 * len(names) + len(own))]
    wins = {n: {} for n in own}
    for s in seqs:
        vals = [results[(s, n)] for n in names]
        best_peer = max((results[(s, p)]["success"] for p in peers), default=np.nan)
        cells = []
        for v in vals:
            cells += [f"{v['success']:.1f}", f"{v['precision']:.1f}", f"{v['size']:.3f}"]
        for n in own:
            wins[n][s] = results[(s, n)]["success"] >= best_peer
            cells.append("yes" if wins[n][s] else "no")
        tag = " (aside)" if s in HELD_ASIDE else ""
        lines.append(f"| {s}{tag} | {fold_of[s]} | " + " | ".join(cells) + " |")
    for label, group in rows:
        cells = []
        for n in names:
            cells += [f"{np.mean([results[(s, n)][k] for s in group]):.1f}" if k != "size" else
                      f"{np.mean([results[(s, n)][k] for s in group]):.3f}" for k in ("success", "precision", "size")]
        for n in own:
            cells.append(f"{sum(wins[n][s] for s in group)}/{len(group)}")
        lines.append(f"| **mean, {label}** | | " + " | ".join(cells) + " |")
    return lines


def with_label_sizes(boxes: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """The tracker's box centres with the labels' widths and heights (its own size where the target is absent)."""
    centres = boxes[:, :2] + boxes[:, 2:] / 2
    sizes = np.where(gt[:, 2:] > 0, gt[:, 2:], boxes[:, 2:])
    return np.hstack([centres - sizes / 2, sizes])


def position_table(tracks: dict, names: list[str], folders: list[Path],
                   groups_: list[tuple[str, list[str]]]) -> list[str]:
    """Success of every tracker's centres with the labels' sizes: how far position alone goes, and how many clips
    each of our trackers would win if every tracker knew the target's size (the size error then counts for nothing)."""
    peers = [n for n in names if not ours(n)]
    starts, rows = {}, {}
    for f in folders:
        gt = np.loadtxt(f / "groundtruth.txt", delimiter=",", ndmin=2)
        starts[f.name] = int(np.flatnonzero(np.any(gt != 0, axis=1))[0])
        for n in names:
            if (f.name, n) in tracks:
                b = tracks[(f.name, n)]
                rows[(f.name, n)] = scores(with_label_sizes(b, gt[:len(b)]), gt[:len(b)], starts[f.name])["success"]
    lines = ["| set | " + " | ".join(names) + " | " + " | ".join(f"{n} ≥ best peer" for n in names
                                                           if ours(n)) + " |",
             "|---|" + "---:|" * (len(names) + sum(ours(n) for n in names))]
    for label, group in groups_:
        cells = [f"{np.mean([rows[(s, n)] for s in group]):.1f}" for n in names]
        for n in (n for n in names if ours(n)):
            won = sum(rows[(s, n)] >= max((rows[(s, p)] for p in peers), default=-1) for s in group)
            cells.append(f"{won}/{len(group)}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return lines


def frames_to_reacquire(boxes: np.ndarray, gt: np.ndarray, jump: int, end: int, tolerance: float = 20.0) -> int | None:
    """Frames from a shot cut at ``jump`` until the centre error is within ``tolerance`` px for 5 frames in a row
    (frames with an absent target skipped); None when that does not happen before ``end``."""
    on = (centre_error(boxes, gt) <= tolerance) | ~np.any(gt != 0, axis=1)
    for k in range(jump, max(jump, end - 4)):
        if on[k:k + 5].all():
            return k - jump
    return None


def reacquisition_table(tracks: dict, names: list[str], folders: list[Path]) -> list[str]:
    """Per shot cut (``box_jumps`` in meta.json): frames until each of our trackers is back on the target."""
    own = [n for n in names if ours(n)]
    lines = ["| sequence | cut at frame | " + " | ".join(own) + " |", "|---|---:|" + "---:|" * len(own)]
    for f in folders:
        jumps = json.loads((f / "meta.json").read_text()).get("box_jumps", []) if (f / "meta.json").is_file() else []
        gt = np.loadtxt(f / "groundtruth.txt", delimiter=",", ndmin=2)
        for i, jump in enumerate(jumps):
            end = jumps[i + 1] if i + 1 < len(jumps) else len(gt)
            cells = []
            for n in own:
                if (f.name, n) not in tracks:
                    cells.append("-")
                    continue
                back = frames_to_reacquire(tracks[(f.name, n)], gt[:len(tracks[(f.name, n)])], jump, end)
                cells.append("never" if back is None else str(back))
            lines.append(f"| {f.name} | {jump} | " + " | ".join(cells) + " |")
    return lines


def summary(results: dict, names: list[str], seqs: list[str]) -> list[str]:
    """The issue's goals, checked on the means over all sequences."""
    peers = [n for n in names if not ours(n)]
    mean = {n: float(np.mean([results[(s, n)]["success"] for s in seqs])) for n in names}
    size = {n: float(np.mean([results[(s, n)]["size"] for s in seqs])) for n in names}
    out = []
    if peers:
        best = max(peers, key=mean.get)
        best_size = min(size[p] for p in peers)
        out.append(f"best peer by mean success: {best} {mean[best]:.1f}; lowest peer size error {best_size:.4f}")
        for n in (n for n in names if ours(n)):
            # four decimals: the goal (size error at most the best peer's) has been decided in the fourth
            verdict = "<=" if size[n] <= best_size else ">"
            # the 80 % clause read both ways: against the per-clip best of all peers (the table's last columns)
            # and against the best single peer by mean
            single = sum(results[(s, n)]["success"] >= results[(s, best)]["success"] for s in seqs)
            out.append(f"{n}: mean success {mean[n]:.1f} ({mean[n] - mean[best]:+.1f} vs {best}), "
                       f"size error {size[n]:.4f} ({verdict} the lowest peer's); at or above {best} on "
                       f"{single} of {len(seqs)} sequences")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared")
    ap.add_argument("--jobs", type=int, default=2, help="processes side by side (one thread each)")
    ap.add_argument("--trackers", default=",".join(TRACKERS), help="comma-separated subset of " + ", ".join(TRACKERS))
    ap.add_argument("--only", choices=("tune", "aside"), default=None,
                    help="run only the 25 tuning or the 9 held-aside clips of real/ (the 34-clip protocol)")
    ap.add_argument("--in-folds", default=None, help="run only the clips of these folds, e.g. 0,1")
    ap.add_argument("--tune-folds", default=None,
                    help="the folds a change was tuned on, e.g. 0,1: the report gives them and the others apart")
    ap.add_argument("--folds", action="store_true",
                    help="print the per-fold, per-class and collapse tables only, not the per-clip ones")
    ap.add_argument("--sequences", default=None, help="comma-separated sequence names (default: all)")
    ap.add_argument("--eco", default="{}", help="JSON of EcoParams overrides for both ECO presets (tuning)")
    ap.add_argument("--jmmac", default="{}", help="JSON of JmmacConfig overrides for the JMMAC trackers (tuning)")
    ap.add_argument("--cache", type=Path, default=None,
                    help="keep each tracker's boxes here and reuse them (keyed by --eco and --jmmac too)")
    ap.add_argument("--init", choices=("first", "next-labels"), default="first",
                    help="start every tracker from the first label (default) or, as a diagnostic, from its centre "
                         "with the median size of the next 10 labels")
    ap.add_argument("--out", type=Path, default=None, help="write the table as markdown here")
    ap.add_argument("--sets", default=",".join(SETS), help="comma-separated folders under data/tracking/ to read "
                    "(default: " + ",".join(SETS) + ")")
    args = ap.parse_args()
    roots = [args.shared / "data/tracking" / s.strip() for s in args.sets.split(",") if s.strip()]
    missing = [r for r in roots if not r.is_dir()]
    if missing:
        print(f"skipped: {missing[0]} is absent (real sequences are in ../shared, not in the repository)")
        return
    names = [n.strip() for n in args.trackers.split(",") if n.strip()]
    unknown = [n for n in names if n not in TRACKERS + OPTIONAL]
    if unknown:
        sys.exit(f"unknown tracker {unknown[0]!r}; choose from {', '.join(TRACKERS + OPTIONAL)}")
    folders = sorted((p for r in roots for p in r.iterdir() if (p / "groundtruth.txt").is_file()),
                     key=lambda p: p.name)
    where = {f.name: f for f in folders}
    # the split is made on every clip of the default folders, whichever --sets reads, so a clip's fold never
    # depends on the options
    every = {p.name for s in SETS if (args.shared / "data/tracking" / s).is_dir()
             for p in (args.shared / "data/tracking" / s).iterdir() if (p / "groundtruth.txt").is_file()}
    fold_of = folds(sorted(every | set(where)))
    try:
        tuned, wanted_folds = parse_folds(args.tune_folds), parse_folds(args.in_folds)
    except ValueError as e:
        sys.exit(str(e))
    if wanted_folds:
        folders = [f for f in folders if fold_of[f.name] in wanted_folds]
    if args.sequences:
        wanted = set(args.sequences.split(","))
        folders = [f for f in folders if f.name in wanted]
    if args.only:
        folders = [f for f in folders if f.parent.name == "real" and (f.name in HELD_ASIDE) == (args.only == "aside")]
    overrides = json.loads(args.eco)
    key = json.dumps(overrides, sort_keys=True)
    jmmac = json.loads(args.jmmac)
    jmmac_key = json.dumps(jmmac, sort_keys=True)

    def cached(seq: str, name: str) -> Path | None:
        if args.cache is None:
            return None
        tag = "" if not name.startswith("ECO") or not overrides else "_" + hashlib.sha1(key.encode()).hexdigest()[:8]
        if name in JMMAC_PRESETS and jmmac:
            tag += "_" + hashlib.sha1(jmmac_key.encode()).hexdigest()[:8]
        tag += "" if args.init == "first" else f"_{args.init}"
        return args.cache / f"{name}{tag}" / f"{seq}.txt"

    todo, results, seconds, tracks = {}, {}, {}, {}
    for f in folders:
        gt = np.loadtxt(f / "groundtruth.txt", delimiter=",", ndmin=2)
        for n in names:
            c = cached(f.name, n)
            if c is not None and c.is_file():
                boxes = np.loadtxt(c, delimiter=",", ndmin=2)
                start = int(np.flatnonzero(np.any(gt != 0, axis=1))[0])
                m = min(len(boxes), len(gt))
                results[(f.name, n)] = scores(boxes[:m], gt[:m], start)
                tracks[(f.name, n)] = boxes[:m]
            else:
                todo.setdefault(f, []).append(n)
    load = open("/proc/loadavg").read().split()[:3] if os.path.exists("/proc/loadavg") else ["?"] * 3
    print(f"{len(folders)} sequences, {sum(map(len, todo.values()))} runs to do; load average {' '.join(load)}; "
          f"{machine.describe()}", flush=True)
    # fold by fold, so that a run stopped early leaves whole folds in the cache (each one a sample of every class);
    # within a fold the slowest jobs first (weight x frames x pixels), so the pool does not end with one long job
    weight = {"ECO-deep": 3, "ECO-hc+cnn": 2, **{n: 2 for n in JMMAC_PRESETS}}

    def cost(folder: Path, trackers: list[str]) -> float:
        meta = json.loads((folder / "meta.json").read_text()) if (folder / "meta.json").is_file() else {}
        pixels = meta.get("frames", 1) * meta.get("width", 1) * meta.get("height", 1)
        return sum(weight.get(n, 1) for n in trackers) * pixels

    jobs = sorted(todo.items(), key=lambda kv: (fold_of[kv[0].name], -cost(*kv)))
    with ProcessPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        for out in pool.map(_job, [(f, ns, args.shared, overrides, args.init, jmmac) for f, ns in jobs]):
            for seq, name, boxes, cpu, start in out:
                gt = np.loadtxt(where[seq] / "groundtruth.txt", delimiter=",", ndmin=2)
                m = min(len(boxes), len(gt))
                results[(seq, name)] = scores(boxes[:m], gt[:m], start)
                tracks[(seq, name)] = boxes[:m]
                seconds[(seq, name)] = cpu / max(len(boxes) - start - 1, 1)
                c = cached(seq, name)
                if c is not None:
                    c.parent.mkdir(parents=True, exist_ok=True)
                    # full float64 precision: scores re-read from the cache equal the run's own (at 0.01 px a
                    # 14x12 px box's size error moved in the fourth decimal, where the size goal was decided)
                    np.savetxt(c, boxes, fmt="%.17g", delimiter=",")
                r = results[(seq, name)]
                print(f"{seq:24s} {name:10s} success {r['success']:5.1f} precision {r['precision']:5.1f} "
                      f"size {r['size']:.3f}  {1000 * seconds[(seq, name)]:.1f} ms/frame CPU", flush=True)
    seqs = [f.name for f in folders]
    peers = [n for n in names if not ours(n)]
    rows = groups(seqs, fold_of, {f.name: f.parent.name for f in folders}, tuned, HELD_ASIDE)
    lines_groups = group_table(results, names, rows, peers)
    lines_classes = class_table(results, names, seqs, peers)
    both = "ECO-hc" in names and "ECO-deep" in names
    lines_collapse = collapse_table(results, seqs, fold_of, peers) if both else []
    lines = table(results, names, seqs, fold_of, rows)
    lines_back = reacquisition_table(tracks, names, [f for f in folders])
    by_class = [(f"{c} ({sum(clip_class(s) == c for s in seqs)})", [s for s in seqs if clip_class(s) == c])
                for c in sorted(set(map(clip_class, seqs)))]
    lines_position = position_table(tracks, names, folders, rows + by_class)
    print("\n".join(lines_groups))
    print("\n".join(lines_classes))
    print("\n".join(lines_collapse))
    if not args.folds:
        print("\n".join(lines))
        print("\n".join(lines_back))
        print("\n".join(lines_position))
    notes = summary(results, names, seqs)
    print("\n".join(notes))
    if seconds:
        speed = {n: [v for (s, m), v in seconds.items() if m == n] for n in names}
        print("CPU ms/frame: " + ", ".join(f"{n} {1000 * np.mean(v):.1f}" for n, v in speed.items() if v))
    if args.out:
        from rgbt_toolkit._atomic import write_text_atomic

        collapse_head = (f"### ECO-hc below {COLLAPSE_RATIO} x ECO-deep where ECO-deep scores at least "
                         f"{COLLAPSE_FLOOR:.0f}")
        text = "\n".join([f"Load average at the start: {' '.join(load)}; {machine.describe()}; overrides: {key}; "
                          f"JMMAC overrides: {jmmac_key}"
                          f"; initial box: {args.init}; tuned on folds: {args.tune_folds or 'none'}",
                          "", "### Mean success by fold", "", *lines_groups, "", "### By class", "", *lines_classes,
                          "", collapse_head, "", *lines_collapse, "", "### Every clip", "", *lines, "",
                          *(f"- {n}" for n in notes), "", "### Back on the target after a shot cut", "", *lines_back,
                          "", "### Position alone: each tracker's centres with the labels' sizes (groups, then classes)", "",
                          *lines_position, ""])
        write_text_atomic(args.out, text)


if __name__ == "__main__":
    main()
