"""Fuse visible/infrared image files (the library side of ``rgbt fuse``): read, register, fuse, write.

Reading the next pair and writing the previous result run in a background thread while the network works (image
codecs, ONNX Runtime and torch all release the GIL), so on two cores the I/O mostly hides behind the backbone.

The default network is the shipped ONNX export (:func:`load_fusion_net`): ``rgbt fuse`` on one pair then never imports
torch (2-4 s on the 2-core target, more than the whole 1.5 s start-up goal); user ``.pt`` heads still run in torch.
"""

from __future__ import annotations

import dataclasses
import os
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Iterator

import cv2
import numpy as np

from rgbt_toolkit._atomic import atomic_path
from rgbt_toolkit.errors import InputError, RgbtError
from rgbt_toolkit.fusion.image_fusion import FuseSettings, FusionNet, fuse_images, grey_of, weight_heatmap
from rgbt_toolkit.fusion.onnx_model import IMAGE_ONNX, OnnxMfnet
from rgbt_toolkit.fusion.pairs import Alignment, output_path
from rgbt_toolkit.io.pixels import as_uint8
from rgbt_toolkit.io.images import read_image, write_image

if TYPE_CHECKING:
    from rgbt_toolkit.fusion.model import MFNet


def load_fusion_net(weights: str | Path | None = None, backbone_weights: str | Path | None = None,
                    threads: int = 1) -> OnnxMfnet | MFNet:
    """The network of ``rgbt fuse``: the shipped ONNX export (:data:`IMAGE_ONNX`, ONNX Runtime with ``threads``
    intra-op threads, no torch import) unless the user passes their own heads or backbone weights (``.pt`` files,
    which only torch reads)."""
    if weights is None and backbone_weights is None:
        return OnnxMfnet(IMAGE_ONNX, threads=threads)
    from rgbt_toolkit.fusion.model import MFNet

    return MFNet.from_file(weights, backbone_weights)


@dataclass
class PairReport:
    """What happened to one pair: fused (``error`` None), failed (``error`` says why, file named) or skipped."""

    vis: Path
    ir: Path
    out: Path
    w_g: float = float("nan")
    mean_w_f: float = float("nan")
    timings: dict[str, float] = field(default_factory=dict)
    error: str | None = None  # the pair failed and nothing was written for it
    skipped: bool = False  # its outputs existed and ``skip_existing`` was asked

    @property
    def ok(self) -> bool:
        return self.error is None


@dataclass(frozen=True)
class PlannedPair:
    """One pair and the files it will write."""

    vis: Path
    ir: Path
    out: Path
    heat: Path | None  # weight heat map (``save_weights``)
    skip: bool = False  # outputs exist and ``skip_existing``: not fused again


# Per-pair problems: the pair is reported and skipped, the others are still fused.
PAIR_ERRORS = (RgbtError, OSError, cv2.error)


def plan_outputs(
    pairs: list[tuple[Path, Path]], out: str | Path, folder: bool | None = None, save_weights: bool = False,
    overwrite: bool = False, skip_existing: bool = False,
) -> list[PlannedPair]:
    """Output files of every pair, checked before anything is read or written.

    Parameters
    ----------
    folder : bool, optional
        Folder input (``OUT`` is then always a folder); default: more than one pair.
    overwrite, skip_existing : bool
        What to do with outputs that exist: replace them, or skip their pairs (re-running after a partial failure).
        With neither, existing outputs raise :class:`InputError` before any pair is fused.

    Raises
    ------
    InputError
        Bad ``OUT`` (see :func:`rgbt_toolkit.fusion.pairs.output_path`), two pairs (or a fused image and a weight map)
        that would write the same file, an output that is one of the inputs, or existing outputs.
    """
    folder = len(pairs) > 1 if folder is None else folder
    writers: dict[Path, str] = {}
    inputs = {p.resolve() for pair in pairs for p in pair}
    planned = []
    for vis, ir in pairs:
        target = output_path(out, vis, folder)
        heat = target.with_name(f"{target.stem}_weights.png") if save_weights else None
        for path, what in ((target, f"the fused image of {vis}"), (heat, f"the weight map of {vis}")):
            if path is None:
                continue
            if path in writers:
                raise InputError(f"{path}: would be both {writers[path]} and {what}; rename one input or fuse "
                                 "them into separate folders")
            if path.resolve() in inputs:
                raise InputError(f"{path}: {what} would overwrite an input image; choose another output")
            writers[path] = what
        planned.append(PlannedPair(vis, ir, target, heat))
    existing = [p for p in writers if os.path.lexists(p)]
    if existing and not overwrite:
        if not skip_existing:
            more = f" and {len(existing) - 1} more output(s) exist" if len(existing) > 1 else " exists"
            raise InputError(f"{existing[0]}{more}; pass --force to overwrite, or --skip-existing to fuse only "
                             "the pairs whose outputs are missing")
        found = set(existing)
        planned = [dataclasses.replace(p, skip=p.out in found and (p.heat is None or p.heat in found))
                   for p in planned]
    return planned


