"""What the registration estimate adds to `rgbt track` on a real 1080p pair, against the same inputs with --calib.

    python benchmarks/bench_track_registration.py PAIR_DIR [--frames 300] [--rounds 3] [--baseline-tree DIR]

Each run is a fresh process resolving the inputs as `rgbt track` does (``api.tracking.open_inputs``, with the
library threads `rgbt track` sets by default): opening both recordings, the RGB->T transform and the first box. Runs
with and without the true calibration alternate, ``--rounds`` each; the figure is the difference of their medians,
wall-clock and (in brackets) CPU time of the process: on a shared machine the CPU time is the steadier of the two.
The ``rgbt_toolkit`` measured is the one of the source tree holding this script (its C extensions built in place).
The inputs are those of ``benchmarks/real_pair.py`` (written to PAIR_DIR when missing, about a minute):
``rgb.mp4`` (1920x1080) with ``t.mp4`` (640x512), and the 1920x1080 JPEG folders ``rgb_jpg/`` with ``t_jpg/``; both
have a known registration, so the estimate's corner error (mean over the thermal frame's corners, thermal pixels)
is printed too.
``--baseline-tree`` also times the estimate with the ``rgbt_toolkit`` of another source tree (built in place),
alternated with this one.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

CHILD = """
import json, sys, time
from rgbt_toolkit.runtime import set_threads, split_tracker_threads
set_threads(split_tracker_threads()[0])  # as `rgbt track` sets them before resolving its inputs
from rgbt_toolkit.api.tracking import open_inputs
rgb, thermal, calib, init = sys.argv[1:5]
start, cpu = time.perf_counter(), time.process_time()
inputs = open_inputs(rgb, thermal, init=[float(v) for v in init.split(",")], calib=calib or None)
print(json.dumps({"seconds": time.perf_counter() - start, "cpu": time.process_time() - cpu,
                  "matrix": inputs.h_rgb_to_t.tolist()}))
"""


def corner_error(matrix: np.ndarray, truth: np.ndarray, t_size: tuple[int, int]) -> float:
    """Mean distance (thermal px) between the thermal frame's corners and where ``matrix`` puts the RGB points that
    ``truth`` maps onto them."""
    w, h = t_size
    corners = np.array([[0, 0, 1], [w, 0, 1], [w, h, 1], [0, h, 1]], float).T
    mapped = matrix @ np.linalg.inv(truth) @ corners
    return float(np.mean(np.linalg.norm(mapped[:2] / mapped[2] - corners[:2], axis=0)))


def run_once(tree: Path, rgb: Path, thermal: Path, calib: Path | None, init: str) -> dict:
    """One fresh process resolving the inputs with the ``rgbt_toolkit`` of ``tree``."""
    env = dict(os.environ, PYTHONPATH=str(tree))
    out = subprocess.run([sys.executable, "-c", CHILD, str(rgb), str(thermal), str(calib or ""), init], env=env,
                         capture_output=True, text=True, check=True, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(trees: dict[str, Path], rgb: Path, thermal: Path, calib: Path, init: str, rounds: int) -> dict:
    """Alternated runs: with the calibration, then the estimate of each tree, ``rounds`` times. Per run kind the
    (wall, CPU) seconds of each run, and the estimated matrices."""
    times: dict[str, list[tuple[float, float]]] = {"calib": [], **{name: [] for name in trees}}
    matrices = {}
    first = next(iter(trees.values()))
    for _ in range(rounds):
        result = run_once(first, rgb, thermal, calib, init)
        times["calib"].append((result["seconds"], result["cpu"]))
        for name, tree in trees.items():
            result = run_once(tree, rgb, thermal, None, init)
            times[name].append((result["seconds"], result["cpu"]))
            matrices[name] = np.asarray(result["matrix"])
    return {"times": times, "matrices": matrices}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pair", type=Path, help="real_pair.py's output folder (written when missing)")
    parser.add_argument("--frames", type=int, default=300, help="frames of the pair (real_pair.py --frames)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline-tree", type=Path, default=None,
                        help="a source tree whose rgbt_toolkit is timed too (e.g. an export of an older commit)")
    args = parser.parse_args()
    this = Path(__file__).resolve().parents[1]  # the tree this script belongs to is the one measured
    sys.path[:0] = [str(this / "benchmarks"), str(this)]
    from real_pair import write_pair

    from rgbt_toolkit.registration.calib import load_calibration

    paths = write_pair(args.pair, args.frames, jpeg=True)
    trees = {"estimate": this, **({"baseline": args.baseline_tree.resolve()} if args.baseline_tree else {})}
    cases = {"video (1920x1080 H.264 + 640x512)": (paths["rgb"], paths["t"], paths["calib"], "rgb.init.txt"),
             "JPEG folders (1920x1080 both)": (paths["rgb_jpg"], paths["t_jpg"], args.pair / "calib_jpg.json",
                                              "rgb_jpg.init.txt")}
    print(f"{args.frames} frames, {args.rounds} alternated rounds; median wall (CPU) seconds to resolve the inputs; "
          f"tree {this}; load average {os.getloadavg()[0]:.1f}")
    print("| inputs | code | with --calib (s) | estimated (s) | registration estimate: s added against --calib "
          "| corner error (T px) |")
    print("|---|---|---|---|---|---|")
    for label, (rgb, thermal, calib, init_name) in cases.items():
        init = (args.pair / init_name).read_text().strip()
        result = measure(trees, rgb, thermal, calib, init, args.rounds)
        truth = load_calibration(calib)
        with_calib = np.median(result["times"]["calib"], axis=0)
        for name in trees:
            estimated = np.median(result["times"][name], axis=0)
            added = estimated - with_calib
            error = corner_error(result["matrices"][name], np.asarray(truth.matrix), truth.thermal_size)
            print(f"| {label} | {name} | {with_calib[0]:.2f} ({with_calib[1]:.2f}) | {estimated[0]:.2f} "
                  f"({estimated[1]:.2f}) | **{added[0]:.2f}** ({added[1]:.2f}) | {error:.2f} |", flush=True)
    print(f"load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
