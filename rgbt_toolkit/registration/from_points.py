"""Calibration from hand-picked correspondences: a CSV of ``x_rgb, y_rgb, x_t, y_t`` rows.

For rigs whose two images share too little for the image-based estimate (a drone against a night sky): the user
clicks the same few features (mast tips, lamp posts, a warm window corner) in one RGB and one thermal frame. Two
points fix a similarity, four (not on one line) a homography; more points let the robust fit name the mis-clicked
ones. Rows may be separated by commas, semicolons or spaces; a header line and ``#`` comments are allowed.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import FileFormatError, InputError
from rgbt_toolkit.io.boxes import read_text_file
from rgbt_toolkit.registration.fit import SourceFit, calibration_from_fit
from rgbt_toolkit.registration.weigh import fit_weighed

_SPLIT = re.compile(r"[,;\s]+")


def read_points(path: str | os.PathLike) -> tuple[np.ndarray, np.ndarray, list[int]]:
    """The RGB (N, 2) and thermal (N, 2) points of a correspondence file and each row's line number.

    Raises
    ------
    FileFormatError
        A row without four numbers (the message names the file and line), or no rows at all.
    """
    path = Path(path)
    text = read_text_file(path, "points file (x_rgb, y_rgb, x_t, y_t per line)")
    rows, lines, header_seen = [], [], False
    for number, line in enumerate(text.splitlines(), 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        tokens = [t for t in _SPLIT.split(line) if t]
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            if not rows and not header_seen:  # a header line such as "x_rgb,y_rgb,x_t,y_t"
                header_seen = True
                continue
            raise FileFormatError(f"{path}: line {number}: '{line}' is not four numbers x_rgb, y_rgb, x_t, y_t")
        if len(values) != 4 or not np.isfinite(values).all():
            raise FileFormatError(f"{path}: line {number}: expected four numbers x_rgb, y_rgb, x_t, y_t, got "
                                  f"'{line}'")
        rows.append(values)
        lines.append(number)
    if not rows:
        raise FileFormatError(f"{path}: no points; write one correspondence per line as x_rgb, y_rgb, x_t, y_t")
    table = np.asarray(rows, dtype=float)
    return table[:, :2], table[:, 2:], lines


def check_inside(points: np.ndarray, size: tuple[int, int], what: str, lines: list[int]) -> None:
    """Refuse points outside a frame of ``size`` (w, h): a wrong column or the other camera's coordinates."""
    w, h = size
    outside = np.flatnonzero((points[:, 0] < -0.5) | (points[:, 1] < -0.5) | (points[:, 0] > w - 0.5)
                             | (points[:, 1] > h - 0.5))
    if len(outside):
        k = outside[0]
        raise InputError(f"{what}: line {lines[k]}: point ({points[k, 0]:g}, {points[k, 1]:g}) lies outside the "
                         f"{w}x{h} frame")


def calibrate_from_points(path: str | os.PathLike, rgb_size: tuple[int, int], thermal_size: tuple[int, int], *,
                          model: str = "auto", threshold: float | None = None,
                          max_rms: float | None = None) -> SourceFit:
    """Fit the RGB->T transform to the correspondences in ``path`` (see
    :func:`~rgbt_toolkit.registration.weigh.fit_weighed`: ``"auto"`` picks the model the points' spread supports,
    the acceptance comes from their residual scale unless ``threshold`` is given, and the result carries its
    bootstrap uncertainty; :func:`~rgbt_toolkit.registration.fit.fit_points` for the checks).

    ``rgb_size`` and ``thermal_size`` (w, h) are the frame sizes the points were picked in; they go into the
    calibration (``rgbt track`` refuses it on other frame sizes) and every point must lie inside its frame.
    """
    rgb, thermal, lines = read_points(path)
    check_inside(rgb, rgb_size, f"{path} (RGB x_rgb, y_rgb)", lines)
    check_inside(thermal, thermal_size, f"{path} (thermal x_t, y_t)", lines)
    weighed = fit_weighed(rgb, thermal, model, rgb_size, thermal_size, threshold=threshold, max_rms=max_rms,
                          what=str(path))
    calibration = calibration_from_fit(weighed.fit, "points", rgb_size, thermal_size, evidence=weighed.evidence())
    return SourceFit(calibration, weighed.fit, tuple(f"line {n}" for n in lines), tuple(weighed.lines()))
