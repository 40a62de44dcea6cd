"""Speed of `rgbt track` on real content against OpenCV CSRT, measured in one run on the same frames: the real rows
of docs/benchmarks.md ("Speed").

    python benchmarks/bench_speed_real.py [--frames 300] [--rounds 2] [--workdir DIR]

The pair is built by ``benchmarks/real_pair.py`` from a shared real full-HD street clip (1920x1080 H.264 visible, a
640x512 H.264 thermal view derived from it with a known registration, and the same frames as 1920x1080 JPEG folders
of both cameras). Tables (markdown):

1. end to end, wall clock from the command to the last file closed (``annotated.mp4`` and ``track.png`` included),
   with the true calibration (``--calib``): `rgbt track` on the video pair against "decode the RGB video with PyAV +
   CSRT", and on the JPEG folders against "``cv2.imread`` + CSRT", the peer with 1 and 2 OpenCV threads; ``--rounds``
   rounds, ours and the peer alternated, the fastest run of each kept, and each round's own ratio with their median;
   peak memory of our process;
2. the loop's stages and the tracker's modules per frame (from track.json of the fastest run);
3. the registration estimate: `rgbt track --max-frames 1 --no-video --no-plot` without and with ``--calib``, median
   of 3 alternated runs, the difference is what the estimate adds.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bench_speed import DECODE_CSRT, byte_compile
from real_pair import write_pair

IMREAD_CSRT = """
import sys, cv2
from pathlib import Path
cv2.setNumThreads(int(sys.argv[3]))
box = tuple(int(round(float(v))) for v in open(sys.argv[2]).read().split(","))
tracker = None
for path in sorted(Path(sys.argv[1]).glob("*.jpg")):
    image = cv2.imread(str(path))
    if tracker is None:
        tracker = cv2.TrackerCSRT_create(); tracker.init(image, box)
    else:
        tracker.update(image)
"""

# runs a command and prints its wall seconds and peak resident memory (MB) on the last line
MEASURED = """
import resource, subprocess, sys, time
started = time.perf_counter()
done = subprocess.run(sys.argv[1:], capture_output=True, text=True)
wall = time.perf_counter() - started
if done.returncode != 0:
    sys.exit(done.stderr[-800:])
