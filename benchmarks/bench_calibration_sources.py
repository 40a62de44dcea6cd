"""Benchmark of calibration from other evidence (``rgbt register --points / --from-boxes / --board``).

Everything is generated (no data needed): for each seed, a synthetic rig (``SceneConfig`` with a random thermal zoom
1.0-1.3, roll +-4 deg, shift +-10 px, keystone 0-4 %; 640x480 RGB -> 320x256 thermal) and

* points: 8 correspondences spread over the RGB frame, clicked with 0.5 px noise (thermal px), one mis-clicked by
  20-40 px (it must be named an outlier);
* boxes: both cameras' truth boxes of a 6 s scene (15 fps) with the thermal clock 0.2 s late (the offset must be
  found), rounded to whole pixels as label files are;
* board: a 9x6 chessboard and a 7x5 circle grid in 6 poses, rendered by both cameras (``rgbt synth --board``).

Errors: mean corner error (thermal px) at the thermal frame's corners mapped back to RGB
(``overlap_corner_error``, in RGB px) and at the points the evidence covers (max, thermal px); for boxes also the
recovered clock offset. Times are the fit alone (board: detection included) on this machine.

Usage: python benchmarks/bench_calibration_sources.py [--seeds 5] [--out FILE]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from rgbt_toolkit.io.boxes import write_boxes
from rgbt_toolkit.registration.board import BoardSpec, calibrate_from_board
from rgbt_toolkit.registration.from_boxes import calibrate_from_boxes
from rgbt_toolkit.registration.from_points import calibrate_from_points
from rgbt_toolkit.registration.transforms import overlap_corner_error, project
from rgbt_toolkit.synth import SceneConfig, SceneRenderer
from rgbt_toolkit.synth.board import write_board_pair

RGB, T = (640, 480), (320, 256)


def _config(seed: int, **fields) -> SceneConfig:
    rng = np.random.default_rng([seed, 99])
    return SceneConfig(seed=seed, rgb_size=RGB, t_size=T, t_zoom=rng.uniform(1.0, 1.3),
                       t_rotation_deg=rng.uniform(-4, 4), t_shift=tuple(rng.uniform(-10, 10, 2)),
                       t_keystone=rng.uniform(0, 0.04), **fields)


def _covered_error(matrix, truth, rgb_points) -> float:
    return float(np.linalg.norm(project(matrix, rgb_points) - project(truth, rgb_points), axis=1).max())


def bench_points(seed: int, folder: Path) -> dict:
    truth = SceneRenderer(_config(seed, duration=0.2)).h_rgb_to_t
    rng = np.random.default_rng(seed)
    rgb = rng.uniform([60, 60], [580, 420], (8, 2))
    thermal = project(truth, rgb) + rng.normal(0, 0.5, (8, 2))
    thermal[3] += rng.uniform(20, 40) * np.array([np.cos(seed), np.sin(seed)])
    path = folder / f"p{seed}.csv"
    path.write_text("\n".join(",".join(f"{v:.2f}" for v in row) for row in np.c_[rgb, thermal]) + "\n")
    start = time.perf_counter()
    fit = calibrate_from_points(path, RGB, T)
    seconds = time.perf_counter() - start
    return {"overlap_err": overlap_corner_error(fit.calibration.matrix, truth, T),
            "covered_err": _covered_error(fit.calibration.matrix, truth, rgb), "rms": fit.fit.rms,
            "outlier_named": list(fit.fit.outliers) == [3], "seconds": seconds}


def bench_boxes(seed: int, folder: Path) -> dict:
    config = _config(seed, duration=6.0, t_offset=0.2)
    renderer = SceneRenderer(config)
    times = np.arange(config.rgb_frame_count) / config.rgb_fps
    rgb = np.round([renderer.render(t, "rgb").box for t in times])
    thermal = np.round([renderer.render(t + config.t_offset, "t").box for t in times])
    write_boxes(folder / f"r{seed}.txt", rgb)
    write_boxes(folder / f"t{seed}.txt", thermal)
    start = time.perf_counter()
    fit = calibrate_from_boxes(folder / f"r{seed}.txt", folder / f"t{seed}.txt", RGB, T, fps=config.rgb_fps)
    seconds = time.perf_counter() - start
    centres = rgb[:, :2] + rgb[:, 2:] / 2
    return {"overlap_err": overlap_corner_error(fit.calibration.matrix, renderer.h_rgb_to_t, T),
            "covered_err": _covered_error(fit.calibration.matrix, renderer.h_rgb_to_t, centres), "rms": fit.fit.rms,
            "offset": fit.calibration.time_offset, "seconds": seconds}


def bench_board(seed: int, folder: Path, pattern: str, board: str) -> dict:
    config = _config(seed, duration=0.2)
    spec = BoardSpec.parse(board, pattern)
    written = write_board_pair(folder, config, spec.cols, spec.rows, views=6, pattern=pattern,
                               name=f"{pattern}{seed}")
    truth = SceneRenderer(config).h_rgb_to_t
    start = time.perf_counter()
    fit = calibrate_from_board(written["rgb"], written["t"], spec)
    seconds = time.perf_counter() - start
    grid = np.stack(np.meshgrid(np.linspace(0, RGB[0], 9), np.linspace(0, RGB[1], 7)), -1).reshape(-1, 2)
    inside = project(truth, grid)
    inside = grid[(inside[:, 0] >= 0) & (inside[:, 0] <= T[0]) & (inside[:, 1] >= 0) & (inside[:, 1] <= T[1])]
    return {"overlap_err": overlap_corner_error(fit.calibration.matrix, truth, T),
            "covered_err": _covered_error(fit.calibration.matrix, truth, inside), "rms": fit.fit.rms,
            "views": fit.calibration.pairs_used, "seconds": seconds}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        runs = {"points (8, 1 outlier)": lambda s: bench_points(s, folder),
                "boxes (6 s walk)": lambda s: bench_boxes(s, folder),
                "board 9x6 chessboard": lambda s: bench_board(s, folder, "chessboard", "9x6"),
                "board 7x5 circles": lambda s: bench_board(s, folder, "circles", "7x5")}
        for name, run in runs.items():
            results = [run(seed) for seed in range(args.seeds)]
            mean = {k: float(np.mean([r[k] for r in results])) for k in ("overlap_err", "covered_err", "rms",
                                                                          "seconds")}
            worst = float(max(r["covered_err"] for r in results))
            extra = ""
            if "outlier_named" in results[0]:
                extra = f"outlier named {sum(r['outlier_named'] for r in results)}/{len(results)}"
            if "offset" in results[0]:
                extra = "offset " + ", ".join(f"{r['offset']:+.3f}" for r in results) + " s (truth -0.200)"
            if "views" in results[0]:
                extra = "views used " + ", ".join(str(r["views"]) for r in results)
            rows.append(f"| {name} | {mean['overlap_err']:.2f} | {mean['covered_err']:.2f} | {worst:.2f} | "
                        f"{mean['rms']:.2f} | {mean['seconds']:.2f} | {extra} |")
            print(rows[-1], flush=True)
    header = ["| source | overlap corner err (RGB px) | covered err mean (T px) | covered err worst | fit RMS (T px) "
              "| s / fit | notes |", "|---|---|---|---|---|---|---|"]
    text = "\n".join(header + rows) + "\n"
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
