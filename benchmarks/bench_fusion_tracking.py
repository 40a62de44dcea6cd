"""Does learned fusion help tracking? The same two ECO trackers, six fusion rules, on generated sequences where one
modality is degraded in its own way (issue 7: "fused tracking beats the better single modality and a fixed 0.5/0.5
average ... and the ablation global-only / local-only / both is reported").

The sequence types, seeds and length are fixed here; each type puts the burden on one modality, so the right
weighting differs from type to type. A look-alike that passes right behind the target (``crossing_*`` challenges of
the generator) is what makes a modality confidently wrong; a first design with the generator's roaming look-alikes
(``distractor_*``) was dropped after one run showed it could not tell fusion rules apart: the single-modality
trackers never failed on it (B-RGB and B-T 90-93 MSR, seeds 0-1, on every type but dark RGB) and the average and +MF
(shipped heads of then, seed 0) both scored 91-92 on every type.

- ``dark+colour_crossing`` (low_light + crossing_color): RGB goes dark, then a person in the target's colours (at
  background temperature) passes behind the target -> trust thermal;
- ``colour_crossing`` (crossing_color): the same in daylight;
- ``crossover+warm_crossing`` (thermal_crossover + crossing_thermal): the target fades into the background in
  thermal while a warm body in other colours passes behind it -> trust RGB;
- ``warm_crossing`` (crossing_thermal): the same without the crossover;
- ``crossover`` (thermal_crossover) and ``low_light`` (dark RGB): one modality fades, nothing else.

Evaluation seeds are 0-3 (the training sequences of the shipped tracking heads use seeds 100 and up). Rows: B-RGB,
B-T (one tracker), average (fixed 0.5/0.5), +MF-G (w_G only), +MF-L (W_L only), +MF (W_F = w_G W_L); every row
without CME, TMP or box refinement (the paper's ablation presets). Scores: success AUC (MSR) and precision at 20 px
(MPR), RGBT234 convention, per type (mean over its seeds) and over all sequences.

    python benchmarks/bench_fusion_tracking.py [--heads heads.pt] [--variants ...] [--seeds 0 1 2 3] [--md FILE]
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import tempfile
import time
from pathlib import Path

import numpy as np

# name -> synth challenges; fixed before looking at results (see the module docstring)
TYPES: dict[str, tuple[str, ...]] = {
    "dark+colour_crossing": ("low_light", "crossing_color"),
    "colour_crossing": ("crossing_color",),
    "crossover+warm_crossing": ("thermal_crossover", "crossing_thermal"),
    "warm_crossing": ("crossing_thermal",),
    "crossover": ("thermal_crossover",),
    "low_light": ("low_light",),
}
SEEDS = (0, 1, 2, 3)
DURATION = 4.0  # seconds at 15 frames/s: 60 frames, as benchmarks/bench_jmmac.py
VARIANTS = ("B-RGB", "B-T", "average", "+MF-G", "+MF-L", "+MF")


def generate(workdir: Path, seeds, duration: float, size=(320, 240)) -> list[str]:
    """Write one aligned RGBT234-layout folder per (type, seed); returns their names ``<type>_s<seed>``."""
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence

    names = []
    for kind, challenges in TYPES.items():
        for seed in seeds:
            name = f"{kind}_s{seed}"
            config = SceneConfig.aligned(rgb_size=size, challenges=frozenset(challenges), seed=seed,
                                         duration=duration)
            write_scene_sequence(SceneRenderer(config), workdir / name)
            names.append(name)
    return names


def job(args):
    """Track one sequence with one variant: (variant, sequence, boxes, mean w_G, CPU seconds)."""
    variant, seq_dir, heads = args
    from rgbt_toolkit.jmmac.api import build_tracker
    from rgbt_toolkit.jmmac.config import preset
    from rgbt_toolkit.jmmac.inputs import resolve_inputs
    from rgbt_toolkit.runtime import set_threads

    set_threads(1)
    started = time.process_time()
    inputs = resolve_inputs(seq_dir)
    tracker = build_tracker(preset(variant), mfnet_weights=heads)
    boxes, w_g = [], []
    for index, (rgb, thermal, _) in enumerate(inputs.pairs):
        aligned = inputs.thermal_in_rgb(thermal)
        result = tracker.initialize(rgb, aligned, inputs.init_box) if index == 0 else tracker.track(rgb, aligned)
        boxes.append(result.box)
        if index:
            w_g.append(result.w_g)
    return variant, seq_dir.name, np.asarray(boxes), float(np.nanmean(w_g)), time.process_time() - started


def run(args) -> list[str]:
    from rgbt_toolkit.evaluation.benchmarks import get_benchmark
    from rgbt_toolkit.evaluation.groundtruth import load_groundtruth
    from rgbt_toolkit.evaluation.ope import score_run

    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        names = generate(workdir, args.seeds, args.duration)
        heads = str(args.heads) if args.heads else None
        jobs = [(v, workdir / n, heads) for v in args.variants for n in names]
        results: dict[str, dict[str, np.ndarray]] = {v: {} for v in args.variants}
        w_g: dict[str, dict[str, float]] = {v: {} for v in args.variants}
        cpu = 0.0
        if args.workers > 1:
            with mp.get_context("spawn").Pool(args.workers) as pool:
                outputs = list(pool.imap_unordered(job, jobs))
        else:
            outputs = [job(j) for j in jobs]
        for variant, seq, boxes, mean_w_g, spent in outputs:
            results[variant][seq] = boxes
            w_g[variant][seq] = mean_w_g
            cpu += spent
        truth = load_groundtruth(workdir, get_benchmark("rgbt234"))
    kinds = list(TYPES)
    lines = []
    for metric in ("MSR", "MPR"):
        lines.append(f"| {metric} | " + " | ".join(kinds) + " | mean |")
        lines.append("|---|" + "---|" * (len(kinds) + 1))
        scores = {v: score_run(results[v], truth, v) for v in args.variants}
        for v in args.variants:
            cells = [scores[v].score(metric, [n for n in names if n.rsplit("_s", 1)[0] == k]) for k in kinds]
            lines.append(f"| {v} | " + " | ".join(f"{c:.1f}" for c in cells) + f" | {scores[v].score(metric):.1f} |")
        lines.append("")
    lines.append("| mean w_G (RGB weight) | " + " | ".join(kinds) + " |")
    lines.append("|---|" + "---|" * len(kinds))
    for v in args.variants:
        if v in ("+MF-G", "+MF"):
            cells = [np.mean([w_g[v][n] for n in names if n.rsplit("_s", 1)[0] == k]) for k in kinds]
            lines.append(f"| {v} | " + " | ".join(f"{c:.2f}" for c in cells) + " |")
    lines.append("")
    per_seq = {v: scores_per_sequence(results[v], truth, v) for v in args.variants}
    lines.append("| MSR per sequence | " + " | ".join(args.variants) + " |")
    lines.append("|---|" + "---|" * len(args.variants))
    for n in names:
        lines.append(f"| {n} | " + " | ".join(f"{per_seq[v][n]:.1f}" for v in args.variants) + " |")
    lines.append("")
    lines.append(f"CPU time of all runs: {cpu:.0f} s ({len(jobs)} runs of {len(names)} sequences)")
    return lines


def scores_per_sequence(boxes, truth, name) -> dict[str, float]:
    from rgbt_toolkit.evaluation.ope import score_run

    scores = score_run(boxes, truth, name)
    return {seq: scores.score("MSR", [seq]) for seq in boxes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--heads", type=Path, default=None, help="MFNet heads (default: the shipped tracking heads)")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    parser.add_argument("--seeds", type=int, nargs="+", default=list(SEEDS))
    parser.add_argument("--duration", type=float, default=DURATION)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--md", type=Path, default=None, help="also write the tables to this file")
    args = parser.parse_args()
    lines = run(args)
    print("\n".join(lines))
    if args.md is not None:
        from rgbt_toolkit._atomic import write_text_atomic

        write_text_atomic(args.md, "\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
