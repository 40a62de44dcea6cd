"""The calibration of an RGB-thermal rig as a small JSON file.

Example::

    {"format": "rgbt-calibration", "version": 1, "model": "homography",
     "rgb_to_thermal": [[1.02, 0.01, -12.3], [-0.01, 1.02, 4.1], [0.0, 0.0, 1.0]],
     "rgb_size": [640, 480], "thermal_size": [640, 512], "time_offset_s": 0.12,
     "quality": 0.41, "peak_ratio": 2.3, "overlap": 0.93, "pairs_used": 6, "offset_correlation": 0.78}

``rgb_to_thermal`` maps RGB pixel coordinates to thermal pixel coordinates (pixel centres at integers);
``time_offset_s`` is added to RGB timestamps to get thermal ones. ``source`` says what the transform was fitted to
("images": the frames themselves, "points": hand-picked correspondences, "boxes": a target's boxes in both cameras,
"board": a heated calibration board) and, for the fitted sources, ``residuals`` holds the fit's thermal-pixel
residuals (``rms``, ``max``, ``per_point``, and the 0-based indices of the ``outliers`` left out of the fit). Files
without these keys (written before they existed) load as source "images" without residuals.
"""

from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import write_text_atomic
from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.registration.transforms import MODELS, normalize

FORMAT = "rgbt-calibration"
VERSION = 1
SOURCES = ("images", "points", "boxes", "board")


@dataclass(frozen=True)
class Calibration:
    """Spatial and temporal relation between the RGB and thermal cameras of one rig."""

    matrix: np.ndarray  # 3x3, RGB pixels -> thermal pixels
    model: str
    rgb_size: tuple[int, int]  # (width, height)
    thermal_size: tuple[int, int]
    time_offset: float = 0.0  # seconds; t_thermal = t_rgb + time_offset
    quality: float = float("nan")
    peak_ratio: float = float("nan")
    overlap: float = float("nan")
    pairs_used: int = 0
    offset_correlation: float | None = None  # None when the offset was not estimated (--sync not given)
    source: str = "images"  # what the transform was fitted to, one of SOURCES
    residuals: tuple[float, ...] = ()  # per correspondence, thermal pixels (points, box frames, board corners)
    outliers: tuple[int, ...] = ()  # indices into ``residuals`` left out of the fit
    # points and boxes: the fit's residual scale and acceptance, why its model, and its bootstrap uncertainty at
    # the thermal frame's centre and corners (see registration.weigh); None for other sources
    evidence: dict | None = None

    @property
    def residual_rms(self) -> float:
        """RMS residual of the correspondences the fit kept, thermal pixels (NaN without residuals)."""
        kept = self._kept()
        return float(np.sqrt(np.mean(kept ** 2))) if len(kept) else float("nan")

    @property
    def residual_max(self) -> float:
        """Largest residual of the correspondences the fit kept, thermal pixels (NaN without residuals)."""
        kept = self._kept()
        return float(kept.max()) if len(kept) else float("nan")

    def _kept(self) -> np.ndarray:
        values = np.asarray(self.residuals, dtype=float)
        keep = np.ones(len(values), bool)
        keep[list(self.outliers)] = False
        return values[keep]

    @property
    def inverse(self) -> np.ndarray:
        """Thermal pixels -> RGB pixels."""
        return normalize(np.linalg.inv(self.matrix))

    def save(self, path: str | os.PathLike) -> None:
        """Write this calibration as the JSON file ``rgbt register`` writes (atomically)."""
        save_calibration(path, self)

    def to_dict(self) -> dict:
        return {
            "format": FORMAT,
            "version": VERSION,
            "model": self.model,
            "rgb_to_thermal": [[round(float(v), 10) for v in row] for row in normalize(self.matrix)],
            "rgb_size": [int(v) for v in self.rgb_size],
            "thermal_size": [int(v) for v in self.thermal_size],
            "time_offset_s": float(self.time_offset),
            "quality": _finite_or_none(self.quality),
            "peak_ratio": _finite_or_none(self.peak_ratio),
            "overlap": _finite_or_none(self.overlap),
            "pairs_used": int(self.pairs_used),
            "offset_correlation": None if self.offset_correlation is None else float(self.offset_correlation),
            "source": self.source,
            "residuals": None if not self.residuals else {
                "units": "thermal px",
                "rms": round(self.residual_rms, 4), "max": round(self.residual_max, 4),
                "per_point": [round(float(v), 4) for v in self.residuals],
                "outliers": [int(i) for i in self.outliers],
            },
            **({"evidence": self.evidence} if self.evidence is not None else {}),
        }


