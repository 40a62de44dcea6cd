"""Anti-UAV label and result files: per frame a flag (target there or not) and, where there is one, a box.

Anti-UAV scores whether a tracker knows the target is *absent* as well as where it is, so a frame is a flag plus a
box, not a box alone. Inside the toolkit a track is :class:`TargetFrames`: ``present`` (N,) bool and ``boxes``
(N, 4) float ``x, y, w, h`` (NaN rows where there is no box). Conversions happen only here, at the file edge:

* labels ``<seq>/IR_label.json`` (and ``RGB_label.json``): ``{"exist": [0/1 per frame], "gt_rect": [[x, y, w, h]
  per frame]}``; a frame's ``gt_rect`` may be ``[]`` or ``[0, 0, 0, 0]`` when there is no box (both occur in the
  official data) and is kept as a NaN row;
* results ``{"res": [[x, y, w, h] or [] per frame]}`` -- JSON, also inside a ``.txt`` file (the official baselines
  write JSON to ``<seq>_IR.txt``). ``[]`` and ``[0]`` mean "target absent" (the official ``not_exist``); a box of
  zero size is a box, not an absent mark, as the official scoring treats it;
* results as text rows: one line per frame, ``x,y,w,h`` (commas, spaces, tabs or semicolons, optionally inside
  ``[...]``); an empty line, ``[]``, ``0`` or ``nan`` means "target absent". Every line is a frame, so blank lines
  are *not* skipped here, unlike ``io.boxes``; a final newline does not add a frame.
"""

from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import atomic_path
from rgbt_toolkit.errors import FileFormatError, InputError
from rgbt_toolkit.io.boxes import read_text_file

_SEPARATORS = re.compile(r"[,;\t ]+")
ABSENT_HINT = "write [] for a frame where the target is absent"


@dataclass(frozen=True)
class TargetFrames:
    """One sequence of one modality: ``present[i]`` says the target is there (labels) or was reported (results)."""

    present: np.ndarray  # (N,) bool
    boxes: np.ndarray  # (N, 4) float x, y, w, h; NaN rows where there is no box

    def __len__(self) -> int:
        return len(self.present)


def _load_json(path: Path, text: str) -> object:
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise FileFormatError(f"{path}: malformed JSON ({exc.msg} at line {exc.lineno}, column {exc.colno})") from None


def _number(value: object) -> float | None:
    """``value`` as a float when it is a JSON number (``true`` and ``false`` are not), else ``None``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    return float(value)


def _box(entry: object, path: Path, frame: int) -> list[float] | None:
    """One frame's box: four finite numbers, or ``None`` for ``[]``, ``[0]`` and all-NaN (no box)."""
    if not isinstance(entry, list):
        raise FileFormatError(f"{path}, frame {frame}: expected [x, y, w, h] or [], got {json.dumps(entry)}")
    values = [_number(v) for v in entry]
    if any(v is None for v in values) or len(values) not in (0, 1, 4):
        raise FileFormatError(f"{path}, frame {frame}: expected [x, y, w, h] or [], got {json.dumps(entry)}")
    if not values or values == [0.0] or all(math.isnan(v) for v in values):
        return None
    if len(values) == 1:
        raise FileFormatError(f"{path}, frame {frame}: a single value {entry[0]} is neither a box nor the absent "
                              f"mark 0; {ABSENT_HINT}")
    if not all(math.isfinite(v) for v in values):
        raise FileFormatError(f"{path}, frame {frame}: box {json.dumps(entry)} is not four finite numbers")
    return values


def _frames(present: list[bool], boxes: list[list[float] | None]) -> TargetFrames:
    table = np.array([b if b is not None else [math.nan] * 4 for b in boxes], dtype=float).reshape(-1, 4)
    return TargetFrames(np.array(present, dtype=bool), table)


