"""Box files: read and write x,y,w,h, x1 y1 x2 y2, 4-corner and VOT polygon rows, with the VOT 1/2/0 markers.

Inside the toolkit every box is a float ``[x, y, w, h]`` with ``x, y`` the top-left corner, in the pixel coordinates
of the file (no +/-1 shifts). Conversions happen only here, at the file edge, with the conventions of the benchmark
toolkits (``../shared/reference/jmmac_official_code_notes.md``):

* ``xyxy`` rows ``x1 y1 x2 y2`` (GTOT ground truth) become ``w = x2 - x1``, ``h = y2 - y1`` -- no ``+1``. The GTOT
  toolkit converts this way and the published GTOT numbers are only reproduced with it.
* ``corners`` rows ``x1,y1,x2,y1,x2,y2,x1,y2`` (result files of several RGB-T trackers) become ``x = x1, y = y1,
  w = x2 - x1, h = y2 - y1``, taken from the fixed positions of that row layout.
* ``polygon`` rows (VOT, any even count >= 6) become the axis-aligned bounding box of their points.

Separators may be commas, spaces, tabs or semicolons, mixed freely. Blank lines are skipped (as ``numpy.loadtxt``
does). A row reading ``nan`` (one token, or one per value) is a missing box: NaN in all four values.
"""

from __future__ import annotations

import math
import os
import re
from pathlib import Path
from typing import Sequence, Union

import numpy as np

from rgbt_toolkit._atomic import atomic_path
from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError

BOX_FORMATS = ("auto", "xywh", "xyxy", "corners", "polygon")
VOT_INIT, VOT_FAILURE, VOT_SKIP = 1, 2, 0
VotEntry = Union[int, np.ndarray]

_SEPARATORS = re.compile(r"[,;\t]")


# --------------------------------------------------------------------------------------------------- conversions
def xyxy_to_xywh(boxes: np.ndarray) -> np.ndarray:
    """``x1, y1, x2, y2`` -> ``x, y, w, h`` with ``w = x2 - x1`` (GTOT convention, no ``+1``); works on (..., 4)."""
    b = np.asarray(boxes, dtype=float)
    return np.concatenate([b[..., :2], b[..., 2:4] - b[..., :2]], axis=-1)


def xywh_to_xyxy(boxes: np.ndarray) -> np.ndarray:
    """``x, y, w, h`` -> ``x1, y1, x2, y2`` with ``x2 = x + w``; the exact inverse of :func:`xyxy_to_xywh`."""
    b = np.asarray(boxes, dtype=float)
    return np.concatenate([b[..., :2], b[..., :2] + b[..., 2:4]], axis=-1)


def corners_to_xywh(rows: np.ndarray) -> np.ndarray:
    """Benchmark corner rows ``x1,y1,x2,y1,x2,y2,x1,y2`` -> ``x1, y1, x2 - x1, y2 - y1`` (fixed positions, no +1)."""
    p = np.asarray(rows, dtype=float)
    return np.stack([p[..., 0], p[..., 1], p[..., 4] - p[..., 0], p[..., 5] - p[..., 1]], axis=-1)


def polygon_to_xywh(polygons: np.ndarray) -> np.ndarray:
    """Polygons (..., 2k) as ``x1, y1, x2, y2, ...`` -> their axis-aligned bounding boxes (..., 4)."""
    p = np.asarray(polygons, dtype=float)
    if p.shape[-1] < 6 or p.shape[-1] % 2:
        raise InputError(f"a polygon needs an even number of at least 6 values, got {p.shape[-1]}")
    xs, ys = p[..., 0::2], p[..., 1::2]
    x0, y0 = xs.min(axis=-1), ys.min(axis=-1)
    return np.stack([x0, y0, xs.max(axis=-1) - x0, ys.max(axis=-1) - y0], axis=-1)


def xywh_to_polygon(boxes: np.ndarray) -> np.ndarray:
    """``x, y, w, h`` -> 4-corner polygons ``x,y, x+w,y, x+w,y+h, x,y+h`` (..., 8), clockwise from top-left."""
    b = np.asarray(boxes, dtype=float)
    x, y = b[..., 0], b[..., 1]
    x2, y2 = x + b[..., 2], y + b[..., 3]
    return np.stack([x, y, x2, y, x2, y2, x, y2], axis=-1)


# ------------------------------------------------------------------------------------------------------- parsing
def read_text_file(path: Path, what: str = "box file") -> str:
    """A label or result file's text (a BOM dropped), or a one-line error naming the file and what it should be."""
    if not path.is_file():
        raise MissingFileError(f"{path}: no such {what}")
    try:
        return path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise FileFormatError(f"{path}: not a text {what} (cannot decode as UTF-8)") from None


_TO_SPACE = str.maketrans({",": " ", ";": " ", "\t": " ", "\r": " "})
_ROW_PATTERNS: dict[int, re.Pattern] = {}


