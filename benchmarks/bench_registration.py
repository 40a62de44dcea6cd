"""Benchmark of RGB->thermal registration on real aligned pairs warped by random known transforms.

For every aligned (visible, infrared) pair of RoadScene, TNO, VIFB and MSRS in ``../shared/data/fusion``, at its
native size, the infrared image is warped by random rig geometry (``--warp rig``, the default: a relative yaw and
pitch of +-1.5 deg seen through a 50-70 deg horizontal field of view, i.e. H = K R K^-1, then a similarity) or by a
random similarity alone (``--warp similarity``: scale 0.8-1.25, rotation +-5 deg, shift up to 10 % of the size) and
cropped to its valid area; the registration must recover the warp. ``--warp crop`` is a diagnostic: the same part of
the view a rig warp would show, cut out without any warp, so its failures are the reference's, not the warp's.
``--fov`` also crops the thermal side to a narrower field of view and resamples it to a smaller 5:4 frame (a 640x512
core beside a wider visible camera).
Success: within 2 px per 640 px of the RGB image's width. The datasets' own alignment is imperfect (a few pixels on
RoadScene, more on some VIFB/TNO pairs, see docs/registration.md), so the truth is the warp composed with the
registration of the unwarped pair ("relative" error); the error against the datasets' nominal identity alignment
("absolute") is reported too. Errors are mean corner errors at the thermal frame's corners, in RGB pixels.

Negatives: the RGB image of one pair against the warped infrared images of the pairs half and a third of the dataset
away must be rejected (a RegistrationError), never reported as a transform.

Timing: a 10-second 640x480 synthetic video pair (``rgbt_toolkit.synth``) registered end to end on 2 threads.

``--canvas`` keeps the whole warped infrared view on a zero-filled canvas instead of cropping it: the warped and the
unwarped pair then show the same content, so the warp composed with the unwarped pair's registration is the exact
answer (errors at the corners of the infrared view). ``--planar N`` adds generated planar pairs scored against their
exact truth, ``--overlay-negatives`` mismatches sharing one burned-in OSD, ``--timing-1280`` a 1280x1024 estimate.

Usage: python benchmarks/bench_registration.py [--warp rig|similarity|crop] [--canvas] [--fov] [--limit N]
       [--model homography] [--negatives 0|1|2] [--overlay-negatives] [--planar N] [--timing-1280]
       [--datasets ...] [--raw rows.json] [--out FILE]
"""

from __future__ import annotations

import argparse
import json
import os
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import machine
from rgbt_toolkit.errors import RegistrationError
from rgbt_toolkit.io.images import list_images, read_image
from rgbt_toolkit.synth.osd import draw_osd
from rgbt_toolkit.registration import SpatialSettings, estimate_transform, overlap_corner_error
from rgbt_toolkit.registration.synthetic import (
    narrower_view, random_rig_warp, random_similarity, rig_view_crop, same_content_box, warp_and_crop,
    warp_onto_canvas,
)
from rgbt_toolkit.registration.transforms import corners, project
from rgbt_toolkit.runtime import set_threads

REPO = Path(__file__).resolve().parents[1]
DATASETS = {"roadscene": ("vi", "ir"), "tno": ("vi", "ir"), "vifb": ("VI", "IR"), "msrs": ("vi", "ir")}  # folders
SUCCESS_PX = 2.0  # per TOLERANCE_WIDTH pixels of the RGB image's width: 2 px on a 640-px frame, 4 px on 1280 px
TOLERANCE_WIDTH = 640
# "fov" variant: the thermal side is cropped to this fraction of the visible field of view and resampled to a
# 640x512-like frame of this width, as a 1080p visible camera beside a 640x512 thermal core sees the world
FOV_FRACTION = 0.7
FOV_ASPECT = 512 / 640


def tolerance_px(rgb_width: int) -> float:
    """Success threshold for a frame of this width: registration error scales with the image, so does the bar."""
    return SUCCESS_PX * rgb_width / TOLERANCE_WIDTH


def draw_warp(rng: np.random.Generator, size: tuple[int, int], kind: str) -> np.ndarray:
    """A random RGB->thermal warp: a similarity, or rig geometry (relative yaw/pitch before the similarity)."""
    return random_rig_warp(rng, size) if kind == "rig" else random_similarity(rng, size)