def _read(vis: Path, ir: Path, alignment: Alignment):
    t0 = time.perf_counter()
    v = as_uint8(read_image(vis), str(vis))
    i = grey_of(as_uint8(read_image(ir), str(ir)))
    i = alignment.apply(i, v.shape[:2], vis, ir)
    return v, i, time.perf_counter() - t0


def save_image(path: Path, image: np.ndarray) -> None:
    """Atomic write; PNG with fast zlib level 1 (4x less CPU than the default level, files ~15% larger)."""
    if path.suffix.lower() != ".png":
        write_image(path, image)
        return
    bgr = cv2.cvtColor(image, cv2.COLOR_RGB2BGR) if image.ndim == 3 else image
    ok, buf = cv2.imencode(".png", bgr, [cv2.IMWRITE_PNG_COMPRESSION, 1])
    if not ok:  # pragma: no cover - OpenCV encodes any uint8 grey/BGR array
        raise InputError(f"{path}: PNG encoding failed for an image of shape {image.shape}")
    with atomic_path(path) as tmp:
        tmp.write_bytes(buf.tobytes())


def _write(path: Path, image: np.ndarray, heat_path: Path | None, heat: np.ndarray | None) -> float:
    t0 = time.perf_counter()
    save_image(path, image)
    if heat_path is not None:
        save_image(heat_path, weight_heatmap(heat))
    return time.perf_counter() - t0


def fuse_files(
    pairs: list[tuple[Path, Path]], out: str | Path, net: FusionNet, settings: FuseSettings = FuseSettings(),
    alignment: Alignment | None = None, save_weights: bool = False, overwrite: bool = False,
    *, folder: bool | None = None, skip_existing: bool = False,
) -> Iterator[PairReport]:
    """Fuse each pair and write ``OUT`` (one pair, image suffix) or ``OUT/<stem>.png``; yield a report per pair.

    Outputs are checked up front (:func:`plan_outputs`, which raises before anything is fused). A pair that cannot
    be fused (unreadable image, sizes that differ, unsupported pixels) does not stop the others: its report carries
    the ``error`` (naming the files) and nothing is written for it. With ``save_weights`` the weight map ``W_F`` is
    written beside the image as ``<name>_weights.png`` (heat map). ``alignment`` brings the infrared image onto the
    visible grid.
    """
    planned = plan_outputs(pairs, out, folder, save_weights, overwrite, skip_existing)
    return fuse_planned(planned, net, settings, alignment or Alignment())


def fuse_planned(planned: list[PlannedPair], net: FusionNet, settings: FuseSettings, alignment: Alignment
                 ) -> Iterator[PairReport]:
    """:func:`fuse_files` for outputs already checked by :func:`plan_outputs` (a CLI checks before loading MFNet)."""
    for p in planned:
        if p.skip:
            yield PairReport(p.vis, p.ir, p.out, skipped=True)
    todo = [p for p in planned if not p.skip]
    with ThreadPoolExecutor(max_workers=2) as pool:
        pending_read = pool.submit(_read, todo[0].vis, todo[0].ir, alignment) if todo else None
        previous = None  # (report, write future) of the last fused pair, reported once its files are written
        for k, p in enumerate(todo):
            reading = pending_read
            if k + 1 < len(todo):
                pending_read = pool.submit(_read, todo[k + 1].vis, todo[k + 1].ir, alignment)
            report = PairReport(p.vis, p.ir, p.out)
            try:
                v, i, t_read = reading.result()
                result = fuse_images(v, i, net, settings)
            except PAIR_ERRORS as exc:
                report.error, result = _name_files(exc, p), None
            t_write = 0.0
            if previous is not None:
                done, t_write = _finish(*previous)
                yield done
                previous = None
            if result is None:
                yield report
                continue
            heat = result.w_f if p.heat is not None else None
            report.w_g, report.mean_w_f = result.w_g, float(result.w_f.mean())
            report.timings = {"read": t_read, **result.timings, "write(prev)": t_write}
            previous = (report, pool.submit(_write, p.out, result.fused, p.heat, heat), p)
        if previous is not None:
            yield _finish(*previous)[0]


def _finish(report: PairReport, writing, p: PlannedPair) -> tuple[PairReport, float]:
    """Wait for a pair's files; a write error becomes the pair's error."""
    try:
        return report, writing.result()
    except PAIR_ERRORS as exc:
        report.error = _name_files(exc, p)
        return report, 0.0


def _name_files(exc: BaseException, p: PlannedPair) -> str:
    """The one-line message of a per-pair error, prefixed with the pair's files unless it names one already."""
    text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
    if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in text:
        text = f"{exc.filename}: {exc.strerror or text}"
    if not any(str(f) in text for f in (p.vis, p.ir, p.out, p.heat) if f is not None):
        text = f"{p.vis} + {p.ir}: {text}"
    return text
