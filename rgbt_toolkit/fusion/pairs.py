"""Visible/infrared image pairs from two files or two folders (``rgbt fuse``, MFNet training folders), and how an
infrared image is brought onto its visible partner's grid.

Folders are paired by file stem (``vi/01.png`` with ``ir/01.jpg``). Alignment comes from an ``rgbt register``
calibration file (its sizes checked against each pair) or a bare ``{"H": [[h11, h12, h13], [h21, h22, h23],
[h31, h32, h33]]}`` mapping infrared pixels onto the visible image (``x_vis ~ H x_ir``).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError, RegistrationError
from rgbt_toolkit.io.images import IMAGE_SUFFIXES, list_images
from rgbt_toolkit.registration.calib import FORMAT as CALIBRATION_FORMAT
from rgbt_toolkit.registration.calib import check_frame_sizes, load_calibration

MAX_ASPECT_MISMATCH = 0.02  # log ratio of the two aspect ratios --registered tolerates (integer sizes, crops)
OUTPUT_SUFFIXES = IMAGE_SUFFIXES  # what write_image encodes (imageio/Pillow); .webp etc. are refused


@dataclass(frozen=True)
class Pairing:
    """Pairs found in two inputs, and the stems found on one side only (folder mode)."""

    pairs: list[tuple[Path, Path]]
    folders: bool  # two folders (OUT is then always a folder) rather than two files
    only_vis: list[str] = field(default_factory=list)
    only_ir: list[str] = field(default_factory=list)


def find_pairs(vis: str | Path, ir: str | Path) -> Pairing:
    """Pairs from two files, or from two folders matched by file stem (natural order), with the unpaired stems."""
    vis, ir = Path(vis), Path(ir)
    for p in (vis, ir):
        if not p.exists():
            raise MissingFileError(f"{p}: no such file or folder")
    if vis.is_file() and ir.is_file():
        return Pairing([(vis, ir)], folders=False)
    if vis.is_dir() and ir.is_dir():
        irs: dict[str, Path] = {}
        for p in list_images(ir):
            irs.setdefault(p.stem, p)
        vis_files = list_images(vis)
        pairs = [(v, irs[v.stem]) for v in vis_files if v.stem in irs]
        if not pairs:
            raise InputError(f"{vis} and {ir}: no image file stem appears in both folders")
        vis_stems = {v.stem for v in vis_files}
        return Pairing(pairs, True, [v.name for v in vis_files if v.stem not in irs],
                       [p.name for s, p in irs.items() if s not in vis_stems])
    raise InputError(f"{vis} and {ir}: give two image files or two folders, not one of each")


def pair_inputs(vis: str | Path, ir: str | Path) -> list[tuple[Path, Path]]:
    """``[(vis_file, ir_file), ...]`` from two files or two folders (matched by stem, natural order)."""
    return find_pairs(vis, ir).pairs


def output_path(out: str | Path, vis_file: Path, folder: bool, suffix: str = ".png") -> Path:
    """Where the fused image of ``vis_file`` goes.

    Rules (``rgbt fuse -o``): folder input -> ``OUT`` is a folder, ``OUT/<stem>.png`` (an existing *file* ``OUT`` is
    an error). File input -> ``OUT`` itself when it has an image suffix (:data:`OUTPUT_SUFFIXES`) and is not an
    existing folder; ``OUT/<stem>.png`` when ``OUT`` is an existing folder or has no suffix; any other suffix
    (``.txt``, ``.webp``) is an error rather than a folder named like a file.
    """
    out = Path(out)
    if out.exists() and not out.is_dir() and (folder or out.suffix.lower() not in OUTPUT_SUFFIXES):
        raise InputError(f"{out}: exists and is not a folder; "
                         + ("folder input writes a folder of fused images, choose a folder name" if folder
                            else f"give an image file name ({', '.join(OUTPUT_SUFFIXES)}) or a folder"))
    if folder or out.is_dir():
        return out / f"{vis_file.stem}{suffix}"
    if out.suffix.lower() in OUTPUT_SUFFIXES:
        return out
    if out.suffix:
        raise InputError(f"{out}: cannot write a {out.suffix} image; use one of {', '.join(OUTPUT_SUFFIXES)}, "
                         "or a name without a suffix for a folder")
    return out / f"{vis_file.stem}{suffix}"


@dataclass(frozen=True)
class Alignment:
    """How an infrared image is brought onto its visible partner's pixel grid before fusion.

    Default (nothing): the pair must already have the same size. ``resize`` (``rgbt fuse --registered``): the pair
    is co-registered (same field of view) but may differ in resolution; the infrared image is resized onto the
    visible grid. ``homography`` (``--calib``): infrared pixels -> visible pixels; ``rgb_size`` / ``thermal_size``
    (width, height) are the sizes the calibration was made for, checked against each pair when known.
    """

    homography: np.ndarray | None = None
    resize: bool = False
    source: Path | None = None
    rgb_size: tuple[int, int] | None = None
    thermal_size: tuple[int, int] | None = None

    def apply(self, ir: np.ndarray, vis_shape: tuple[int, int], vis_file: Path | str = "visible",
              ir_file: Path | str = "infrared") -> np.ndarray:
        """``ir`` on the visible grid ``vis_shape`` (h, w); :class:`InputError` naming both files if impossible."""
        vh, vw = vis_shape
        ih, iw = ir.shape[:2]
        if self.homography is not None:
            if self.rgb_size is not None:
                check_frame_sizes(self.source, (self.rgb_size, self.thermal_size), (vw, vh), (iw, ih),
                                  names=(str(vis_file), str(ir_file)))
            return warp_to_visible(ir, self.homography, (vh, vw))
        if (ih, iw) == (vh, vw):
            return ir
        if self.resize:
            # one field of view on both grids means one aspect ratio (up to rounding); stretching a 4:3 infrared
            # image onto a 5:4 visible one would misplace every edge near the borders, silently
            if abs(np.log((iw / ih) / (vw / vh))) > MAX_ASPECT_MISMATCH:
                raise InputError(f"{vis_file} is {vw}x{vh} ({vw / vh:.3f}:1) but {ir_file} is {iw}x{ih} "
                                 f"({iw / ih:.3f}:1): --registered needs one field of view, i.e. one aspect ratio; "
                                 "align them with --calib calib.json (rgbt register)")
            shrink = iw > vw or ih > vh
            return cv2.resize(ir, (vw, vh), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
        raise InputError(f"{vis_file} is {vw}x{vh} but {ir_file} is {iw}x{ih}; pass --registered if they show the "
                         "same field of view, or --calib calib.json (rgbt register) to align them")


def read_homography(path: str | Path) -> np.ndarray:
    """3x3 float homography (infrared -> visible) from a calibration file (see :func:`read_calibration`)."""
    return read_calibration(path).homography


def read_calibration(path: str | Path) -> "Alignment":
    """The alignment a calibration file describes: homography (infrared -> visible) and, where recorded, sizes.

    Takes the file ``rgbt register`` writes (its RGB -> thermal matrix, inverted here; it records the RGB and
    thermal image sizes it was made for) or a bare ``{"H": [[...], [...], [...]]}`` already mapping infrared to
    visible pixels (no sizes, so no size check).
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: calibration file not found")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: not valid JSON (line {getattr(exc, 'lineno', '?')})") from None
    if isinstance(data, dict) and data.get("format") == CALIBRATION_FORMAT:
        calib = load_calibration(path)
        return Alignment(calib.inverse, source=path, rgb_size=tuple(calib.rgb_size),
                         thermal_size=tuple(calib.thermal_size))
    h = data.get("H") if isinstance(data, dict) else None
    try:
        mat = np.asarray(h, dtype=np.float64)
    except (TypeError, ValueError):
        mat = np.zeros(0)
    if mat.shape != (3, 3) or not np.isfinite(mat).all():
        raise FileFormatError(f'{path}: expected {{"H": [[3 numbers], [3 numbers], [3 numbers]]}}, a 3x3 homography')
    if abs(np.linalg.det(mat)) < 1e-12:
        raise RegistrationError(f"{path}: the homography is singular (determinant ~0); re-run the calibration")
    return Alignment(mat / mat[2, 2] if abs(mat[2, 2]) > 1e-12 else mat, source=path)


def warp_to_visible(ir: np.ndarray, homography: np.ndarray, vis_shape: tuple[int, int]) -> np.ndarray:
    """Resample the infrared image onto the visible image's pixel grid (bilinear, black outside)."""
    h, w = vis_shape
    return cv2.warpPerspective(ir, homography, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
