"""Throughput of ``rgbt batch track`` per executor: in-process, process pool with 1 and 2 workers, Dask local cluster.

Generates RGBT234-layout sequences with the scene generator (cached in ``--data``), then tracks all of them with each
executor into a fresh results folder, and prints a Markdown table: executor start-up, run time, items/s, frames/s and
the speed-up over in-process and over the one-worker pool. Executors are started once and warmed up (worker imports),
then timed over interleaved rounds, so a change in machine load affects them alike. The results of every executor
and round are checked to be identical.

    python benchmarks/bench_batch.py --sequences 8 --duration 2 --rounds 3 --tracker csrt

The load average during the runs is printed, since scaling on a shared machine depends on what else runs. Two columns
make that visible: CPU ms/frame (CPU time the items took, all threads: the work itself, equal for every executor when
none adds overhead) and cores obtained (that CPU time over the run's wall time: how much of the machine the batch got;
at most workers x threads).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import platform
import shutil
import statistics
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


def run_once(executor, dataset: Path, tracker: str, out: Path) -> tuple[float, float, str]:
    """Track the whole dataset into ``out`` with a warm executor; (seconds, CPU seconds of the items, digest)."""
    from rgbt_toolkit.batch.runner import run_job
    from rgbt_toolkit.batch.tasks import plan_track, track_item

    job, found = plan_track(dataset, out, tracker)
    t0 = time.perf_counter()
    report = run_job(track_item, job, list(found.items), executor)
    seconds = time.perf_counter() - t0
    if not report.ok:
        raise SystemExit(f"{executor.describe()}: {len(report.failed)} items failed: {report.failed[0].error}")
    return seconds, sum(r.cpu_seconds for r in report.items), digest(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data", type=Path, default=Path(tempfile.gettempdir()) / "rgbt_bench_batch")
    parser.add_argument("--sequences", type=int, default=8)
    parser.add_argument("--duration", type=float, default=3.0, help="seconds per generated sequence (15 frames/s)")
    parser.add_argument("--tracker", default="csrt", help="tracker name for rgbt batch track (csrt, jmmac)")
    parser.add_argument("--rounds", type=int, default=3, help="interleaved timed rounds per executor")
    parser.add_argument("--no-dask", action="store_true", help="skip the Dask local cluster")
    args = parser.parse_args()

    from rgbt_toolkit.batch.dask_executor import DaskExecutor
    from rgbt_toolkit.batch.executors import InProcessExecutor, ProcessPoolExecutor, cpu_count
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
    work = Path(tempfile.mkdtemp(prefix="rgbt_bench_batch_"))
    executors, rows, loads = {}, {name: {"runs": [], "cpu": [], "digests": set()} for name, _ in configs}, []
    try:
        for name, make in configs:
            t0 = time.perf_counter()
            executors[name] = make()  # the cold run includes starting workers and their first imports
            run_once(executors[name], dataset, args.tracker, work / "warmup" / name.replace(" ", "_"))
            rows[name]["cold"] = time.perf_counter() - t0
        for round_index in range(args.rounds):  # interleaved, so a change in machine load hits every executor
            for name, _ in configs:
                loads.append(os.getloadavg()[0])
                seconds, cpu, result = run_once(executors[name], dataset, args.tracker,
                                                work / f"r{round_index}" / name.replace(" ", "_"))
                rows[name]["runs"].append(seconds)
                rows[name]["cpu"].append(cpu)
                rows[name]["digests"].add(result)
    finally:
        for executor in executors.values():
            executor.close()
        shutil.rmtree(work, ignore_errors=True)
    items = len(list_sequences(dataset)[: args.sequences])
    print(f"rgbt batch track --tracker {args.tracker}: {items} generated sequences, {frames} frames "
          f"(320x240 RGB + 256x192 T), {cpu_count()} cores, {platform.processor() or platform.machine()}; "
          f"warm executors, best and median of {args.rounds} interleaved rounds; 1-min load average during the "
          f"runs {min(loads):.1f} to {max(loads):.1f}")
    print()
    print("| executor | threads/worker | cold run s | best s | median s | items/s (best) | frames/s (best) "
          "| speed-up vs in-process | speed-up vs pool-1 | CPU ms/frame | cores obtained |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    best = {name: min(row["runs"]) for name, row in rows.items()}
    for name, _ in configs:
        row = rows[name]
        print(f"| {name} | {getattr(executors[name], 'threads', None) or 1} | {row['cold']:.2f} | {best[name]:.2f} | "
              f"{statistics.median(row['runs']):.2f} | {items / best[name]:.2f} | {frames / best[name]:.1f} | "
              f"{best['in-process'] / best[name]:.2f} | {best['pool, 1 worker'] / best[name]:.2f} | "
              f"{1000 * statistics.median(row['cpu']) / frames:.0f} | "
              f"{statistics.median(c / r for c, r in zip(row['cpu'], row['runs'])):.2f} |")
    digests = set().union(*(row["digests"] for row in rows.values()))
    print()
    print("identical results across executors and rounds" if len(digests) == 1
          else "RESULTS DIFFER between executors")


if __name__ == "__main__":
    main()
