"""Time every fusion metric on one 640x480 visible/infrared/fused triple, one thread, and print a table.

Usage::

    python benchmarks/bench_fusion_metrics.py [--shared ../shared] [--repeat 5] [--markdown]

The triple is TNO pair 10 (640x480) from ``../shared/data/fusion/tno`` with the fused image their rounded mean; a
synthetic triple is used when ``../shared`` is absent. Times are the best of ``--repeat`` runs, as wall clock and as
process CPU time; the machine may be shared, so the load average is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.runtime import keep_freed_memory
from rgbt_toolkit.metrics.conventions import CONVENTIONS
from rgbt_toolkit.runtime import set_threads

REPO = Path(__file__).resolve().parents[1]


def _triple(shared: Path) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    tno = shared / "data" / "fusion" / "tno"
    if (tno / "vi" / "10.png").is_file():
        a = read_image(tno / "vi" / "10.png", grey=True).astype(np.float64)
        b = read_image(tno / "ir" / "10.png", grey=True).astype(np.float64)
        source = "TNO pair 10"
    else:
        rng = np.random.default_rng(0)
        yy, xx = np.mgrid[:480, :640]
        a = np.clip(np.round(120 + 60 * np.sin(xx / 17.0) + rng.normal(0, 8, (480, 640))), 0, 255)
        b = np.clip(np.round(90 + 70 * np.cos(yy / 23.0) + rng.normal(0, 8, (480, 640))), 0, 255)
        source = "synthetic"
    return a, b, np.round((a + b) / 2.0), source


def _time(fn, repeat: int) -> tuple[float, float]:
    fn()  # warm caches (filter banks, FFT plans)
    wall, cpu = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return min(wall), min(cpu)


def _load() -> str:
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "n/a"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared")
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--markdown", action="store_true", help="print a markdown table")
    args = parser.parse_args()
    set_threads(1)
    keep_freed_memory()  # as the CLI does: reuse freed image-sized temporaries
    a, b, f, source = _triple(args.shared)
    print(f"triple: {source}, {f.shape[1]}x{f.shape[0]} grey; 1 thread; load average before: {_load()}; "
          f"cpus: {os.cpu_count()}")
    sep = " | " if args.markdown else "  "
    head = ["convention", "metric", "wall ms", "cpu ms"]
    print(("| " if args.markdown else "") + sep.join(head) + (" |" if args.markdown else ""))
    if args.markdown:
        print("|" + "|".join("---" for _ in head) + "|")
    for name, conv in CONVENTIONS.items():
        total_wall = total_cpu = 0.0
        for metric in conv.default_metrics:
            fn = conv.metric(metric)
            wall, cpu = _time(lambda: fn(a, b, f), args.repeat)
            total_wall += wall
            total_cpu += cpu
            cells = [name, metric, f"{wall * 1e3:.1f}", f"{cpu * 1e3:.1f}"]
            print(("| " if args.markdown else "") + sep.join(cells) + (" |" if args.markdown else ""))
        cells = [name, f"total ({len(conv.default_metrics)} metrics)", f"{total_wall * 1e3:.1f}",
                 f"{total_cpu * 1e3:.1f}"]
        print(("| " if args.markdown else "") + sep.join(cells) + (" |" if args.markdown else ""))
    print(f"load average after: {_load()}")


if __name__ == "__main__":
    main()
