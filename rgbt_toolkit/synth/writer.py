"""Write a rendered scene to disk: two MP4 videos (each camera at its own rate) or an RGBT234-layout folder.

Both outputs carry the full truth in a JSON file: the config, the RGB->T homography, and per frame each camera's time,
box and challenge flags. Everything is written atomically.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import write_text_atomic
from rgbt_toolkit.io.boxes import write_boxes
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.video import VideoWriter
from rgbt_toolkit.synth.config import SceneConfig
from rgbt_toolkit.synth.render import RenderedFrame, SceneRenderer

Progress = Callable[[int], None]


def _frame_record(index: int, frame: RenderedFrame) -> dict:
    return {"index": index, "time": round(frame.time, 6), "box": [round(float(v), 3) for v in frame.box],
            "flags": sorted(k for k, v in frame.flags.items() if v)}


def _truth(renderer: SceneRenderer, rgb: list[dict], thermal: list[dict], layout: str) -> dict:
    config = asdict(renderer.config)
    config["challenges"] = sorted(renderer.config.challenges)
    return {
        "generator": "rgbt_toolkit.synth",
        "layout": layout,
        "config": config,
        "h_rgb_to_t": renderer.h_rgb_to_t.tolist(),
        "box_convention": "x, y, w, h; x, y = first pixel column/row covered (benchmark convention)",
        "rgb": {"fps": renderer.config.rgb_fps, "size": list(renderer.config.rgb_size), "frames": rgb},
        "t": {"fps": renderer.config.t_fps, "size": list(renderer.config.t_size),
              "offset_seconds": renderer.config.t_offset, "frames": thermal},
    }


def _as_rgb(image: np.ndarray) -> np.ndarray:
    return np.repeat(image[:, :, None], 3, axis=2) if image.ndim == 2 else image


def write_scene_videos(renderer: SceneRenderer, outdir: str | os.PathLike, name: str = "scene",
                       progress: Progress | None = None) -> dict[str, Path]:
    """Write ``<name>_rgb.mp4`` and ``<name>_t.mp4`` with box files, init files and ``<name>_scene.json``.

    Each camera samples the scene at its own frame rate; the thermal clock lags by ``config.t_offset`` seconds,
    so thermal frame j shows scene time ``j / t_fps + t_offset`` while its timestamp in the file is ``j / t_fps``.
    """
    cfg, out = renderer.config, Path(outdir)
    paths = {"rgb": out / f"{name}_rgb.mp4", "t": out / f"{name}_t.mp4"}
    records: dict[str, list[dict]] = {"rgb": [], "t": []}
    boxes: dict[str, list[np.ndarray]] = {"rgb": [], "t": []}
    for modality, fps, count, offset in (("rgb", cfg.rgb_fps, cfg.rgb_frame_count, 0.0),
                                         ("t", cfg.t_fps, cfg.t_frame_count, cfg.t_offset)):
        with VideoWriter(paths[modality], fps) as writer:
            for index in range(count):
                frame = renderer.render(index / fps + offset, modality, index)
                writer.write(_as_rgb(frame.image))
                records[modality].append(_frame_record(index, frame))
                boxes[modality].append(frame.box)
                if progress:
                    progress(1)
    for modality in ("rgb", "t"):
        stem = paths[modality].with_suffix("")
        write_boxes(f"{stem}.boxes.txt", np.array(boxes[modality]))
        write_boxes(f"{stem}.init.txt", np.array(boxes[modality][:1]))
    truth_path = out / f"{name}_scene.json"
    write_text_atomic(truth_path, json.dumps(_truth(renderer, records["rgb"], records["t"], "videos"), indent=1))
    return {**paths, "truth": truth_path}


def write_scene_sequence(renderer: SceneRenderer, outdir: str | os.PathLike,
                         progress: Progress | None = None) -> Path:
    """Write an RGBT234-layout sequence folder (``visible/``, ``infrared/``, box files, ``init.txt``).

    A benchmark folder pairs frames one to one, so both cameras are rendered at the RGB frame times (the thermal
    clock offset and rate are ignored here); each keeps its own resolution and ground truth.
    """
    cfg, out = renderer.config, Path(outdir)
    records: dict[str, list[dict]] = {"rgb": [], "t": []}
    boxes: dict[str, list[np.ndarray]] = {"rgb": [], "t": []}
    for index in range(cfg.rgb_frame_count):
        t = index / cfg.rgb_fps
        for modality, folder, letter in (("rgb", "visible", "v"), ("t", "infrared", "i")):
            frame = renderer.render(t, modality, index)
            write_image(out / folder / f"{index + 1:05d}{letter}.jpg", frame.image)
            records[modality].append(_frame_record(index, frame))
            boxes[modality].append(frame.box)
        if progress:
            progress(1)
    write_boxes(out / "visible.txt", np.array(boxes["rgb"]))
    write_boxes(out / "infrared.txt", np.array(boxes["t"]))
    write_boxes(out / "init.txt", np.array(boxes["rgb"][:1]))
    write_text_atomic(out / "scene.json", json.dumps(_truth(renderer, records["rgb"], records["t"], "rgbt234"),
                                                     indent=1))
    return out


def generate_scene(outdir: str | os.PathLike, challenges: list[str] | tuple[str, ...] = (), seed: int = 0,
                   layout: str = "videos", name: str = "scene", progress: Progress | None = None,
                   **config_fields) -> dict[str, Path] | Path:
    """Render a scene with the named challenges and write it in ``layout`` ('videos' or 'rgbt234')."""
    config = SceneConfig(challenges=frozenset(challenges), seed=seed, **config_fields)
    renderer = SceneRenderer(config)
    if layout == "videos":
        return write_scene_videos(renderer, outdir, name, progress)
    if layout == "rgbt234":
        return write_scene_sequence(renderer, Path(outdir) / name, progress)
    raise ValueError(f"unknown layout '{layout}'; choose 'videos' or 'rgbt234'")
