"""Time ``rgbt eval``'s library path on the shared benchmark data, one core, and print a table.

Usage: ``python benchmarks/bench_eval.py [--shared ../shared] [--repeat 5]``. Every run reads all ground-truth and
result files from disk and scores them (the same path as the command). The machine is shared, so the load average
is printed beside the times; the minimum over repeats is the figure to quote.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

from rgbt_toolkit.evaluation.api import evaluate
from rgbt_toolkit.io.boxes import read_boxes, write_boxes
from rgbt_toolkit.runtime import set_threads


def _loadavg() -> str:
    try:
        return Path("/proc/loadavg").read_text().split()[0]
    except OSError:  # pragma: no cover - not Linux
        return "?"


def _time(fn, repeat: int) -> tuple[float, float, float, object]:
    """Best and median wall time, best CPU time (the process's own, unaffected by other jobs' time slices)."""
    times, cpu, out = [], [], None
    for _ in range(repeat):
        start, start_cpu = time.perf_counter(), time.process_time()
        out = fn()
        times.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return min(times), statistics.median(times), min(cpu), out


def _vot_stand_in(data: Path, folder: Path) -> Path:
    """VOT-layout truth for the 60 VOT19-RGBT sequences from RGBT234's infrared truth (the VOT truth is absent)."""
    for seq in sorted(p.name for p in (data / "results/JMMAC/VOT19-RGBT/baseline").iterdir()):
        boxes = read_boxes(data / "gt/RGBT234/rgbt234_gt" / seq / "infrared.txt")
        write_boxes(folder / seq / "groundtruth.txt", boxes, fmt="polygon", precision=0)
    return folder


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=str(Path(__file__).resolve().parents[2] / "shared"))
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    data = Path(args.shared) / "data" / "tracking"
    if not data.is_dir():
        raise SystemExit(f"{data}: shared tracking data not found (give --shared)")
    set_threads(1)
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    with tempfile.TemporaryDirectory() as tmp:
        cases = [
            ("GTOT", "gtot", data / "gt/GTOT", data / "results/JMMAC/GTOT"),
            ("RGBT234", "rgbt234", data / "gt/RGBT234", data / "results/JMMAC/RGBT234"),
            ("RGBT210", "rgbt210", data / "gt/RGBT210", data / "results/JMMAC/RGBT234"),
            ("VOT19-RGBT*", "vot-rgbt", _vot_stand_in(data, Path(tmp) / "vot"), data / "results/JMMAC/VOT19-RGBT"),
        ]
        rows = []
        for label, key, gt, res in cases:
            load_before = _loadavg()
            best, median, cpu, report = _time(lambda: evaluate(key, gt, [res]), args.repeat)
            scores = next(iter(report.trackers.values()))
            n_seq = len(scores.sequences)
            frames = sum(s.n_frames for s in scores.sequences.values())
            summary = ", ".join(
                f"{k} {v:.4f}" if key == "vot-rgbt" else f"{k} {v:.2f}"
                for k, v in scores.summary.items() if k != "failures"
            )
            rows.append((label, n_seq, frames, best, median, cpu, load_before, summary))
    print(f"rgbt eval, JMMAC raw results, 1 thread: wall time best / median of {args.repeat}, best CPU time, "
          f"load average before each case; {os.cpu_count()} cores")
    print(f"{'benchmark':<12} {'seqs':>5} {'frames':>8} {'best s':>7} {'median s':>9} {'cpu s':>6} {'load':>5}  scores")
    for label, n_seq, frames, best, median, cpu, load, summary in rows:
        print(f"{label:<12} {n_seq:>5} {frames:>8} {best:>7.3f} {median:>9.3f} {cpu:>6.3f} {load:>5}  {summary}")
    print("* VOT19-RGBT scored against RGBT234's infrared truth as a stand-in: R is exact, A and EAO are not official")


if __name__ == "__main__":
    main()