def make_thermal(ir: np.ndarray, rng: np.random.Generator, kind: str, fov: bool,
                 canvas: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The warped infrared view and the truth (source pixels -> its pixels); ``fov``: narrower and resampled;
    ``canvas``: the whole warped view kept on a zero-filled canvas instead of cropped."""
    if canvas:
        return warp_onto_canvas(ir, draw_warp(rng, (ir.shape[1], ir.shape[0]), kind))
    if kind == "crop":
        thermal, truth = rig_view_crop(ir, rng)
    else:
        thermal, truth = warp_and_crop(ir, draw_warp(rng, (ir.shape[1], ir.shape[0]), kind))
    if fov:
        width = max(64, int(round(ir.shape[1] * float(rng.uniform(0.55, 0.85)))))
        size = (width, int(round(width * FOV_ASPECT)))
        thermal, truth = narrower_view(thermal, truth, fov_fraction=FOV_FRACTION, size=size)
    return thermal, truth


def view_corner_error(estimate: np.ndarray, reference: np.ndarray, truth: np.ndarray,
                      source_size: tuple[int, int]) -> float:
    """Mean distance (RGB pixels) between the corners of the infrared view, placed by ``truth`` (source pixels ->
    thermal pixels), mapped back by ``estimate`` and by ``reference`` (RGB -> thermal). On a canvas the frame's own
    corners lie in the zero fill; the view's corners are where the thermal camera sees."""
    points = project(truth, corners(source_size))
    return float(np.linalg.norm(project(np.linalg.inv(estimate), points) - project(np.linalg.inv(reference), points),
                                axis=1).mean())


def _pairs(shared: Path, name: str) -> list[tuple[Path, Path]]:
    vis, ir = DATASETS[name]
    root = shared / "data" / "fusion" / name
    return [(p, root / ir / p.name) for p in list_images(root / vis) if (root / ir / p.name).is_file()]


def _nmi(a: np.ndarray, b: np.ndarray, mask: np.ndarray, bins: int = 32) -> float:
    """Normalised mutual information (H(A) + H(B)) / H(A, B) of two uint8 grey images inside ``mask``."""
    joint = np.histogram2d(a[mask] // (256 // bins), b[mask] // (256 // bins), bins=bins, range=[[0, bins]] * 2)[0]
    joint /= joint.sum()

    def entropy(p):
        p = p[p > 0]
        return float(-(p * np.log(p)).sum())

    return (entropy(joint.sum(1)) + entropy(joint.sum(0))) / entropy(joint.ravel())


def alignment_check(rgb: np.ndarray, ir: np.ndarray, matrix: np.ndarray) -> tuple[float, float]:
    """NMI of the dataset's pair as given (identity) and after our registration, over the same pixels.

    An independent check of the "relative" protocol: intensity NMI is not what the registration optimises, so if it
    rises the datasets' nominal alignment is off, not our estimate.
    """
    import cv2

    from rgbt_toolkit.io.images import rgb_to_grey

    a = rgb_to_grey(rgb) if rgb.ndim == 3 else rgb
    b = rgb_to_grey(ir) if ir.ndim == 3 else ir
    h, w = a.shape
    warped = cv2.warpPerspective(b, matrix, (w, h), flags=cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR)
    valid = cv2.warpPerspective(np.ones_like(b), matrix, (w, h), flags=cv2.WARP_INVERSE_MAP | cv2.INTER_NEAREST)
    mask = cv2.erode(valid, np.ones((9, 9), np.uint8)) > 0
    if b.shape != a.shape:
        return float("nan"), _nmi(a, warped, mask)
    return _nmi(a, b, mask), _nmi(a, warped, mask)


def _estimate(rgb, thermal, settings):
    """(result or None, CPU seconds, refusal message or None, the estimate's evidence details either way)."""
    t0 = time.process_time()
    try:
        result = estimate_transform([rgb], [thermal], settings)
        return result, time.process_time() - t0, None, result.details
    except RegistrationError as exc:
        return None, time.process_time() - t0, str(exc), exc.details


def _registers(rgb: np.ndarray, thermal: np.ndarray, settings: SpatialSettings) -> bool:
    """Whether the whole still-pair path (``register_streams``: overlays found and left out, then the estimate)
    returns a transform for this pair."""
    from rgbt_toolkit.registration import RegisterSettings, register_streams

    try:
        register_streams(lambda: iter([(rgb, 0.0)]), lambda: iter([(thermal, 0.0)]),
                         RegisterSettings(spatial=settings))
    except RegistrationError:
        return False
    return True


def run_dataset(shared: Path, name: str, settings: SpatialSettings, limit: int | None, seed: int,
                n_negatives: int = 2, same_content: bool = False, warp: str = "similarity",
                fov: bool = False, canvas: bool = False, overlay_negatives: bool = False) -> list[dict]:
    pairs = _pairs(shared, name)
    if limit:
        pairs = pairs[:: max(1, len(pairs) // limit)][:limit]
    # mismatch partners: none for a single pair, distinct when there are few
    offsets = [o for o in dict.fromkeys((len(pairs) // 2, len(pairs) // 3)) if o > 0][:n_negatives]
    rows = []
    for index, (vis_path, ir_path) in enumerate(pairs):
        rng = np.random.default_rng([seed, index])
        rgb, ir = read_image(vis_path), read_image(ir_path)
        thermal, truth = make_thermal(ir, rng, warp, fov, canvas)
        size_t = (thermal.shape[1], thermal.shape[0])
        size_ir = (ir.shape[1], ir.shape[0])

        def view_error(estimate: np.ndarray, reference: np.ndarray) -> float:
            """At the thermal frame's corners; on a canvas, at the infrared view's (the frame's are fill)."""
            if canvas:
                return view_corner_error(estimate, reference, truth, size_ir)
            return overlap_corner_error(estimate, reference, size_t)

        base = _estimate(rgb, ir, settings)[0]
        w0 = time.perf_counter()
        result, cpu, error, _ = _estimate(rgb, thermal, settings)
        wall = time.perf_counter() - w0
        # negatives: this RGB against the warped infrared image of the pairs half and a third of the dataset away
        # (neighbouring RoadScene pairs are often consecutive frames of one drive, i.e. the same view)
        negatives = []
        for k, offset in enumerate(offsets):
            other = read_image(pairs[(index + offset) % len(pairs)][1])
            neg_rng = rng if k == 0 else np.random.default_rng([seed + 7, index])
            neg_thermal, _ = make_thermal(other, neg_rng, warp, fov, canvas)
            negative, neg_cpu, _, details = _estimate(rgb, neg_thermal, settings)
            # what the last fit saw: the second look's when there was one (accepted or refused)
            look = details.get("second_look")
            last = look if isinstance(look, dict) else details
            negatives.append((negative, last.get("evidence"), last.get("blocks_agreeing"), look is not None,
                              neg_cpu))
        overlay_accepted = None
        if overlay_negatives and offsets:
            # the same mismatch with one on-screen display burned into both frames: all the views share is the OSD
            other = read_image(pairs[(index + offsets[0]) % len(pairs)][1])
            neg_thermal, _ = make_thermal(other, np.random.default_rng([seed + 11, index]), warp, fov, canvas)
            overlay_accepted = _registers(draw_osd(rgb, 0.0, "rgb"), draw_osd(neg_thermal, 0.0, "rgb"), settings)
        nmi_identity, nmi_registered = alignment_check(rgb, ir, base.matrix) if base else (None, None)
        same_px = None
        if same_content and result:
            x0, y0, x1, y1 = same_content_box(truth, ir.shape[:2], thermal.shape[:2])
            part = _estimate(rgb, ir[y0:y1, x0:x1], settings)[0]
            if part:
                to_source = np.array([[1, 0, x0], [0, 1, y0], [0, 0, 1.0]])
                same_px = overlap_corner_error(result.matrix, truth @ to_source @ part.matrix, size_t)
        rows.append({
            "dataset": name, "pair": vis_path.name, "cpu_s": cpu, "wall_s": wall, "width": rgb.shape[1],
            "tolerance_px": tolerance_px(rgb.shape[1]), "truth": truth.tolist(), "rejected": result is None, "error": error,
            "nmi_identity": nmi_identity, "nmi_registered": nmi_registered,
            "base_rejected": base is None,
            "relative_px": view_error(result.matrix, truth @ base.matrix) if result and base else None,
            "absolute_px": view_error(result.matrix, truth) if result else None,
            "same_content_px": same_px,
            "quality": result.quality if result else None,
            "evidence": result.details["evidence"] if result else None,
            "negative_evidence": [n[1] for n in negatives],  # accepted or not (before: accepted ones only)
            "negative_blocks": [n[2] for n in negatives],  # agreeing blocks, where they were counted
            "negative_second_look": [n[3] for n in negatives],
            "negative_cpu_s": [n[4] for n in negatives],
            "negatives": len(negatives),
            "negative_accepted": sum(n[0] is not None for n in negatives),
            "overlay_negative_accepted": overlay_accepted,
        })
    return rows


def _pct(values, q):
    return float(np.percentile(values, q)) if len(values) else float("nan")


def summarise(rows: list[dict]) -> list[str]:
    lines = [
        "| dataset | pairs | widths (px) | success (rel <= tol) | success where the unwarped pair registers | "
        "rejected | rel p50 / p90 / p95 / max (px) | abs p50 / p90 (px) | accepted, rel > tol | negatives accepted | "
        "CPU s / pair |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    groups = sorted({r["dataset"] for r in rows}) + ["all"]
    for name in groups:
        sub = [r for r in rows if name == "all" or r["dataset"] == name]
        rel = np.array([r["relative_px"] for r in sub if r["relative_px"] is not None])
        ab = np.array([r["absolute_px"] for r in sub if r["absolute_px"] is not None])
        # success threshold per pair: 2 px per 640 px of its RGB width (older raw rows: 2 px)
        within = [r["relative_px"] <= r.get("tolerance_px", SUCCESS_PX) for r in sub if r["relative_px"] is not None]
        ok = int(np.sum(within))
        bad = len(within) - ok
        widths = [r.get("width", 0) for r in sub]
        referenced = sum(not r.get("base_rejected", False) for r in sub)
        lines.append(
            f"| {name} | {len(sub)} | {min(widths)}-{max(widths)} | {ok} ({ok / len(sub):.1%}) | "
            f"{ok} of {referenced} ({ok / max(referenced, 1):.1%}) | "
            f"{sum(r['rejected'] for r in sub)} | "
            f"{_pct(rel, 50):.2f} / {_pct(rel, 90):.2f} / {_pct(rel, 95):.2f} / {rel.max(initial=0):.1f} | "
            f"{_pct(ab, 50):.2f} / {_pct(ab, 90):.2f} | {bad} | "
            f"{sum(r['negative_accepted'] for r in sub)} of {sum(r['negatives'] for r in sub)} | "
            f"{np.median([r['cpu_s'] for r in sub]):.2f} |"
        )
    return lines


def same_content_summary(rows: list[dict]) -> list[str]:
    """Relative error when the unwarped pair is registered on the part of the view the warped crop shows."""
    lines = ["| dataset | warped pairs accepted | rel <= tol (whole-view reference) | same-content reference accepted | "
             "same-content rel <= tol | same-content p50 / p90 (px) |", "|---|---|---|---|---|---|"]
    for name in sorted({r["dataset"] for r in rows}) + ["all"]:
        sub = [r for r in rows if (name == "all" or r["dataset"] == name) and not r["rejected"]]
        same = np.array([r["same_content_px"] for r in sub if r["same_content_px"] is not None])
        same_ok = sum(r["same_content_px"] <= r.get("tolerance_px", SUCCESS_PX) for r in sub
                      if r["same_content_px"] is not None)
        whole = sum(r["relative_px"] is not None and r["relative_px"] <= r.get("tolerance_px", SUCCESS_PX) for r in sub)
        lines.append(f"| {name} | {len(sub)} | {whole} | {len(same)} | {same_ok} | "
                     f"{_pct(same, 50):.2f} / {_pct(same, 90):.2f} |")
    return lines


def negative_summary(rows: list[dict]) -> list[str]:
    """How close the mismatches came: their last fit's evidence by the number of blocks agreeing with it."""
    found: dict[tuple[bool, str], list[float]] = {}
    for r in rows:
        for evidence, blocks, second in zip(r["negative_evidence"], r["negative_blocks"], r["negative_second_look"]):
            if evidence is not None:
                found.setdefault((second, "not counted" if blocks is None else str(blocks)), []).append(evidence)
    lines = ["| fit | blocks agreeing | mismatches | highest evidence |", "|---|---|---|---|"]
    for second, key in sorted(found, key=lambda k: (k[0], k[1] == "not counted", int(k[1]) if k[1].isdigit() else 0)):
        lines.append(f"| {'second look' if second else 'first'} | {key} | {len(found[second, key])} | "
                     f"{max(found[second, key]):.2f} |")
    cpu = [c for r in rows for c in r["negative_cpu_s"]]
    if cpu:
        lines += ["", f"CPU per mismatch (refusals included): median {np.median(cpu):.2f} s, max {max(cpu):.2f} s"]
    return lines


def alignment_summary(rows: list[dict]) -> list[str]:
    """How often our registration of the unwarped pair beats the datasets' nominal alignment on intensity NMI."""
    lines = ["| dataset | unwarped pairs registered | NMI higher after registration | median NMI identity / registered |",
             "|---|---|---|---|"]
    for name in sorted({r["dataset"] for r in rows}):
        sub = [r for r in rows if r["dataset"] == name and r["nmi_identity"] is not None
               and np.isfinite(r["nmi_identity"])]
        if not sub:
            continue
        better = sum(r["nmi_registered"] > r["nmi_identity"] for r in sub)
        lines.append(f"| {name} | {len(sub)} | {better} ({better / len(sub):.0%}) | "
                     f"{np.median([r['nmi_identity'] for r in sub]):.4f} / "
                     f"{np.median([r['nmi_registered'] for r in sub]):.4f} |")
    return lines


def generated_scenes(seeds: range, dense: int = SpatialSettings().dense_iterations) -> list[str]:
    """Corner error on single frame pairs of the scene generator (true RGB->T homography with a 3 % keystone)."""
    from rgbt_toolkit.registration import corner_error
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    lines = ["| seed | homography (default) px | similarity px |", "|---|---|---|"]
    errors = {"homography": [], "similarity": []}
    for seed in seeds:
        renderer = SceneRenderer(SceneConfig(seed=seed))
        rgb, thermal = renderer.render(1.0, "rgb").image, renderer.render(1.0, "t").image
        for model in errors:
            result = estimate_transform([rgb], [thermal], SpatialSettings(model=model, dense_iterations=dense))
            errors[model].append(corner_error(result.matrix, renderer.h_rgb_to_t, renderer.config.rgb_size))
        lines.append(f"| {seed} | {errors['homography'][-1]:.2f} | {errors['similarity'][-1]:.2f} |")
    lines.append(f"| median | {np.median(errors['homography']):.2f} | {np.median(errors['similarity']):.2f} |")
    return lines


def planar_pairs(seeds: range, warp: str, settings: SpatialSettings) -> list[str]:
    """Absolute error on generated planar scenes (``rgbt_toolkit.synth``: one plane seen by both cameras, so the
    RGB->T homography is exact), the thermal frame warped by ``warp`` onto a canvas that keeps its whole view."""
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    lines = ["| seed | error (px, RGB) | CPU s |", "|---|---|---|"]
    errors = []
    for seed in seeds:
        renderer = SceneRenderer(SceneConfig(seed=seed, rgb_size=(640, 512), t_size=(640, 512)))
        rgb, thermal = renderer.render(1.0, "rgb").image, renderer.render(1.0, "t").image
        rng = np.random.default_rng([seed, 99])
        canvas, to_canvas = warp_onto_canvas(thermal, draw_warp(rng, (thermal.shape[1], thermal.shape[0]), warp))
        result, cpu, error, _ = _estimate(rgb, canvas, settings)
        if result is None:
            lines.append(f"| {seed} | refused: {error} | {cpu:.2f} |")
            errors.append(np.inf)
            continue
        errors.append(view_corner_error(result.matrix, to_canvas @ renderer.h_rgb_to_t, to_canvas, (640, 512)))
        lines.append(f"| {seed} | {errors[-1]:.2f} | {cpu:.2f} |")
    lines.append(f"| median / p90 / max | {np.median(errors):.2f} / {_pct(errors, 90):.2f} / {max(errors):.2f} | |")
    return lines


def timing_1280(shared: Path, settings: SpatialSettings, repeats: int = 5) -> list[str]:
    """CPU and wall time of one estimate (in process, one thread) on a 1280x1024 pair: MSRS 00055D upscaled
    (bicubic), its infrared image warped by rig geometry (seed 3) onto a canvas; and its error against the
    upscaled unwarped pair's registration. The same estimate without the final dense refinement runs in turn with
    it, so that both see the same load on a shared machine."""
    import cv2

    root = shared / "data" / "fusion" / "msrs"
    rgb, ir = (cv2.resize(read_image(root / folder / "00055D.png"), (1280, 1024), interpolation=cv2.INTER_CUBIC)
               for folder in ("vi", "ir"))
    canvas, truth = warp_onto_canvas(ir, random_rig_warp(np.random.default_rng(3), (1280, 1024)))
    variants = {f"dense_iterations={settings.dense_iterations}": settings}
    if settings.dense_iterations:
        variants["dense_iterations=0"] = replace(settings, dense_iterations=0)
    runs = {name: ([], [], None) for name in variants}
    for repeat in range(repeats + 1):  # the first run warms caches and imports
        for name, chosen in variants.items():
            w0, c0 = time.perf_counter(), time.process_time()
            result = estimate_transform([rgb], [canvas], chosen)
            if repeat:
                runs[name][0].append(time.perf_counter() - w0)
                runs[name][1].append(time.process_time() - c0)
            runs[name] = (runs[name][0], runs[name][1], result)
    lines = ["| pair | settings | canvas (px) | CPU min / median (s) | wall min / median (s) | rel error (px) |",
             "|---|---|---|---|---|---|"]
    for name, chosen in variants.items():
        walls, cpus, result = runs[name]
        base = estimate_transform([rgb], [ir], chosen)
        error = view_corner_error(result.matrix, truth @ base.matrix, truth, (1280, 1024))
        lines.append(f"| MSRS 00055D at 1280x1024, rig warp | {name} | {canvas.shape[1]}x{canvas.shape[0]} | "
                     f"{min(cpus):.2f} / {np.median(cpus):.2f} | {min(walls):.2f} / {np.median(walls):.2f} | "
                     f"{error:.2f} |")
    return lines


def video_timing(workdir: Path, threads: int) -> list[str]:
    """Register a 10 s 640x480 synthetic video pair (30 / 25 fps, thermal clock 0.2 s behind) on ``threads``."""
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.registration import RegisterSettings, corner_error, register_paths
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos

    cfg = SceneConfig(seed=11, duration=10.0, rgb_size=(640, 480), t_size=(640, 512), rgb_fps=30.0, t_fps=25.0,
                      t_offset=0.2, challenges=frozenset({"camera_motion"}))
    renderer = SceneRenderer(cfg)
    paths = write_scene_videos(renderer, workdir)
    lines = ["| run | wall s | CPU s | corner error px | offset s (truth -0.200) |", "|---|---|---|---|---|"]
    t0 = time.perf_counter()
    for path in (paths["rgb"], paths["t"]):
        for _ in open_frames(path):
            pass
    lines.append(f"| decode both videos only | {time.perf_counter() - t0:.2f} | | | |")
    for sync in (False, True):
        for _ in range(2):  # second run is warm (imports, caches)
            w0, c0 = time.perf_counter(), time.process_time()
            reg = register_paths(paths["rgb"], paths["t"], RegisterSettings(sync=sync))
            wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        err = corner_error(reg.calibration.matrix, renderer.h_rgb_to_t, cfg.rgb_size)
        lines.append(f"| register{' --sync' if sync else ''} | {wall:.2f} | {cpu:.2f} | {err:.2f} | "
                     f"{reg.calibration.time_offset:+.3f} |")
    return lines


def still_timing(workdir: Path, threads: int, repeats: int = 3) -> list[str]:
    """Wall and CPU time of the `rgbt register` command (a fresh process: interpreter start and imports included)
    on a generated 1280x1024 pair warped by rig geometry, and the corner error of what it wrote."""
    import subprocess
    import sys

    import cv2

    from rgbt_toolkit.registration import corner_error
    from rgbt_toolkit.registration.synthetic import procedural_scene

    rng = np.random.default_rng(1)
    visible, thermal = procedural_scene(rng, (1280, 1024))
    cropped, truth = warp_and_crop(thermal, random_rig_warp(rng, (1280, 1024)))
    rgb_path, t_path, out = workdir / "rgb.png", workdir / "t.png", workdir / "calib.json"
    cv2.imwrite(str(rgb_path), visible[..., ::-1])
    cv2.imwrite(str(t_path), cropped)
    command = [sys.executable, "-m", "rgbt_cli.main", "register", str(rgb_path), str(t_path), "-o", str(out),
               "--force", "--threads", str(threads)]
    lines = ["| run | wall s | CPU s (user + sys) | corner error px |", "|---|---|---|---|"]
    for k in range(repeats):
        before = os.times()
        w0 = time.perf_counter()
        subprocess.run(command, check=True, capture_output=True)
        wall = time.perf_counter() - w0
        after = os.times()
        cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
        matrix = np.array(json.loads(out.read_text())["rgb_to_thermal"])
        err = corner_error(matrix, truth, (1280, 1024))
        lines.append(f"| `rgbt register` 1280x1024 pair, {threads} thread(s), run {k + 1} | {wall:.2f} | {cpu:.2f} | "
                     f"{err:.2f} |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", type=Path, default=REPO.parent / "shared")
    parser.add_argument("--datasets", nargs="+", default=list(DATASETS), choices=list(DATASETS))
    parser.add_argument("--limit", type=int, default=None, help="pairs per dataset (evenly spaced); default all")
    parser.add_argument("--model", default="homography", choices=["homography", "affine", "similarity"])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--dense", type=int, default=None, metavar="N",
                        help="SpatialSettings.dense_iterations: the final dense refinement's evaluations per level "
                             "(0: off; default: the library's, 6 since D46)")
    parser.add_argument("--dense-levels", type=float, nargs="+", default=None, metavar="F",
                        help="SpatialSettings.dense_levels: fractions of the analysis size, coarse to fine (default: "
                             "the library's, 0.5 1.0 since D53; D46's was 1.0)")
    parser.add_argument("--dense-max-scale", type=float, default=None, metavar="X",
                        help="SpatialSettings.dense_max_scale (1: plain Gauss-Newton steps, D37's)")
    parser.add_argument("--dense-cutoff", type=float, default=None, metavar="C",
                        help="SpatialSettings.dense_cutoff (0: every direction moves, D37's; D46's default 0.02)")
    parser.add_argument("--dense-damping", type=float, default=None, metavar="D",
                        help="SpatialSettings.dense_damping (0: Gauss-Newton steps, D37's and D46's; default 0.005)")
    parser.add_argument("--stiffness", type=float, default=None,
                        help="SpatialSettings.stiffness (pull of the homography towards the similarity fit)")
    parser.add_argument("--warp", default="rig", choices=["rig", "similarity", "crop"],
                        help="rig: relative yaw/pitch (+-1.5 deg, 50-70 deg HFOV) then a similarity; or a similarity; "
                             "crop (diagnostic): the part of the view a rig warp shows, cut out unwarped")
    parser.add_argument("--canvas", action="store_true",
                        help="keep the whole warped infrared view on a zero-filled canvas (no crop): both fits see "
                             "the same content, so the warp composed with the unwarped pair's registration is exact")
    parser.add_argument("--fov", action="store_true",
                        help="thermal side also cropped to a narrower field of view and resampled to a smaller frame")
    parser.add_argument("--negatives", type=int, default=2, choices=[0, 1, 2], help="mismatched pairs per pair")
    parser.add_argument("--overlay-negatives", action="store_true",
                        help="also one mismatch per pair with the same on-screen display burned into both frames")
    parser.add_argument("--planar", type=int, default=0, metavar="N",
                        help="also N generated planar pairs (640x512, seeds 0..N-1) warped by --warp onto a canvas: "
                             "absolute error against the exact truth")
    parser.add_argument("--timing-1280", action="store_true",
                        help="also time the estimate on MSRS 00055D upscaled to 1280x1024, infrared rig-warped onto "
                             "a canvas (one thread, in process)")
    parser.add_argument("--same-content", action="store_true",
                        help="also register the unwarped pair on the part of the view the warped crop shows")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--raw", type=Path, default=None, help="also write per-pair rows as JSON")
    parser.add_argument("--timing", action="store_true", help="also time a 10 s 640x480 video pair (2 threads)")
    parser.add_argument("--generated", type=int, default=0, metavar="N",
                        help="also register single frames of N generated scenes (seeds 0..N-1)")
    parser.add_argument("--out", type=Path, default=None, help="write the tables to this markdown file")
    args = parser.parse_args()
    if args.canvas and (args.fov or args.same_content or args.warp == "crop"):
        parser.error("--canvas keeps the whole view: it goes with --warp rig or similarity, without --fov or "
                     "--same-content")
    set_threads(args.threads)
    settings = SpatialSettings(model=args.model)
    if args.stiffness is not None:
        settings = replace(settings, stiffness=args.stiffness)
    if args.dense is not None:
        settings = replace(settings, dense_iterations=args.dense)
    if args.dense_levels is not None:
        settings = replace(settings, dense_levels=tuple(args.dense_levels))
    if args.dense_max_scale is not None:
        settings = replace(settings, dense_max_scale=args.dense_max_scale)
    if args.dense_cutoff is not None:
        settings = replace(settings, dense_cutoff=args.dense_cutoff)
    if args.dense_damping is not None:
        settings = replace(settings, dense_damping=args.dense_damping)
    rows = []
    for name in args.datasets:
        rows += run_dataset(args.shared, name, settings, args.limit, args.seed, args.negatives, args.same_content,
                            args.warp, args.fov, args.canvas, args.overlay_negatives)
        if args.raw:
            args.raw.write_text(json.dumps(rows, indent=1))
    what = {"rig": "rig geometry (yaw/pitch + similarity)", "similarity": "similarities",
            "crop": "nothing (crops of the view a rig warp shows)"}[args.warp]
    view = (", thermal side narrower and resampled" if args.fov else
            ", the whole view kept on a canvas" if args.canvas else "")
    lines = [f"Registration of real pairs at native size warped by {what}{view} (model {args.model}, seed "
             f"{args.seed}; tolerance {SUCCESS_PX:g} px per {TOLERANCE_WIDTH} px of width); {machine.describe()}:",
             ""]
    lines += summarise(rows)
    if args.negatives:
        lines += ["", "Mismatches by agreeing blocks of their last fit (first fit: counted for evidence 0.5-1.5 only; second "
                  "look, for pairs refused for weak evidence alone: always counted):", ""]
        lines += negative_summary(rows)
    overlay = [r["overlay_negative_accepted"] for r in rows if r.get("overlay_negative_accepted") is not None]
    if overlay:
        lines += ["", f"Mismatches sharing one burned-in OSD (the whole `register_streams` path): {sum(overlay)} of "
                  f"{len(overlay)} accepted"]
    lines += ["", "Nominal alignment of the datasets vs our registration of the unwarped pairs (intensity NMI):", ""]
    lines += alignment_summary(rows)
    if args.same_content:
        lines += ["", "Diagnostic: reference registered on the same part of the view as the warped crop:", ""]
        lines += same_content_summary(rows)
    if args.generated:
        lines += ["", f"Generated scenes (320x240 RGB -> 256x192 thermal, seeds 0-{args.generated - 1}):", ""]
        lines += generated_scenes(range(args.generated), settings.dense_iterations)
    if args.planar:
        lines += ["", f"Planar generated pairs (640x512 both cameras, seeds 0-{args.planar - 1}), thermal frame "
                  f"warped ({args.warp}) onto a canvas; error against the exact truth at the thermal view's corners:",
                  ""]
        lines += planar_pairs(range(args.planar), args.warp if args.warp != "crop" else "rig", settings)
    if args.timing_1280:
        lines += ["", "One estimate on a 1280x1024 pair, one thread:", ""]
        lines += timing_1280(args.shared, settings)
    if args.timing:
        import tempfile

        set_threads(2)
        with tempfile.TemporaryDirectory() as tmp:
            lines += ["", "10-second 640x480 video pair (RGB 30 fps, thermal 640x512 25 fps), 2 threads:", ""]
            lines += video_timing(Path(tmp), 2)
            lines += ["", "Single 1280x1024 image pair (generated, rig warp), the whole command:", ""]
            for threads in (1, 2):
                lines += still_timing(Path(tmp), threads)[(0 if threads == 1 else 2):]
    text = "\n".join(lines)
    print(text)
    if args.out:
        from rgbt_toolkit._atomic import write_text_atomic

        write_text_atomic(args.out, text + "\n")


if __name__ == "__main__":
    main()