def read_anti_uav_label(path: str | os.PathLike) -> TargetFrames:
    """Read ``IR_label.json`` / ``RGB_label.json``: ``present`` from ``exist``, boxes from ``gt_rect``.

    A ``gt_rect`` of ``[]`` or ``[0, 0, 0, 0]`` becomes a NaN row (no box), whatever ``exist`` says; the scorer
    decides what such frames count for.

    Raises
    ------
    MissingFileError
        The file does not exist.
    FileFormatError
        Malformed JSON, missing keys, ``exist`` and ``gt_rect`` of different lengths, or a bad entry (the message
        names the file and the 1-based frame).
    """
    path = Path(path)
    data = _load_json(path, read_text_file(path, "label file"))
    if not (isinstance(data, dict) and isinstance(data.get("exist"), list) and isinstance(data.get("gt_rect"), list)):
        raise FileFormatError(f'{path}: an Anti-UAV label is {{"exist": [0/1 per frame], "gt_rect": [[x, y, w, h] '
                              f"per frame]}}")
    exist, rects = data["exist"], data["gt_rect"]
    if len(exist) != len(rects):
        raise FileFormatError(f"{path}: 'exist' has {len(exist)} frames but 'gt_rect' has {len(rects)}")
    flags = []
    for frame, flag in enumerate(exist, start=1):
        if not isinstance(flag, bool) and _number(flag) not in (0.0, 1.0):
            raise FileFormatError(f"{path}, frame {frame}: 'exist' must be 0 or 1, got {json.dumps(flag)}")
        flags.append(bool(flag))
    boxes = [_box(r, path, f) for f, r in enumerate(rects, start=1)]
    boxes = [None if b is not None and not any(b) else b for b in boxes]  # [0, 0, 0, 0]: no box
    return _frames(flags, boxes)


def read_anti_uav_result(path: str | os.PathLike) -> TargetFrames:
    """Read a tracker's Anti-UAV result: ``{"res": [...]}`` JSON (any extension) or one text row per frame.

    Raises
    ------
    MissingFileError
        The file does not exist.
    FileFormatError
        Malformed JSON, no ``res`` list, or a malformed frame (named by file and 1-based frame / line).
    """
    path = Path(path)
    text = read_text_file(path, "result file")
    if text.lstrip().startswith("{"):
        data = _load_json(path, text)
        if not isinstance(data, dict) or not isinstance(data.get("res"), list):
            raise FileFormatError(f'{path}: an Anti-UAV JSON result is {{"res": [[x, y, w, h] or [] per frame]}}')
        boxes = [_box(entry, path, frame) for frame, entry in enumerate(data["res"], start=1)]
    else:
        boxes = [_text_row(line, path, number) for number, line in enumerate(text.splitlines(), start=1)]
    return _frames([b is not None for b in boxes], boxes)


def _text_row(line: str, path: Path, number: int) -> list[float] | None:
    body = line.strip()
    if body.startswith("[") and body.endswith("]"):
        body = body[1:-1]
    tokens = [t for t in _SEPARATORS.split(body.strip()) if t]
    try:
        values = [float(t) for t in tokens]
    except ValueError:
        raise FileFormatError(f"{path}, line {number}: '{line.strip()}' is not x,y,w,h or an empty line "
                              f"(target absent)") from None
    if len(values) not in (0, 1, 4):
        raise FileFormatError(f"{path}, line {number}: expected 4 values x,y,w,h or an empty line (target absent), "
                              f"got {len(values)}")
    return _box(values, path, number)


def write_anti_uav_result(
    path: str | os.PathLike, boxes: np.ndarray, present: np.ndarray | None = None, decimals: int = 4
) -> None:
    """Write a track as an Anti-UAV result ``{"res": [[x, y, w, h] or [] per frame]}``, atomically.

    The file is JSON whatever its extension: the official submissions are JSON in ``<seq>_IR.txt``.

    Parameters
    ----------
    boxes : (N, 4) array
        ``x, y, w, h`` per frame; NaN rows are frames without a box.
    present : (N,) bool array, optional
        Whether the tracker reports the target in each frame; ``False`` frames are written ``[]`` (target absent)
        whatever their box. Default: present where the box is not NaN.
    decimals : int
        Values are rounded to this many decimals.

    Raises
    ------
    InputError
        ``boxes`` is not (N, 4), ``present`` has another length, or a present frame has no finite box.
    """
    b = np.asarray(boxes, dtype=float)
    if b.ndim != 2 or b.shape[1] != 4:
        raise InputError(f"boxes must be an (N, 4) array of x, y, w, h; got shape {b.shape}")
    flags = ~np.isnan(b).any(axis=1) if present is None else np.asarray(present, dtype=bool).ravel()
    if len(flags) != len(b):
        raise InputError(f"present has {len(flags)} flags for {len(b)} boxes; give one per frame")
    bad = flags & ~np.isfinite(b).all(axis=1)
    if bad.any():
        raise InputError(f"frame {int(np.flatnonzero(bad)[0]) + 1} is marked present but its box is not finite; "
                         f"mark it absent or give a box")
    res = [[round(float(v), decimals) for v in row] if on else [] for row, on in zip(b.tolist(), flags)]
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({"res": res}) + "\n", encoding="utf-8")
