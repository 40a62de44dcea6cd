"""Per-item task functions of the batch commands, and the registry of trackers they can call.

Tasks are top-level functions of ``(item, job)``; the runner binds ``job`` with :func:`functools.partial`, which
pickles by reference, so the same task runs in this process, in pool workers and on Dask workers. Each task writes
its outputs itself (atomically) and returns the list of paths written, which goes into the manifest.

Trackers are named, not imported: a :class:`TrackerSpec` holds ``"module:function"`` strings resolved inside the
worker, so a tracker module that is missing or heavy costs nothing until an item actually needs it.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from rgbt_toolkit.batch.items import Discovery, Item
from rgbt_toolkit.errors import InputError, RgbtError


@dataclass(frozen=True)
class TrackerSpec:
    """Where a tracker's batch entry points live.

    ``sequence_fn(seq_dir, preset) -> (N, 4) boxes`` in the RGB camera, for benchmark sequence folders;
    ``video_fn(rgb_path, t_path, out_dir, preset) -> {name: path}`` for video pairs. Either may be None.
    """

    sequence_fn: str | None
    video_fn: str | None = None
    presets: str | None = None  # "module:NAME" of the tracker's preset table, to check --preset before starting
    default_preset: str = "default"


def check_preset(spec: TrackerSpec, preset: str) -> None:
    """Fail before any worker starts when the tracker has a preset table that lacks ``preset``."""
    if spec.presets is None:
        return
    try:
        names = list(resolve(spec.presets))
    except RgbtError:
        return  # the tracker module is not importable here; each item will report that itself
    if preset not in names:
        raise InputError(f"unknown preset '{preset}'; choose one of {', '.join(names)}")


#: Named trackers ``rgbt batch track --tracker`` offers. The JMMAC API is the product's tracker.
TRACKERS: dict[str, TrackerSpec] = {
    "jmmac": TrackerSpec("rgbt_toolkit.jmmac.api:track_sequence_folder", "rgbt_toolkit.jmmac.api:track_video_pair",
                         "rgbt_toolkit.jmmac.config:PRESETS"),
    "csrt": TrackerSpec("rgbt_toolkit.batch.baselines:csrt_sequence", None,
                        "rgbt_toolkit.batch.baselines:CSRT_PRESETS", "rgb"),
}


def resolve(target: str) -> Callable[..., Any]:
    """Import ``"package.module:function"`` and return the function, with a one-line error when it is missing."""
    module_name, _, attr = target.partition(":")
    if not module_name or not attr:
        raise InputError(f"'{target}' is not a 'module:function' reference")
    try:
        module = importlib.import_module(module_name)
    except ImportError as exc:
        raise RgbtError(f"{target}: cannot import {module_name} ({exc})") from None
    try:
        return getattr(module, attr)
    except AttributeError:
        raise RgbtError(f"{target}: {module_name} has no {attr}") from None


def check_available(target: str | None) -> None:
    """Fail early, without importing it, when the module of ``"module:function"`` is not installed."""
    if target is None:
        return
    module_name = target.partition(":")[0]
    try:
        found = importlib.util.find_spec(module_name) is not None
    except (ImportError, ValueError):
        found = False
    if not found:
        raise RgbtError(f"{module_name} is not available in this installation, so '{target}' cannot run; "
                        f"update rgbt-toolkit or choose another --tracker")


def tracker_spec(name: str) -> TrackerSpec:
    """A registered tracker by name, or custom ``"module:seq_fn[,module:video_fn]"`` entry points."""
    if name in TRACKERS:
        return TRACKERS[name]
    if ":" in name:
        sequence_fn, _, video_fn = name.partition(",")
        return TrackerSpec(sequence_fn.strip() or None, video_fn.strip() or None)
    raise InputError(f"unknown tracker '{name}'; choose one of {', '.join(sorted(TRACKERS))} or give "
                     f"'module:function'")


@dataclass(frozen=True)
class TrackJob:
    """Settings of ``rgbt batch track``: which tracker, which preset, where results go."""

    out_dir: Path
    tracker: TrackerSpec = field(default_factory=lambda: TRACKERS["jmmac"])
    preset: str = "default"
    precision: int = 4  # decimals in the result files
    assume_aligned: bool = False  # video pairs are registered already (--assume-aligned): no estimate, no calibration

    def signature(self) -> str:
        """Identifies the job in the manifest: same tracker and preset, same results."""
        aligned = ":aligned" if self.assume_aligned else ""
        return f"track:{self.tracker.sequence_fn}|{self.tracker.video_fn}:{self.preset}{aligned}"

    def expected_outputs(self, item: Item) -> list[Path]:
        """Result paths an item will write (checked before a fresh run so nothing is overwritten silently)."""
        if item.kind == "sequence":
            return [self.out_dir / f"{item.key}.txt"]
        return [self.out_dir / item.key]


def plan_track(dataset_dir: str | os.PathLike, out_dir: str | os.PathLike, tracker: str = "jmmac",
               preset: str | None = None, assume_aligned: bool = False) -> tuple[TrackJob, Discovery]:
    """The job and items of ``rgbt batch track``, checked before any worker starts (``preset`` None: the tracker's
    default).

    Raises
    ------
    InputError
        Unknown tracker or preset, or nothing to track in ``dataset_dir``.
    RgbtError
        The tracker's module is not installed.
    """
    from rgbt_toolkit.batch.items import track_items

    spec = tracker_spec(tracker)
    preset = spec.default_preset if preset is None else preset
    found = track_items(dataset_dir)
    kinds = {item.kind for item in found.items}
    for kind, target in (("sequence", spec.sequence_fn), ("video_pair", spec.video_fn)):
        if kind in kinds:
            if target is None:
                raise InputError(f"tracker '{tracker}' cannot track {kind.replace('_', ' ')}s; found some in "
                                 f"{dataset_dir} (move them out, or choose a tracker that takes them)")
            check_available(target)
    check_preset(spec, preset)
    return TrackJob(Path(out_dir), spec, preset, assume_aligned=assume_aligned), found


def track_item(item: Item, job: TrackJob) -> list[str]:
    """Track one sequence folder or video pair; write its results; return the paths written.

    A sequence gives ``OUT/<name>.txt`` with one ``x,y,w,h`` row per frame in RGB-camera pixels: the RGBT234
    result-file layout, so ``rgbt eval --results OUT`` scores the folder directly. A video pair gives the tracker's
    own outputs in ``OUT/<stem>/``.
    """
    import numpy as np

    from rgbt_toolkit.io.boxes import write_boxes

    if item.kind == "sequence":
        if job.tracker.sequence_fn is None:
            raise InputError(f"{item.paths[0]}: this tracker does not take sequence folders")
        boxes = np.asarray(resolve(job.tracker.sequence_fn)(item.paths[0], job.preset), dtype=float)
        if boxes.ndim != 2 or boxes.shape[1] != 4:
            raise RgbtError(f"{item.paths[0]}: the tracker returned boxes of shape {boxes.shape}, expected (N, 4)")
        target = job.out_dir / f"{item.key}.txt"
        write_boxes(target, boxes, fmt="xywh", delimiter=",", precision=job.precision)
        return [str(target)]
    if item.kind == "video_pair":
        if job.tracker.video_fn is None:
            raise InputError(f"{item.paths[0]}: this tracker does not take video pairs")
        aligned = {"assume_aligned": True} if job.assume_aligned else {}  # custom video functions need not take it
        written = resolve(job.tracker.video_fn)(item.paths[0], item.paths[1], job.out_dir / item.key,
                                                job.preset, **aligned)
        return [str(p) for p in (written.values() if isinstance(written, dict) else written)]
    raise InputError(f"{item.key}: cannot track a {item.kind}")


@dataclass(frozen=True)
class FuseJob:
    """Settings of ``rgbt batch fuse``: output folder and format, MFNet weights, optional weight heat maps."""

    out_dir: Path
    weights: str | None = None  # MFNet heads file; None: the shipped ones
    suffix: str = ".png"
    save_weights: bool = False
    net_side: int = 192

    def signature(self) -> str:
        return f"fuse:{self.weights or 'shipped'}:{self.net_side}:{self.suffix}:{int(self.save_weights)}"

    def expected_outputs(self, item: Item) -> list[Path]:
        outputs = [self.out_dir / f"{item.key}{self.suffix}"]
        if self.save_weights:
            outputs.append(self.out_dir / f"{item.key}_weights.png")
        return outputs


def plan_fuse(vis: str | os.PathLike, ir: str | os.PathLike | None, out_dir: str | os.PathLike,
              weights: str | None = None, ext: str = "png", save_weights: bool = False) -> tuple[FuseJob, Discovery]:
    """The job and items of ``rgbt batch fuse``; fails before any worker starts when there are no weights."""
    from rgbt_toolkit.batch.items import image_pair_items
    from rgbt_toolkit.errors import MissingFileError

    found = image_pair_items(vis, ir)
    if weights is None:
        from rgbt_toolkit.fusion.weights_io import DEFAULT_WEIGHTS

        if not DEFAULT_WEIGHTS.is_file():
            raise MissingFileError(f"{DEFAULT_WEIGHTS}: the shipped MFNet weights are missing from this installation; "
                                   f"pass --weights heads.pt (made by rgbt train-mfnet)")
    elif not Path(weights).is_file():
        raise MissingFileError(f"{weights}: no such MFNet weights file")
    job = FuseJob(Path(out_dir), None if weights is None else str(weights), f".{ext.lstrip('.')}", save_weights)
    _refuse_overwriting_inputs(job, found.items)
    return job, found


def _refuse_overwriting_inputs(job: FuseJob, items: tuple[Item, ...]) -> None:
    """An output that is one of the inputs is refused whatever the flags: ``--overwrite`` must never destroy them."""
    inputs = {p.resolve() for item in items for p in item.paths}
    for item in items:
        for path in job.expected_outputs(item):
            if path.resolve() in inputs:
                raise InputError(f"{path}: the output for {item.paths[0]} would overwrite an input image; "
                                 f"choose another output")


_NETS: dict[str | None, Any] = {}  # one fusion network per worker process and weights file, built on its first item


def fuse_item(item: Item, job: FuseJob) -> list[str]:
    """Fuse one registered visible/infrared image pair with MFNet; write ``OUT/<stem><suffix>``."""
    from rgbt_toolkit.fusion.fuse_files import load_fusion_net
    from rgbt_toolkit.fusion.image_fusion import FuseSettings, fuse_images, weight_heatmap
    from rgbt_toolkit.io.images import read_image, write_image

    if job.weights not in _NETS:  # the shipped heads run in ONNX Runtime (no torch import), user .pt heads in torch
        _NETS[job.weights] = load_fusion_net(job.weights)
    vis, ir = read_image(item.paths[0]), read_image(item.paths[1])
    result = fuse_images(vis, ir, _NETS[job.weights], FuseSettings(net_side=job.net_side))
    target = job.out_dir / f"{item.key}{job.suffix}"
    write_image(target, result.fused)
    written = [str(target)]
    if job.save_weights:
        heat = job.out_dir / f"{item.key}_weights.png"
        write_image(heat, weight_heatmap(result.w_f))
        written.append(str(heat))
    return written


def existing_outputs(job: Any, items: list[Item]) -> list[Path]:
    """The output paths ``job`` would write for ``items`` that already exist on disk."""
    return [p for item in items for p in job.expected_outputs(item) if os.path.lexists(p)]
