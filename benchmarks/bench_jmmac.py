"""JMMAC ablation and peers on generated sequences, one per challenge.

Prints a success (MSR, RGBT234 convention) table: rows are the paper's ablation variants and OpenCV's CSRT and
Nano trackers on either modality, columns the challenges. Speed is measured by ``benchmarks/bench_speed.py``.

    python benchmarks/bench_jmmac.py [--duration 4] [--seeds 0] [--workers 2] [--shared ../shared]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import tempfile
import time
from pathlib import Path

import numpy as np

CHALLENGES = ("occlusion", "camera_motion", "low_light", "thermal_crossover", "fast_motion", "scale_change")
VARIANTS = ("B-RGB", "B-T", "average", "+MF-G", "+MF-L", "+MF", "+CME", "+TMP", "+RA", "full", "default")


def generate(workdir: Path, duration: float, seeds: list[int], size=(320, 240),
             challenges: tuple[str, ...] = CHALLENGES) -> list[str]:
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence

    names = []
    for challenge in challenges:
        for seed in seeds:
            name = f"{challenge}_s{seed}"
            config = SceneConfig.aligned(rgb_size=size, challenges=frozenset({challenge}), seed=seed,
                                         duration=duration)
            write_scene_sequence(SceneRenderer(config), workdir / name)
            names.append(name)
    return names


def run_peer(kind: str, modality: str, seq_dir: Path, shared: Path) -> np.ndarray:
    import cv2

    from rgbt_toolkit.io.images import read_image
    from rgbt_toolkit.io.sequences import read_sequence

    seq = read_sequence(seq_dir)
    files = seq.rgb_frames if modality == "rgb" else seq.t_frames
    if kind == "csrt":
        tracker = cv2.TrackerCSRT_create()
    else:
        params = cv2.TrackerNano_Params()
        params.backbone = str(shared / "models" / "nanotrack_backbone_sim.onnx")
        params.neckhead = str(shared / "models" / "nanotrack_head_sim.onnx")
        tracker = cv2.TrackerNano_create(params)
    boxes = [seq.init_box]
    for k, path in enumerate(files):
        image = read_image(path)
        image = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR) if image.ndim == 2 else image[:, :, ::-1].copy()
        if k == 0:
            tracker.init(image, tuple(int(round(v)) for v in seq.init_box))
            continue
        ok, rect = tracker.update(image)
        boxes.append(np.array(rect, float) if ok else boxes[-1])
    return np.asarray(boxes)


def job(args):
    name, seq_dir, shared, overrides = args
    from rgbt_toolkit.runtime import set_threads

    set_threads(1)
    started = time.perf_counter()
    if name.startswith(("CSRT", "Nano")):
        kind, modality = name.split("-")
        boxes = run_peer(kind.lower(), modality.lower(), seq_dir, shared)
    else:
        from rgbt_toolkit.jmmac.api import track_sequence_folder

        boxes = track_sequence_folder(seq_dir, name, config_overrides=overrides)
    return name, seq_dir.name, boxes, time.perf_counter() - started


def accuracy(args) -> None:
    """Success (MSR) per challenge for every variant and peer, all run on the same generated sequences."""
    from rgbt_toolkit.evaluation.benchmarks import get_benchmark
    from rgbt_toolkit.evaluation.groundtruth import load_groundtruth
    from rgbt_toolkit.evaluation.ope import score_run

    with tempfile.TemporaryDirectory() as tmp:
        workdir = Path(tmp)
        challenges = tuple(args.challenges)
        names = generate(workdir, args.duration, args.seeds, challenges=challenges)
        trackers = list(args.variants) + (["CSRT-RGB", "CSRT-T"] if args.peers else [])
        if args.peers and (args.shared / "models" / "nanotrack_backbone_sim.onnx").is_file():
            trackers += ["Nano-RGB", "Nano-T"]
        overrides = json.loads(args.config)
        if overrides:
            print(f"JMMAC variants run with {overrides}")
        jobs = [(t, workdir / n, args.shared, overrides) for t in trackers for n in names]
        results: dict[str, dict[str, np.ndarray]] = {t: {} for t in trackers}
        seconds: dict[str, float] = {t: 0.0 for t in trackers}
        with mp.get_context("spawn").Pool(args.workers) as pool:
            for tracker, seq, boxes, spent in pool.imap_unordered(job, jobs):
                results[tracker][seq] = boxes
                seconds[tracker] += spent
        truth = load_groundtruth(workdir, get_benchmark("rgbt234"))
        frames = sum(len(truth.sequences[n].boxes[0]) for n in names)
        print(f"| tracker | {' | '.join(challenges)} | mean MSR | mean MPR | frames/s |")
        print("|" + "---|" * (len(challenges) + 4))
        for tracker in trackers:
            scores = score_run(results[tracker], truth, tracker)
            cells = [f"{scores.score('MSR', [n for n in names if n.startswith(c)]):.1f}" for c in challenges]
            print(f"| {tracker} | {' | '.join(cells)} | {scores.score('MSR'):.1f} | {scores.score('MPR'):.1f} | "
                  f"{frames / seconds[tracker]:.1f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=4.0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[0])
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--shared", type=Path, default=Path(__file__).resolve().parents[1].parent / "shared")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS))
    parser.add_argument("--challenges", nargs="+", default=list(CHALLENGES),
                        help="generated challenges (rgbt synth --help lists them); default: the ablation's six")
    parser.add_argument("--peers", action=argparse.BooleanOptionalAction, default=True, help="run CSRT and Nano too")
    parser.add_argument("--config", default="{}", help='JSON of JmmacConfig fields set in every variant, e.g. '
                        '\'{"scale_search_interval": 2}\'')
    parser.add_argument("--skip-speed", action="store_true", help="ignored: speed moved to benchmarks/bench_speed.py")
    args = parser.parse_args()
    accuracy(args)


if __name__ == "__main__":
    main()