print(wall, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)
"""


def measured(command: list[str]) -> tuple[float, float]:
    """Wall seconds and peak memory (MB) of a command; a failure stops the benchmark with its message."""
    done = subprocess.run([sys.executable, "-c", MEASURED, *command], capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed: {done.stderr.strip()[-800:]}")
    wall, peak = done.stdout.split()[-2:]
    return float(wall), float(peak)


def track_command(rgb: Path, t: Path, calib: Path | None, out: Path, *extra: str) -> list[str]:
    command = [sys.executable, "-m", "rgbt_cli.main", "track", str(rgb), str(t), "-o", str(out), "--force", *extra]
    return command + (["--calib", str(calib)] if calib is not None else [])


def end_to_end(paths: dict, workdir: Path, rounds: int) -> dict:
    """Ours and the peers on both kinds of input, alternated; every wall time and our peak memory."""
    cases = {
        "video": (paths["rgb"], paths["t"], paths["calib"], DECODE_CSRT, paths["rgb"].with_name("rgb.init.txt")),
        "jpeg": (paths["rgb_jpg"], paths["t_jpg"], paths["calib"].with_name("calib_jpg.json"), IMREAD_CSRT,
                 paths["rgb_jpg"].with_name("rgb_jpg.init.txt")),
    }
    rows: dict = {}
    for _ in range(rounds):
        for case, (rgb, t, calib, peer, init) in cases.items():
            box = init.read_text().strip()
            wall, peak = measured(track_command(rgb, t, calib, workdir / f"out_{case}", "--init", box))
            row = rows.setdefault(case, {"ours": [], "peak_mb": [], "peer": {1: [], 2: []}})
            row["ours"].append(wall)
            row["peak_mb"].append(peak)
            if wall <= min(row["ours"]):
                row["summary"] = json.loads((workdir / f"out_{case}" / "track.json").read_text())["summary"]
            for threads in (1, 2):
                row["peer"][threads].append(measured([sys.executable, "-c", peer, str(rgb), str(init),
                                                      str(threads)])[0])
    return rows


def round_ratios(row: dict) -> list[float]:
    """Each round's own ratio: the peer at that round's better thread setting against our run of the same round.

    Why beside the fastest-of ratio: on a shared machine one lucky run of either side moves the fastest-of figure by
    10-20 %, while the runs of one round share the same minutes (the peer's runs follow ours directly)."""
    return [min(p1, p2) / ours for ours, p1, p2 in zip(row["ours"], row["peer"][1], row["peer"][2])]


def registration_cost(paths: dict, workdir: Path, repeats: int = 3) -> dict:
    """Median seconds of the one-frame run with the true calibration and with the estimate, alternated."""
    cases = {"video": (paths["rgb"], paths["t"], paths["calib"]),
             "jpeg": (paths["rgb_jpg"], paths["t_jpg"], paths["calib"].with_name("calib_jpg.json"))}
    box = paths["rgb"].with_name("rgb.init.txt").read_text().strip()
    costs = {}
    for case, (rgb, t, calib) in cases.items():
        quick = ("--max-frames", "1", "--no-video", "--no-plot", "--init", box)
        given, estimated = [], []
        for _ in range(repeats):
            given.append(measured(track_command(rgb, t, calib, workdir / "reg_given", *quick))[0])
            estimated.append(measured(track_command(rgb, t, None, workdir / "reg_estimated", *quick))[0])
        costs[case] = (float(np.median(given)), float(np.median(estimated)))
    return costs


def print_tables(rows: dict, costs: dict, frames: int) -> None:
    names = {"video": "1920x1080 H.264 visible + 640x512 H.264 thermal, `--calib`",
             "jpeg": "1920x1080 JPEG folders of both cameras, `--calib`"}
    peers = {"video": "PyAV decode + CSRT", "jpeg": "cv2.imread + CSRT"}
    print(f"## End to end on real content ({frames} frames; wall clock, command to last file closed)\n")
    print("| input | `rgbt track` s (each run) | peer, 1 thread | peer, 2 threads | ratio (peer best / ours best) "
          "| ratio per round (median) | our peak memory |")
    print("|---|---|---|---|---|---|---|")
    for case, row in rows.items():
        ours, peer = min(row["ours"]), min(min(row["peer"][1]), min(row["peer"][2]))
        per_round = round_ratios(row)
        print(f"| {names[case]} | {' / '.join(f'{w:.1f}' for w in row['ours'])} | {peers[case]}: "
              f"{' / '.join(f'{w:.1f}' for w in row['peer'][1])} | {' / '.join(f'{w:.1f}' for w in row['peer'][2])} "
              f"| **{peer / ours:.2f}x** | {' / '.join(f'{r:.2f}' for r in per_round)} "
              f"({float(np.median(per_round)):.2f}x) | {max(row['peak_mb']):.0f} MB |")
    print()
    for case, row in rows.items():
        summary = row["summary"]
        print(f"### Where the fastest run's time goes: {names[case]}\n")
        print("| loop stage (main thread) | ms / frame |")
        print("|---|---|")
        for key, value in summary.get("loop_ms_per_frame", {}).items():
            print(f"| {key} | {value:.1f} |")
        outside = min(row["ours"]) - summary["seconds"]
        print(f"| outside the loop (start-up, track.png, closing) | {1000 * outside / frames:.1f} ({outside:.1f} s) |")
        for key, value in summary.get("background_ms_per_frame", {}).items():
            print(f"| background thread: {key} | {value:.1f} |")
        print("\n| tracker module | ms / frame |")
        print("|---|---|")
        for key, value in summary.get("tracker_ms_per_frame", {}).items():
            if value >= 0.05:
                print(f"| {key} | {value:.1f} |")
        print()
    print("## Registration estimate inside `rgbt track` (first frame only, median of 3 alternated runs)\n")
    print("| input | with `--calib` s | estimated s | added s |")
    print("|---|---|---|---|")
    for case, (given, estimated) in costs.items():
        print(f"| {names[case].split(', `')[0]} | {given:.2f} | {estimated:.2f} | **{estimated - given:.2f}** |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=300, help="frames of the real pair")
    parser.add_argument("--rounds", type=int, default=2, help="alternated rounds of ours and the peers")
    parser.add_argument("--workdir", type=Path, default=None, help="where the pair and the outputs go (cached)")
    args = parser.parse_args()
    byte_compile()
    with tempfile.TemporaryDirectory() as tmp:
        workdir = args.workdir or Path(tmp)
        started = time.perf_counter()
        paths = write_pair(workdir / "pair", args.frames, jpeg=True)
        print(f"(pair ready in {time.perf_counter() - started:.0f} s: {workdir / 'pair'})\n", file=sys.stderr)
        rows = end_to_end(paths, workdir, args.rounds)
        costs = registration_cost(paths, workdir)
        print_tables(rows, costs, args.frames)


if __name__ == "__main__":
    main()