def check_frame_sizes(source: str | os.PathLike, made_for: tuple, rgb_size: tuple[int, int],
                      thermal_size: tuple[int, int], names: tuple[str, str] = ("the RGB input", "the thermal input"),
                      ) -> None:
    """Raise InputError unless the frames are the sizes ``made_for`` = (RGB (w, h), thermal (w, h)) a calibration
    was made for: its matrix is in pixels, and on frames of another resolution it maps everything to the wrong place,
    silently. ``names`` name the two frames in the message (e.g. their files)."""
    (rw, rh), (tw, th) = (tuple(int(v) for v in size) for size in made_for)
    if (tuple(rgb_size), tuple(thermal_size)) != ((rw, rh), (tw, th)):
        raise InputError(f"{source}: calibration made for RGB {rw}x{rh} and thermal {tw}x{th}, but {names[0]} is "
                         f"{rgb_size[0]}x{rgb_size[1]} and {names[1]} is {thermal_size[0]}x{thermal_size[1]}; "
                         "calibrate this camera pair with `rgbt register`")


def _finite_or_none(value: float):
    return float(value) if value is not None and np.isfinite(value) else None


def save_calibration(path: str | os.PathLike, calibration: Calibration) -> None:
    """Write ``calibration`` as JSON, atomically."""
    text = json.dumps(calibration.to_dict(), indent=2)
    # one line per matrix row and size: readable, and diffs show which entry changed
    text = re.sub(r"\[\s+([^\[\]]+?)\s+\]", lambda m: "[" + " ".join(m.group(1).split()) + "]", text)
    write_text_atomic(path, text + "\n")


MAX_OFFSET_S = 3600.0  # a clock offset of more than an hour is a corrupt file, not a rig


