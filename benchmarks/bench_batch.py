"""Throughput of ``rgbt batch track`` per executor: in-process, process pool with 1 and 2 workers, Dask local cluster.

Generates RGBT234-layout sequences with the scene generator (cached in ``--data``), then tracks all of them with each
executor into a fresh results folder, and prints a Markdown table: executor start-up, run time, items/s, frames/s and
the speed-up over the one-worker pool. The results of every executor are checked to be identical.

    python benchmarks/bench_batch.py --sequences 8 --duration 3 --tracker csrt

The load average is printed before and after, since scaling on a shared machine depends on what else runs.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path


def make_dataset(folder: Path, count: int, duration: float) -> Path:
    from rgbt_toolkit.synth import generate_scene

    challenges = ((), ("occlusion",), ("fast_motion",), ("scale_change",), ("low_light",), ("camera_motion",))
    for i in range(count):
        if not (folder / f"seq{i:02d}" / "init.txt").is_file():
            generate_scene(folder, challenges[i % len(challenges)], seed=i, layout="rgbt234", name=f"seq{i:02d}",
                           duration=duration)
    return folder


def digest(folder: Path) -> str:
    h = hashlib.sha1()
    for path in sorted(folder.glob("*.txt")):
        h.update(path.name.encode() + path.read_bytes())
    return h.hexdigest()[:12]


def run_one(name: str, make, dataset: Path, tracker: str, work: Path, frames: int) -> dict:
    from rgbt_toolkit.batch.runner import run_job
    from rgbt_toolkit.batch.tasks import plan_track, track_item

    out = work / name.replace(" ", "_")
    job, found = plan_track(dataset, out, tracker)
    t0 = time.perf_counter()
    executor = make()
    t1 = time.perf_counter()
    try:
        report = run_job(track_item, job, list(found.items), executor)
    finally:
        t2 = time.perf_counter()
        executor.close()
        t3 = time.perf_counter()
    if not report.ok:
        raise SystemExit(f"{name}: {len(report.failed)} items failed: {report.failed[0].error}")
    run = t2 - t1
    return {"name": name, "start": t1 - t0, "run": run, "close": t3 - t2, "items": len(found.items),
            "items_s": len(found.items) / run, "frames_s": frames / run, "digest": digest(out)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path(tempfile.gettempdir()) / "rgbt_bench_batch")
    parser.add_argument("--sequences", type=int, default=8)
    parser.add_argument("--duration", type=float, default=3.0, help="seconds per generated sequence (15 frames/s)")
    parser.add_argument("--tracker", default="csrt", help="tracker name for rgbt batch track (csrt, jmmac)")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask local cluster")
    args = parser.parse_args()

    from rgbt_toolkit.batch.executors import DaskExecutor, InProcessExecutor, ProcessPoolExecutor, cpu_count
    from rgbt_toolkit.io.sequences import list_sequences, read_sequence

    dataset = make_dataset(args.data / f"d{args.duration:g}", args.sequences, args.duration)
    frames = sum(len(read_sequence(p)) for p in list_sequences(dataset)[: args.sequences])
    configs = [
        ("in-process", lambda: InProcessExecutor(threads=1)),
        ("pool, 1 worker", lambda: ProcessPoolExecutor(workers=1)),
        ("pool, 2 workers", lambda: ProcessPoolExecutor(workers=2)),
    ]
    if not args.no_dask:
        try:
            import distributed  # noqa: F401

            configs.append(("dask local, 2 workers", lambda: DaskExecutor(local_workers=2)))
        except ImportError:
            print("dask is not installed: skipping the Dask row (pip install 'rgbt-toolkit[dask]')")
    load_before = os.getloadavg()
    work = Path(tempfile.mkdtemp(prefix="rgbt_bench_batch_"))
    rows = []
    try:
        for name, make in configs:
            rows.append(run_one(name, make, dataset, args.tracker, work, frames))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    load_after = os.getloadavg()
    base = next(r["run"] for r in rows if r["name"] == "pool, 1 worker")
    print(f"rgbt batch track --tracker {args.tracker}: {args.sequences} generated sequences, {frames} frames "
          f"(320x240 RGB + 256x192 T), {cpu_count()} cores, {platform.processor() or platform.machine()}, "
          f"load average {load_before[0]:.1f} before / {load_after[0]:.1f} after")
    print()
    print("| executor | start-up s | run s | items/s | frames/s | speed-up vs pool-1 | results |")
    print("|---|---:|---:|---:|---:|---:|---|")
    for r in rows:
        print(f"| {r['name']} | {r['start']:.2f} | {r['run']:.2f} | {r['items_s']:.2f} | {r['frames_s']:.1f} | "
              f"{base / r['run']:.2f} | {r['digest']} |")
    same = len({r["digest"] for r in rows}) == 1
    print()
    print("identical results across executors" if same else "RESULTS DIFFER between executors")


if __name__ == "__main__":
    main()