def _fast_table(text: str) -> np.ndarray | None:
    """The file as an (N, k) float table when every non-blank line has the same k numeric fields, else ``None``.

    One regular-expression pass checks the shape of every line in C (the token and gap classes are disjoint, so
    matching is linear); the per-line parser then only runs for files that need its error messages or NaN rows.
    """
    norm = text.translate(_TO_SPACE)
    head = norm.lstrip().split("\n", 1)[0].split()
    k = len(head)
    if k not in (4, 8):
        return None
    pattern = _ROW_PATTERNS.get(k)
    if pattern is None:
        row = rf"(?: *(?:[^\s]+ +){{{k - 1}}}[^\s]+ *)"
        pattern = _ROW_PATTERNS[k] = re.compile(rf"(?:{row}?\n)*{row}?")
    if pattern.fullmatch(norm) is None:
        return None
    tokens = norm.split()
    try:
        flat = np.array(list(map(float, tokens)), dtype=float)
    except ValueError:
        return None
    if np.isinf(flat).any():  # the checked path reports the line
        return None
    return flat.reshape(-1, k)


def _split_lines(text: str) -> tuple[list[int], list[list[str]]]:
    """Line numbers (1-based, blank lines skipped) and the tokens of each line."""
    numbers, rows = [], []
    for number, line in enumerate(_SEPARATORS.sub(" ", text).splitlines(), start=1):
        tokens = line.split()
        if tokens:
            numbers.append(number)
            rows.append(tokens)
    return numbers, rows


def _to_float(tokens: list[str], path: Path, number: int) -> list[float]:
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        bad = next(t for t in tokens if not _is_float(t))
        raise FileFormatError(f"{path}, line {number}: '{bad}' is not a number; box rows hold numbers only") from None
    if any(math.isinf(v) for v in values):
        raise FileFormatError(f"{path}, line {number}: infinite value in a box row")
    return values


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _row_to_xywh(values: list[float], fmt: str, path: Path, number: int) -> list[float]:
    n = len(values)
    if n == 1 and math.isnan(values[0]):
        return [math.nan] * 4
    if fmt in ("xywh", "xyxy") or (fmt == "auto" and n == 4):
        if n != 4:
            raise FileFormatError(f"{path}, line {number}: expected 4 values for '{fmt}' boxes, got {n}")
        return list(xyxy_to_xywh(np.array(values))) if fmt == "xyxy" else values
    if fmt == "corners":
        if n != 8:
            raise FileFormatError(f"{path}, line {number}: expected 8 values for 4-corner rows, got {n}")
        return list(corners_to_xywh(np.array(values)))
    if n < 6 or n % 2:
        raise FileFormatError(
            f"{path}, line {number}: {n} values is neither a box (4) nor a polygon (an even count >= 6)"
        )
    return list(polygon_to_xywh(np.array(values)))


def read_boxes(path: str | os.PathLike, fmt: str = "auto") -> np.ndarray:
    """Read a box file as a float (N, 4) array of ``x, y, w, h``.

    Parameters
    ----------
    path : path-like
        Text file, one box per line.
    fmt : {"auto", "xywh", "xyxy", "corners", "polygon"}
        Row layout. ``auto`` takes 4 values as ``x, y, w, h`` and 6 or more as a polygon (for the benchmark corner
        rows this equals ``corners``). ``xyxy`` must be named explicitly since 4 values cannot tell it apart.

    Returns
    -------
    numpy.ndarray
        (N, 4) float; rows of ``nan`` stay NaN so frame indices are kept.

    Raises
    ------
    MissingFileError
        The file does not exist.
    FileFormatError
        A line is malformed; the message names the file and the line number.
    """
    if fmt not in BOX_FORMATS:
        raise InputError(f"unknown box format '{fmt}'; choose one of {', '.join(BOX_FORMATS)}")
    path = Path(path)
    text = read_text_file(path)
    table = _fast_table(text)
    if table is not None:
        width = table.shape[1]
        if width == 4 and fmt in ("auto", "xywh"):
            return table
        if width == 4 and fmt == "xyxy":
            return xyxy_to_xywh(table)
        if width == 8 and fmt == "corners":
            return corners_to_xywh(table)
        if width == 8 and fmt in ("auto", "polygon"):
            return polygon_to_xywh(table)
    numbers, rows = _split_lines(text)
    out = [_row_to_xywh(_to_float(r, path, n), fmt, path, n) for n, r in zip(numbers, rows)]
    return np.array(out, dtype=float).reshape(-1, 4)