def _is_number(value) -> bool:
    """A JSON number (JSON true/false load as Python bools, which are ints: not numbers here)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _size(data: dict, key: str, path: Path) -> tuple[int, int]:
    value = data.get(key)
    if not (isinstance(value, list) and len(value) == 2
            and all(isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in value)):
        raise FileFormatError(f"{path}: '{key}' must be [width, height] with positive integers, got {value!r}")
    return int(value[0]), int(value[1])


def _optional_number(data: dict, key: str, path: Path) -> float:
    """A finite number, or NaN for null / a missing key."""
    value = data.get(key)
    if value is None:
        return float("nan")
    if not _is_number(value) or not np.isfinite(value):
        raise FileFormatError(f"{path}: '{key}' must be a finite number or null, got {value!r}")
    return float(value)


def load_calibration(path: str | os.PathLike) -> Calibration:
    """Read a calibration written by :func:`save_calibration`; errors name the file and the bad field."""
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such calibration file")
    try:
        data = json.loads(path.read_text(encoding="utf-8-sig"))  # a BOM from Windows editors is harmless
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        line = getattr(exc, "lineno", None)
        where = f" line {line}" if line else ""
        raise FileFormatError(f"{path}:{where} not valid JSON; write it with 'rgbt register'") from None
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise FileFormatError(f"{path}: not an rgbt calibration (missing \"format\": \"{FORMAT}\")")
    if data.get("version") != VERSION:
        raise FileFormatError(
            f"{path}: calibration version {data.get('version')!r} is not supported (expected {VERSION})"
        )
    rows = data.get("rgb_to_thermal")
    if not (isinstance(rows, list) and len(rows) == 3
            and all(isinstance(r, list) and len(r) == 3 and all(map(_is_number, r)) for r in rows)):
        raise FileFormatError(f"{path}: 'rgb_to_thermal' must be a 3x3 list of numbers")
    matrix = np.array(rows, dtype=float)
    if matrix.shape != (3, 3) or not np.isfinite(matrix).all() or abs(np.linalg.det(matrix)) < 1e-12:
        raise FileFormatError(f"{path}: 'rgb_to_thermal' must be an invertible 3x3 matrix")
    model = data.get("model")
    if model not in MODELS:
        raise FileFormatError(f"{path}: 'model' must be one of {', '.join(MODELS)}, got {model!r}")
    offset = data.get("time_offset_s", 0.0)
    if not _is_number(offset) or not np.isfinite(offset) or abs(offset) > MAX_OFFSET_S:
        raise FileFormatError(
            f"{path}: 'time_offset_s' must be a number of seconds within ±{MAX_OFFSET_S:g}, got {offset!r}"
        )
    pairs = data.get("pairs_used", 0)
    if not (isinstance(pairs, int) and not isinstance(pairs, bool) and pairs >= 0):
        raise FileFormatError(f"{path}: 'pairs_used' must be a whole number >= 0, got {pairs!r}")
    corr = _optional_number(data, "offset_correlation", path)
    source = data.get("source", "images")
    if source not in SOURCES:
        raise FileFormatError(f"{path}: 'source' must be one of {', '.join(SOURCES)}, got {source!r}")
    residuals, outliers = _residuals(data.get("residuals"), path)
    evidence = _evidence(data.get("evidence"), path)
    return Calibration(
        matrix=normalize(matrix), model=model, rgb_size=_size(data, "rgb_size", path),
        thermal_size=_size(data, "thermal_size", path), time_offset=float(offset),
        quality=_optional_number(data, "quality", path), peak_ratio=_optional_number(data, "peak_ratio", path),
        overlap=_optional_number(data, "overlap", path), pairs_used=pairs,
        offset_correlation=None if np.isnan(corr) else corr, source=source, residuals=residuals, outliers=outliers,
        evidence=evidence,
    )


def _residuals(value, path: Path) -> tuple[tuple[float, ...], tuple[int, ...]]:
    """The per-point residuals and outlier indices of a ``residuals`` entry (absent or null: none)."""
    if value is None:
        return (), ()
    per_point = value.get("per_point") if isinstance(value, dict) else None
    outliers = value.get("outliers", []) if isinstance(value, dict) else None
    if not (isinstance(per_point, list) and all(_is_number(v) and np.isfinite(v) and v >= 0 for v in per_point)):
        raise FileFormatError(f"{path}: 'residuals' must hold 'per_point', a list of distances >= 0")
    if not (isinstance(outliers, list) and all(isinstance(i, int) and not isinstance(i, bool)
                                               and 0 <= i < len(per_point) for i in outliers)):
        raise FileFormatError(f"{path}: 'residuals.outliers' must list indices into 'per_point'")
    return tuple(float(v) for v in per_point), tuple(int(i) for i in outliers)


def _evidence(value, path: Path) -> dict | None:
    """The ``evidence`` entry (absent or null: None); its ``uncertainty`` figures must be distances or null."""
    if value is None:
        return None
    uncertainty = value.get("uncertainty", {}) if isinstance(value, dict) else None
    if not isinstance(uncertainty, dict) or not all(
            v is None or (_is_number(v) and np.isfinite(v) and v >= 0)
            for k, v in uncertainty.items() if k not in ("units", "method")):
        raise FileFormatError(f"{path}: 'evidence.uncertainty' must map places to distances in thermal px")
    return value
