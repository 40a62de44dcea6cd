"""Inputs of ``rgbt fuse``: visible/infrared pairs from two files or two folders, and an optional homography.

Folders are paired by file stem (``vi/01.png`` with ``ir/01.jpg``). A calibration file maps infrared pixels onto the
visible image: ``{"H": [[h11, h12, h13], [h21, h22, h23], [h31, h32, h33]]}`` (``x_vis ~ H x_ir``). It is the minimal
format accepted until the registration module (``rgbt_toolkit.registration``) provides richer calibrations.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError, RegistrationError
from rgbt_toolkit.io.images import IMAGE_SUFFIXES, list_images
from rgbt_toolkit.registration.calib import FORMAT as CALIBRATION_FORMAT
from rgbt_toolkit.registration.calib import load_calibration


def pair_inputs(vis: str | Path, ir: str | Path) -> list[tuple[Path, Path]]:
    """``[(vis_file, ir_file), ...]`` from two files or two folders (matched by stem, natural order)."""
    vis, ir = Path(vis), Path(ir)
    for p in (vis, ir):
        if not p.exists():
            raise MissingFileError(f"{p}: no such file or folder")
    if vis.is_file() and ir.is_file():
        return [(vis, ir)]
    if vis.is_dir() and ir.is_dir():
        irs = {}
        for p in list_images(ir):
            irs.setdefault(p.stem, p)
        pairs = [(v, irs[v.stem]) for v in list_images(vis) if v.stem in irs]
        if not pairs:
            raise InputError(f"{vis} and {ir}: no image file stem appears in both folders")
        return pairs
    raise InputError(f"{vis} and {ir}: give two image files or two folders, not one of each")


def output_path(out: str | Path, vis_file: Path, many: bool, suffix: str = ".png") -> Path:
    """Where the fused image of ``vis_file`` goes: ``OUT`` itself for one pair with an image suffix, else ``OUT/stem``."""
    out = Path(out)
    if not many and out.suffix.lower() in IMAGE_SUFFIXES:
        return out
    return out / f"{vis_file.stem}{suffix}"


def read_homography(path: str | Path) -> np.ndarray:
    """3x3 float homography (infrared -> visible) from a calibration file.

    Takes the file ``rgbt register`` writes (its RGB -> thermal matrix, inverted here) or a bare
    ``{"H": [[...], [...], [...]]}`` already mapping infrared to visible pixels.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: calibration file not found")
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise FileFormatError(f"{path}: not valid JSON (line {getattr(exc, 'lineno', '?')})") from None
    if isinstance(data, dict) and data.get("format") == CALIBRATION_FORMAT:
        return load_calibration(path).inverse
    h = data.get("H") if isinstance(data, dict) else None
    try:
        mat = np.asarray(h, dtype=np.float64)
    except (TypeError, ValueError):
        mat = np.zeros(0)
    if mat.shape != (3, 3) or not np.isfinite(mat).all():
        raise FileFormatError(f'{path}: expected {{"H": [[3 numbers], [3 numbers], [3 numbers]]}}, a 3x3 homography')
    if abs(np.linalg.det(mat)) < 1e-12:
        raise RegistrationError(f"{path}: the homography is singular (determinant ~0); re-run the calibration")
    return mat / mat[2, 2] if abs(mat[2, 2]) > 1e-12 else mat


def warp_to_visible(ir: np.ndarray, homography: np.ndarray, vis_shape: tuple[int, int]) -> np.ndarray:
    """Resample the infrared image onto the visible image's pixel grid (bilinear, black outside)."""
    h, w = vis_shape
    return cv2.warpPerspective(ir, homography, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