def read_vot_regions(path: str | os.PathLike, allow_markers: bool = True) -> list[VotEntry]:
    """Read a VOT trajectory or ground truth without converting polygons.

    Each entry is an ``int`` marker (1 = initialisation, 2 = failure, 0 = skipped frame), a rectangle as a float
    array ``[x, y, w, h]``, or a polygon as a float array ``[x1, y1, ..., xk, yk]`` (k >= 3). ``nan`` rows become a
    NaN rectangle. Markers raise :class:`FileFormatError` when ``allow_markers`` is false (ground truth).
    """
    path = Path(path)
    numbers, rows = _split_lines(read_text_file(path))
    entries: list[VotEntry] = []
    for number, tokens in zip(numbers, rows):
        values = _to_float(tokens, path, number)
        if len(values) == 1:
            if math.isnan(values[0]):
                entries.append(np.full(4, np.nan))
                continue
            code = values[0]
            if not allow_markers or code not in (VOT_INIT, VOT_FAILURE, VOT_SKIP):
                what = "ground truth holds regions only" if not allow_markers else "markers are 1, 2 or 0"
                raise FileFormatError(f"{path}, line {number}: unexpected single value {tokens[0]} ({what})")
            entries.append(int(code))
        elif len(values) == 4 or (len(values) >= 6 and len(values) % 2 == 0):
            entries.append(np.array(values, dtype=float))
        else:
            raise FileFormatError(
                f"{path}, line {number}: {len(values)} values is neither a rectangle (4) nor a polygon (even, >= 6)"
            )
    return entries


def _entry_to_xywh(entry: VotEntry) -> VotEntry:
    if isinstance(entry, int):
        return entry
    return entry if entry.size == 4 else polygon_to_xywh(entry)


def read_vot_groundtruth(path: str | os.PathLike) -> list[np.ndarray]:
    """VOT ``groundtruth.txt`` as a list of ``[x, y, w, h]`` arrays; polygons become their axis-aligned bounds.

    Use :func:`read_vot_regions` to keep rotated polygons for exact VOT overlaps.
    """
    return [_entry_to_xywh(e) for e in read_vot_regions(path, allow_markers=False)]


def read_vot_results(path: str | os.PathLike) -> list[VotEntry]:
    """VOT result file: ``int`` markers (1 init, 2 failure, 0 skipped) or ``[x, y, w, h]`` arrays per frame."""
    return [_entry_to_xywh(e) for e in read_vot_regions(path, allow_markers=True)]


# ------------------------------------------------------------------------------------------------------- writing
def _format_value(value: float, precision: int) -> str:
    if math.isnan(value):
        return "nan"
    text = f"{value:.{precision}f}"
    return text[1:] if text.startswith("-") and float(text) == 0 else text  # no "-0.0000"


def write_boxes(
    path: str | os.PathLike,
    boxes: np.ndarray,
    fmt: str = "xywh",
    delimiter: str = ",",
    precision: int = 4,
) -> None:
    """Write (N, 4) ``x, y, w, h`` boxes atomically, one row per frame.

    Parameters
    ----------
    fmt : {"xywh", "xyxy", "corners", "polygon"}
        Row layout; ``xyxy`` writes ``x + w`` as ``x2`` (inverse of the GTOT reading); ``corners`` and ``polygon``
        both write the 8-value corner row.
    delimiter : str
        Between values: ``","``, ``" "`` or ``"\\t"``.
    precision : int
        Decimals per value (0 writes integers, as benchmark result files usually are). NaN rows are written ``nan``.
    """
    if fmt not in BOX_FORMATS or fmt == "auto":
        raise InputError(f"cannot write box format '{fmt}'; choose xywh, xyxy, corners or polygon")
    if delimiter not in (",", " ", "\t", ";"):
        raise InputError(f"delimiter must be a comma, space, tab or semicolon, got {delimiter!r}")
    b = np.asarray(boxes, dtype=float)
    if b.ndim != 2 or b.shape[1] != 4:
        raise InputError(f"boxes must be an (N, 4) array of x, y, w, h; got shape {b.shape}")
    table = {"xywh": b, "xyxy": xywh_to_xyxy(b)}.get(fmt)
    if table is None:
        table = xywh_to_polygon(b)
    lines = [delimiter.join(_format_value(v, precision) for v in row) for row in table.tolist()]
    with atomic_path(path) as tmp:
        tmp.write_text("".join(line + "\n" for line in lines), encoding="utf-8")


def write_vot_results(path: str | os.PathLike, entries: Sequence[VotEntry], precision: int = 4) -> None:
    """Write a VOT trajectory atomically: markers as bare integers, rectangles and polygons comma-separated."""
    lines = []
    for entry in entries:
        if isinstance(entry, (int, np.integer)):
            if entry not in (VOT_INIT, VOT_FAILURE, VOT_SKIP):
                raise InputError(f"VOT markers are 1, 2 or 0, got {entry}")
            lines.append(str(int(entry)))
        else:
            lines.append(",".join(_format_value(v, precision) for v in np.asarray(entry, dtype=float).ravel()))
    with atomic_path(path) as tmp:
        tmp.write_text("".join(line + "\n" for line in lines), encoding="utf-8")


def parse_box(text: str) -> np.ndarray:
    """``x,y,w,h`` (commas or spaces) from the command line."""
    try:
        values = [float(v) for v in text.replace(",", " ").split()]
    except ValueError:
        values = []
    if len(values) != 4:
        raise InputError(f"--init must be four numbers x,y,w,h, got '{text}'")
    if not np.all(np.isfinite(values)):
        raise InputError(f"--init must be four finite numbers x,y,w,h, got '{text}'")
    return np.array(values)
