"""Benchmark of MFNet image fusion: start-up and speed of `rgbt fuse` at 640x480, TNO (paper convention) and VIFB
metrics, and response fusion on held-out generated training pairs (from the weight file's validation record).

    python benchmarks/bench_fuse.py --shared ../shared --threads 2 --md docs/benchmarks_fusion.md
    python benchmarks/bench_fuse.py --threads 1 --pairs 20 --skip tno vifb responses   # quick: start-up and speed

The network is the one `rgbt fuse` runs: the shipped ONNX export, or torch with --weights FILE.pt (or --torch for
the shipped heads in torch). Prints Markdown tables; with --md also writes them (atomically) to that file. Needs
../shared for the data.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit._atomic import write_text_atomic
from rgbt_toolkit.fusion.fuse_files import fuse_files, load_fusion_net
from rgbt_toolkit.fusion.image_fusion import FuseSettings, FusionNet, fuse_images
from rgbt_toolkit.fusion.weights_io import DEFAULT_WEIGHTS, read_meta
from rgbt_toolkit.io.images import read_image, write_image
from rgbt_toolkit.runtime import set_threads

# JMMAC paper, Table "image fusion" (TNO/INO 41 pairs), row "MFNet (Ours)".
PAPER_MFNET = {"EN": 6.912, "MI": 13.825, "Qabf": 0.425, "FMI_w": 0.428, "Nabf": 0.078, "SSIM": 0.714,
               "MS_SSIM": 0.895}
LOWER_BETTER = {"Nabf", "CE", "RMSE", "Qcv"}
VIFB_COLUMNS = {"Avg_gradient": "AG", "Cross_entropy": "CE", "Edge_intensity": "EI", "Entropy": "EN",
                "Mutinf": "MI", "Psnr": "PSNR", "Qabf": "Qabf", "Qcb": "Qcb", "Qcv": "Qcv", "Rmse": "RMSE",
                "Spatial_frequency": "SF", "Ssim": "SSIM", "Variance": "SD"}


def _pairs_640(shared: Path, folder: Path, n_pairs: int) -> list[tuple[Path, Path]]:
    """n 640x480 PNG pairs in ``folder`` (TNO images resized)."""
    tno = shared / "data/fusion/tno"
    pairs = []
    for k in range(n_pairs):
        stem = f"{k % 41 + 1:02d}"
        v = cv2.resize(read_image(tno / "vi" / f"{stem}.png"), (640, 480), interpolation=cv2.INTER_AREA)
        i = cv2.resize(read_image(tno / "ir" / f"{stem}.png", grey=True), (640, 480), interpolation=cv2.INTER_AREA)
        write_image(folder / "vi" / f"{k:03d}.png", v)
        write_image(folder / "ir" / f"{k:03d}.png", i)
        pairs.append((folder / "vi" / f"{k:03d}.png", folder / "ir" / f"{k:03d}.png"))
    return pairs


def startup(shared: Path, threads: int, runs: int = 5) -> str:
    """Wall clock of the `rgbt fuse VIS IR -o OUT` command on one 640x480 pair, from process start to exit (median
    of ``runs``), for the default network (ONNX Runtime) and for the same heads given as a .pt file (torch)."""
    cli = [sys.executable, "-c", "import sys; from rgbt_cli.main import main; sys.exit(main())", "fuse"]
    env = {**os.environ, "RGBT_THREADS": str(threads)}
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        (vis, ir), = _pairs_640(shared, Path(tmp), 1)
        for name, extra in (("ONNX Runtime (default)", []), ("torch (`--weights mfnet_heads.pt`)",
                                                              ["--weights", str(DEFAULT_WEIGHTS)])):
            walls = []
            for _ in range(runs):
                t0 = time.perf_counter()
                subprocess.run([*cli, str(vis), str(ir), "-o", str(Path(tmp) / "out.png"), "--force", *extra],
                               check=True, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
                walls.append(time.perf_counter() - t0)
            rows.append((name, statistics.median(walls), min(walls), max(walls)))
    load = os.getloadavg()[0]
    lines = [f"### Start-up: `rgbt fuse VIS IR -o OUT` on one 640x480 pair (wall clock of the command, median of "
             f"{runs} runs; {threads} thread(s); load average {load:.1f})", "",
             "| network | median | min | max |", "|---|---|---|---|"]
    lines += [f"| {n} | **{m:.2f} s** | {lo:.2f} s | {hi:.2f} s |" for n, m, lo, hi in rows]
    lines += ["", f"ONNX / torch: {rows[0][1] / rows[1][1]:.2f}x the wall clock (goal: <= 1.5 s).", ""]
    return "\n".join(lines)


def speed(net: FusionNet, shared: Path, n_pairs: int, settings: FuseSettings) -> str:
    """`rgbt fuse`'s library path over n 640x480 PNG pairs (TNO images resized), end to end with I/O."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        pairs = _pairs_640(shared, tmp, n_pairs)
        list(fuse_files(pairs[:3], tmp / "warm", net, settings))  # warm-up (allocations, thread pools)
        load0 = os.getloadavg()[0]
        t0, c0 = time.perf_counter(), time.process_time()
        reports = list(fuse_files(pairs, tmp / "out", net, settings))
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        load1 = os.getloadavg()[0]
        stages = {k: statistics.median(r.timings[k] for r in reports) * 1000 for k in reports[0].timings}
        grey_v = read_image(pairs[0][0])
        grey_i = read_image(pairs[0][1])
        compute = []
        for _ in range(max(10, n_pairs // 2)):
            c0 = time.perf_counter()
            fuse_images(grey_v, grey_i, net, settings)
            compute.append(time.perf_counter() - c0)
    lines = [
        f"### Speed: `rgbt fuse` on 640x480 pairs ({n_pairs} PNG pairs, net side {settings.net_side}, "
        f"{type(net).__name__}, {os.environ.get('BENCH_THREADS', '?')} threads; load average {load0:.1f} -> "
        f"{load1:.1f})",
        "",
        "| measure | value |",
        "|---|---|",
        f"| end to end (read, fuse, write; I/O overlapped in a thread) | **{n_pairs / wall:.1f} pairs/s** |",
        f"| CPU time per pair, all threads (load-independent) | {cpu / n_pairs * 1000:.1f} ms |",
        f"| rate if the CPU time spreads over 2 idle cores | {2 * n_pairs / cpu:.1f} pairs/s |",
        f"| fusion only (`fuse_images`, median) | {1 / statistics.median(compute):.1f} pairs/s "
        f"({statistics.median(compute) * 1000:.1f} ms) |",
    ]
    lines += [f"| stage `{k}` (median) | {v:.1f} ms |" for k, v in stages.items()]
    lines.append("")
    return "\n".join(lines)


def tno_metrics(net: FusionNet, shared: Path, settings: FuseSettings) -> str:
    """Mean paper-convention metrics over TNO 01-41 for MFNet, its ablations and a plain average."""
    from rgbt_toolkit.metrics import score_triple

    tno = shared / "data/fusion/tno"
    rows = {"MFNet (ours)": [], "global only": [], "local only": [], "average 0.5/0.5": []}
    variants = {"MFNet (ours)": settings, "global only": FuseSettings(settings.net_side, True, False),
                "local only": FuseSettings(settings.net_side, False, True)}
    w_g = []
    for k in range(1, 42):
        vis = read_image(tno / "vi" / f"{k:02d}.png", grey=True)
        ir = read_image(tno / "ir" / f"{k:02d}.png", grey=True)
        for name, s in variants.items():
            res = fuse_images(vis, ir, net, s)
            if name == "MFNet (ours)":
                w_g.append(res.w_g)
            rows[name].append(score_triple(vis, ir, res.fused, "paper"))
        avg = np.clip(0.5 * vis.astype(np.float64) + 0.5 * ir + 0.5, 0, 255).astype(np.uint8)
        rows["average 0.5/0.5"].append(score_triple(vis, ir, avg, "paper"))
    names = list(PAPER_MFNET)
    means = {r: {m: float(np.mean([x[m] for x in v])) for m in names} for r, v in rows.items()}
    ours = means["MFNet (ours)"]
    better = sum((ours[m] <= PAPER_MFNET[m]) if m in LOWER_BETTER else (ours[m] >= PAPER_MFNET[m]) for m in names)
    head = "| method | " + " | ".join(f"{m}{' (lower better)' if m in LOWER_BETTER else ''}" for m in names) + " |"
    lines = ["### TNO 01-41, `paper` metric convention (mean over 41 pairs)", "", head,
             "|---" * (len(names) + 1) + "|",
             "| paper: MFNet (JMMAC Table) | " + " | ".join(f"{PAPER_MFNET[m]:.3f}" for m in names) + " |"]
    for r, v in means.items():
        lines.append(f"| {r} | " + " | ".join(f"{v[m]:.3f}" for m in names) + " |")
    lines += ["", f"Ours at least as good as the paper's MFNet on **{better} of {len(names)}** metrics. "
              f"Mean w_G over TNO: {np.mean(w_g):.3f} (min {np.min(w_g):.3f}, max {np.max(w_g):.3f}).", ""]
    return "\n".join(lines)


def vifb_metrics(net: FusionNet, shared: Path, settings: FuseSettings) -> str:
    """VIFB-convention means over the 21 VIFB pairs, next to VIFB's published per-method means."""
    import csv

    from rgbt_toolkit.metrics import score_triple

    root = shared / "data/fusion/vifb"
    ref: dict[str, dict[str, list[float]]] = {}
    with open(root / "reference_metrics.csv", newline="") as fh:
        for row in csv.DictReader(fh):
            d = ref.setdefault(row["method"], {})
            for col, m in VIFB_COLUMNS.items():
                d.setdefault(m, []).append(float(row[col]))
    metrics = list(VIFB_COLUMNS.values())
    ours: dict[str, list[float]] = {m: [] for m in metrics}
    for vis_path in sorted((root / "VI").iterdir()):
        vis = read_image(vis_path)
        ir = read_image(root / "IR" / vis_path.name)
        fused = fuse_images(vis, ir, net, settings).fused
        if fused.ndim == 2 and vis.ndim == 3:
            fused = np.repeat(fused[:, :, None], 3, axis=2)
        s = score_triple(vis, ir, fused, "vifb", metrics)
        for m in metrics:
            ours[m].append(s[m])
    table = {"MFNet (ours)": {m: float(np.mean(v)) for m, v in ours.items()}}
    table.update({k: {m: float(np.mean(v)) for m, v in d.items()} for k, d in sorted(ref.items())})
    ranks = {}
    for m in metrics:
        vals = sorted(table.values(), key=lambda d: d[m], reverse=m not in LOWER_BETTER)
        ranks[m] = [d is table["MFNet (ours)"] for d in vals].index(True) + 1
    lines = [f"### VIFB (21 pairs), `vifb` convention: means; our rank among {len(table)} methods in the last row", "",
             "| method | " + " | ".join(f"{m}{'(-)' if m in LOWER_BETTER else ''}" for m in metrics) + " |",
             "|---" * (len(metrics) + 1) + "|"]
    for k, d in table.items():
        lines.append(f"| {k} | " + " | ".join(f"{d[m]:.4g}" for m in metrics) + " |")
    lines.append("| rank of ours | " + " | ".join(str(ranks[m]) for m in metrics) + " |")
    lines.append("")
    return "\n".join(lines)


def response_fusion(weights: Path | None) -> str:
    """Held-out validation figures recorded by `rgbt train-mfnet` in the weight file."""
    meta = read_meta(weights)
    val = meta["validation"]
    rules = ["rgb", "t", "avg", "global", "local", "mfnet"]
    kinds = [k[4:] for k in val["mfnet"] if k.startswith("hit_")]
    lines = [f"### Response fusion on held-out generated pairs ({meta['settings']['val_samples']} pairs from "
             f"{meta['val_images']} unseen RoadScene images; responses: {meta['response_source']})", "",
             "Peak hit rate (fused peak within 2 cells = 8 px of the true centre) and loss ||R_F - Y||^2:", "",
             "| rule | loss | hit (all) | " + " | ".join(kinds) + " |", "|---" * (len(kinds) + 3) + "|"]
    for r in rules:
        v = val[r]
        lines.append(f"| {r} | {v['loss']:.3f} | {v['hit']:.3f} | " + " | ".join(f"{v['hit_' + k]:.2f}" for k in kinds)
                     + " |")
    wg = val.get("w_g_mean", {})
    lines += ["", "Mean w_G by degradation: " + ", ".join(f"{k} {v:.2f}" for k, v in wg.items()), ""]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared")
    ap.add_argument("--weights", type=Path, default=None,
                    help="MFNet head file, run in torch (default: the shipped heads' ONNX export)")
    ap.add_argument("--torch", action="store_true", help="run the shipped heads in torch, not ONNX Runtime")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pairs", type=int, default=60, help="640x480 pairs for the speed run")
    ap.add_argument("--net-side", type=int, default=FuseSettings().net_side)
    ap.add_argument("--skip", nargs="*", default=[], choices=["startup", "speed", "tno", "vifb", "responses"])
    ap.add_argument("--md", type=Path, default=None, help="also write the tables to this Markdown file")
    args = ap.parse_args(argv)
    if not (args.shared / "data/fusion/tno").is_dir():
        print(f"{args.shared}: reference data not found (pass --shared)", file=sys.stderr)
        return 1
    threads = set_threads(args.threads)
    os.environ["BENCH_THREADS"] = str(threads)
    weights = args.weights if args.weights is not None or not args.torch else DEFAULT_WEIGHTS
    net = load_fusion_net(weights, None, threads)
    settings = FuseSettings(net_side=args.net_side)
    parts = ["## MFNet image fusion (benchmarks/bench_fuse.py)", "",
             f"Machine: {os.cpu_count()} CPUs visible, {args.threads} thread(s), network {type(net).__name__}; shared "
             "with other jobs, so timings are noisy (load average shown).", ""]
    steps = [("startup", lambda: startup(args.shared, threads)),
             ("speed", lambda: speed(net, args.shared, args.pairs, settings)),
             ("tno", lambda: tno_metrics(net, args.shared, settings)),
             ("vifb", lambda: vifb_metrics(net, args.shared, settings)),
             ("responses", lambda: response_fusion(args.weights))]
    for name, fn in steps:
        if name in args.skip:
            continue
        t0 = time.perf_counter()
        text = fn()
        print(text, flush=True)
        print(f"({name}: {time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
        parts.append(text)
    if args.md is not None:
        write_text_atomic(args.md, "\n".join(parts))
    return 0


if __name__ == "__main__":
    sys.exit(main())
