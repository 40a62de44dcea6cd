"""Write a rendered scene to disk: two MP4 videos (each camera at its own rate) or an RGBT234-layout folder.

Both outputs carry the full truth in a JSON file: the config, the RGB->T homography, and per frame each camera's time,
box, challenge flags and ``absent`` (no target pixel in view: wholly outside it, flag ``out_of_view``, whose box rows
are 0,0,0,0 as in the benchmarks, or wholly hidden, flag ``long_occlusion``, whose box rows keep the hidden
outline). A scene is written into a hidden staging folder and its files are moved to their final names together at
the end, so an interrupted run leaves neither a truncated video nor a mix of an old and a new scene (the ground truth
would no longer match the frames). Existing outputs are refused unless ``force``.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import asdict
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import check_writable, write_text_atomic
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.boxes import write_boxes
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.video import VideoWriter
from rgbt_toolkit.synth.config import SceneConfig
from rgbt_toolkit.synth.labels import hand_labels
from rgbt_toolkit.synth.render import RenderedFrame, SceneRenderer

Progress = Callable[[int], None]


def _frame_record(index: int, frame: RenderedFrame) -> dict:
    return {"index": index, "time": round(frame.time, 6), "box": [round(float(v), 3) for v in frame.box],
            "flags": sorted(k for k, v in frame.flags.items() if v), "absent": frame.absent}


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


def check_name(name: str) -> str:
    """``name`` if it is a plain file stem; a path (``a/b``, ``../x``), ``.``, ``..`` or an empty name would write
    outside OUTDIR, into a subfolder, or files called ``_rgb.mp4``."""
    if not name or name in (".", "..") or "/" in name or "\\" in name or "\0" in name:
        raise InputError(f"name '{name}' is not a plain file name; give a stem such as 'scene' (no '/', not '.')")
    return name


@contextlib.contextmanager
def _staged(outdir: Path, name: str) -> Iterator[Path]:
    """Yield a hidden folder inside ``outdir`` to write a scene into; on success move its entries onto ``outdir``.

    A folder entry replaces the one already there (forced: the earlier sequence's frames go with it, none stale).
    On any exit other than success (an error, Ctrl-C, SystemExit from SIGTERM) the staging folder is removed, and so
    are the output folders this call created, if they stayed empty.
    """
    created = [folder for folder in (outdir, *outdir.parents) if not folder.exists()]
    outdir.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=outdir))
    try:
        yield stage
        for entry in sorted(stage.iterdir()):
            target = outdir / entry.name
            if target.is_dir() and not target.is_symlink():
                shutil.rmtree(target)
            os.replace(entry, target)
        created = []
    finally:
        shutil.rmtree(stage, ignore_errors=True)
        for folder in created:  # deepest first
            with contextlib.suppress(OSError):
                folder.rmdir()  # only if empty


def _refuse_existing(paths: list[Path], force: bool) -> None:
    """One line naming the first output that exists (unless ``force``), before any frame is rendered."""
    for path in paths:
        if path.is_dir() and path.suffix not in (".mp4", ".txt", ".json"):  # visible/, infrared/
            if not force and any(path.iterdir()):
                raise InputError(f"{path}: already exists; pass --force to overwrite")
            continue
        check_writable(path, "scene file", overwrite=force)


def _as_rgb(image: np.ndarray) -> np.ndarray:
    return np.repeat(image[:, :, None], 3, axis=2) if image.ndim == 2 else image


LABEL_SEED = 20261206  # the labels' own random stream, so frames and truth do not change with label_jitter


def write_scene_videos(renderer: SceneRenderer, outdir: str | os.PathLike, name: str = "scene",
                       progress: Progress | None = None, *, force: bool = False,
                       label_jitter: float = 0.0) -> dict[str, Path]:
    """Write ``<name>_rgb.mp4`` and ``<name>_t.mp4`` with box files, init files and ``<name>_scene.json``.

    ``label_jitter`` > 0 also writes ``<name>_rgb.labels.txt`` and ``<name>_t.labels.txt``: each camera's truth
    boxes as a person labels them (:func:`~rgbt_toolkit.synth.labels.hand_labels`, that many px of noise, whole
    pixels), at that camera's frames, so the thermal clock lag ``t_offset`` is a time shift between the two files.

    Each camera samples the scene at its own frame rate; the thermal clock lags by ``config.t_offset`` seconds,
    so thermal frame j shows scene time ``j / t_fps + t_offset`` while its timestamp in the file is ``j / t_fps``.
    Existing files are refused unless ``force``; sizes must be even (H.264 yuv420p), else the video would be padded
    and no longer match the recorded size.
    """
    cfg, out = renderer.config, Path(outdir)
    check_name(name)
    for camera, (w, h) in (("RGB", cfg.rgb_size), ("thermal", cfg.t_size)):
        if w % 2 or h % 2:
            raise InputError(f"{camera} size {w}x{h}: MP4 video needs an even width and height; choose e.g. "
                             f"{w - w % 2}x{h - h % 2}, or the rgbt234 layout (JPEG frames)")
    if cfg.t_frame_count < 1:
        raise InputError(f"duration {cfg.duration:g} s at {cfg.t_fps:g} fps gives no thermal frame; make the duration "
                         "longer or the frame rate higher")
    stems = {"rgb": f"{name}_rgb", "t": f"{name}_t"}
    ends = (".mp4", ".boxes.txt", ".init.txt") + ((".labels.txt",) if label_jitter > 0 else ())
    files = [f"{stem}{end}" for stem in stems.values() for end in ends]
    _refuse_existing([out / f for f in (*files, f"{name}_scene.json")], force)
    records: dict[str, list[dict]] = {"rgb": [], "t": []}
    boxes: dict[str, list[np.ndarray]] = {"rgb": [], "t": []}
    with _staged(out, name) as stage:
        for modality, fps, count, offset in (("rgb", cfg.rgb_fps, cfg.rgb_frame_count, 0.0),
                                             ("t", cfg.t_fps, cfg.t_frame_count, cfg.t_offset)):
            with VideoWriter(stage / f"{stems[modality]}.mp4", fps, keep_partial=False) as writer:
                for index in range(count):
                    frame = renderer.render(index / fps + offset, modality, index)
                    writer.write(_as_rgb(frame.image))
                    records[modality].append(_frame_record(index, frame))
                    boxes[modality].append(frame.box)
                    if progress:
                        progress(1)
        for modality, stem in stems.items():
            write_boxes(stage / f"{stem}.boxes.txt", np.array(boxes[modality]))
            write_boxes(stage / f"{stem}.init.txt", np.array(boxes[modality][:1]))
        if label_jitter > 0:
            rng = np.random.default_rng([cfg.seed, LABEL_SEED])
            for modality, stem in stems.items():
                write_boxes(stage / f"{stem}.labels.txt", hand_labels(np.array(boxes[modality]), label_jitter, rng))
        write_text_atomic(stage / f"{name}_scene.json",
                          json.dumps(_truth(renderer, records["rgb"], records["t"], "videos"), indent=1))
    written = {"rgb": out / f"{stems['rgb']}.mp4", "t": out / f"{stems['t']}.mp4", "truth": out / f"{name}_scene.json"}
    if label_jitter > 0:
        written.update(labels_rgb=out / f"{stems['rgb']}.labels.txt", labels_t=out / f"{stems['t']}.labels.txt")
    return written


def write_scene_sequence(renderer: SceneRenderer, outdir: str | os.PathLike,
                         progress: Progress | None = None, *, force: bool = False) -> Path:
    """Write an RGBT234-layout sequence folder (``visible/``, ``infrared/``, box files, ``init.txt``).

    A benchmark folder pairs frames one to one, so both cameras are rendered at the RGB frame times (the thermal
    clock offset and rate are ignored here); each keeps its own resolution and ground truth. An earlier sequence in
    ``outdir`` is refused unless ``force``, which replaces its frame folders whole (no stale frames stay).
    """
    cfg, out = renderer.config, Path(outdir)
    entries = ("visible", "infrared", "visible.txt", "infrared.txt", "init.txt", "scene.json")
    _refuse_existing([out / entry for entry in entries], force)
    records: dict[str, list[dict]] = {"rgb": [], "t": []}
    boxes: dict[str, list[np.ndarray]] = {"rgb": [], "t": []}
    with _staged(out, out.name) as stage:
        for index in range(cfg.rgb_frame_count):
            t = index / cfg.rgb_fps
            for modality, folder, letter in (("rgb", "visible", "v"), ("t", "infrared", "i")):
                frame = renderer.render(t, modality, index)
                write_image(stage / folder / f"{index + 1:05d}{letter}.jpg", frame.image)
                records[modality].append(_frame_record(index, frame))
                boxes[modality].append(frame.box)
            if progress:
                progress(1)
        write_boxes(stage / "visible.txt", np.array(boxes["rgb"]))
        write_boxes(stage / "infrared.txt", np.array(boxes["t"]))
        write_boxes(stage / "init.txt", np.array(boxes["rgb"][:1]))
        write_text_atomic(stage / "scene.json",
                          json.dumps(_truth(renderer, records["rgb"], records["t"], "rgbt234"), indent=1))
    return out


def generate_scene(outdir: str | os.PathLike, challenges: list[str] | tuple[str, ...] = (), seed: int = 0,
                   layout: str = "videos", name: str = "scene", progress: Progress | None = None,
                   force: bool = False, label_jitter: float = 0.0, **config_fields) -> dict[str, Path] | Path:
    """Render a scene with the named challenges and write it in ``layout`` ('videos' or 'rgbt234').

    ``name`` is a file stem (videos) or the sequence folder's name (rgbt234); existing outputs are refused unless
    ``force``. ``label_jitter``: hand-label files too (videos layout; see :func:`write_scene_videos`).
    """
    config = SceneConfig(challenges=frozenset(challenges), seed=seed, **config_fields)
    check_name(name)
    if not (np.isfinite(label_jitter) and label_jitter >= 0):
        raise InputError(f"label jitter must be a number of pixels >= 0, got {label_jitter}")
    if label_jitter > 0 and layout != "videos":
        raise InputError("hand labels (label jitter) are written with the videos layout, whose cameras keep their "
                         "own clocks; the rgbt234 layout pairs frames one to one")
    renderer = SceneRenderer(config)
    if layout == "videos":
        return write_scene_videos(renderer, outdir, name, progress, force=force, label_jitter=label_jitter)
    if layout == "rgbt234":
        return write_scene_sequence(renderer, Path(outdir) / name, progress, force=force)
    raise ValueError(f"unknown layout '{layout}'; choose 'videos' or 'rgbt234'")
