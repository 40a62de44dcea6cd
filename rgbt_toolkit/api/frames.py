"""Numpy frames as tracking inputs, and the per-frame record the public API hands back.

Frames from memory go through the same 8-bit conversion and RGB->T geometry as frames read from a sequence folder
(:mod:`rgbt_toolkit.jmmac.inputs`), so the two give the same boxes.
"""

from __future__ import annotations

import itertools
import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.jmmac.track_inputs import TrackInputs, map_box
from rgbt_toolkit.registration.calib import Calibration

FPS = 30.0  # frames from memory carry no timestamps; the rate only labels track.json's times


def is_path(value: Any) -> bool:
    return isinstance(value, (str, os.PathLike))


def as_calibration(calib: str | os.PathLike | Calibration | None) -> Calibration | None:
    """A :class:`Calibration` from a file written by ``rgbt register`` (or one already loaded)."""
    if calib is None or isinstance(calib, Calibration):
        return calib
    if not is_path(calib):
        raise InputError(f"calib: give a calibration file or a Calibration, not {type(calib).__name__}")
    from rgbt_toolkit.registration.calib import load_calibration

    return load_calibration(calib)


@dataclass
class FrameRecord:
    """One frame's result: both cameras' boxes, the tracker's mode and the evidence behind it."""

    index: int
    box_rgb: np.ndarray  # x, y, w, h in RGB pixels
    box_t: np.ndarray  # ... in thermal pixels
    mode: str  # "init", "appearance", "motion" or "skipped" (unreadable frame: the last box repeated)
    q: float  # MAX-PSR of the fused response (NaN where not computed)
    w_g: float  # MFNet's global weight of the RGB modality
    camera_motion: bool  # the trigger fired and CME moved the search region
    time: float  # seconds from the first frame
    timings: dict[str, float] = field(default_factory=dict)  # seconds per module
    present: bool | None = None  # False while the target counts as lost (re-acquisition module of `default`)

    @classmethod
    def of(cls, result, box_t: np.ndarray, time_s: float) -> "FrameRecord":
        """From a :class:`rgbt_toolkit.jmmac.FrameResult` and its box in the thermal camera."""
        return cls(int(result.index), np.asarray(result.box, dtype=float).copy(), np.asarray(box_t, dtype=float),
                   result.mode, float(result.q), float(result.w_g), bool(result.camera_motion), float(time_s),
                   dict(result.timings), getattr(result, "present", None))


def _frames(source: Any, what: str) -> Iterator[np.ndarray]:
    if isinstance(source, np.ndarray) and source.ndim < 3:
        raise InputError(f"{what}: one {source.ndim}-D array; give an iterable of frames (a list, or an N x H x W "
                         "array), or a video / folder path")
    try:
        return iter(source)
    except TypeError:
        raise InputError(f"{what}: expected a path or an iterable of numpy frames, got {type(source).__name__}") \
            from None


def _check_frame(frame: Any, what: str, index: int) -> np.ndarray:
    frame = np.asarray(frame) if frame is not None else frame
    if frame is None or frame.ndim not in (2, 3) or frame.ndim == 3 and frame.shape[2] not in (1, 3, 4) \
            or frame.size == 0:
        shape = None if frame is None else frame.shape
        raise InputError(f"{what} frame {index}: shape {shape}; frames are H x W (grey) or H x W x 3 (RGB)")
    return frame[:, :, 0] if frame.ndim == 3 and frame.shape[2] == 1 else frame


class FrameInputs(TrackInputs):
    """:class:`TrackInputs` over frames held in memory, plus :meth:`convert` for frames fed one at a time."""

    def convert(self, rgb: Any, thermal: Any, index: int) -> tuple[np.ndarray, np.ndarray]:
        """A later frame pair as the tracker takes it (8 bits, checked sizes)."""
        out = []
        for frame, what, size, to_8bit in (
                (rgb, "rgb", self.rgb_size, self._to_8bit[0]), (thermal, "thermal", self.t_size, self._to_8bit[1])):
            frame = _check_frame(frame, what, index)
            if frame.shape[1::-1] != size:
                raise InputError(f"{what} frame {index}: {frame.shape[1]}x{frame.shape[0]}, the first frame is "
                                 f"{size[0]}x{size[1]}")
            out.append(to_8bit(frame, f"{what} frame {index}"))
        return out[0], out[1]


def frame_inputs(rgb: Iterable, thermal: Iterable | None, *, init: np.ndarray | None = None,
                 init_modality: str = "rgb", h_rgb_to_t: np.ndarray | None = None,
                 calibration: Calibration | None = None, calib_name: Any = "calibration",
                 assume_aligned: bool = False) -> FrameInputs:
    """Two iterables of frames, paired one to one, as tracking inputs (first box: ``init``, else automatic).

    Frames in memory carry no recording to estimate a registration from: without ``h_rgb_to_t`` the caller must say
    ``assume_aligned`` (a resolution-only scaling), else a ``RegistrationError`` names the remedies.
    """
    from rgbt_toolkit.io.pixels import FixedRange
    from rgbt_toolkit.jmmac.autoinit import salient_warm_object
    from rgbt_toolkit.jmmac.track_inputs import check_input_box

    if thermal is None:
        raise InputError("rgb: frames from memory need their thermal partners; give thermal frames too")
    if init_modality not in ("rgb", "t"):
        raise InputError(f"init_modality must be 'rgb' or 't', got '{init_modality}'")
    rgb_frames, t_frames = _frames(rgb, "rgb"), _frames(thermal, "thermal")
    first = next(rgb_frames, None), next(t_frames, None)
    if first[0] is None or first[1] is None:
        raise InputError(f"{'rgb' if first[0] is None else 'thermal'}: no frames; the first pair starts the track")
    rgb0, t0 = _check_frame(first[0], "rgb", 0), _check_frame(first[1], "thermal", 0)
    size, t_size = rgb0.shape[1::-1], t0.shape[1::-1]
    notes = []
    if h_rgb_to_t is not None and assume_aligned:
        raise InputError("give either calib or assume_aligned=True, not both")
    if h_rgb_to_t is None:
        if not assume_aligned:
            raise RegistrationError("frames from memory: no RGB->T transform (no calibration given); pass calib= (a "
                                    "calibration from `rgbt register` or rgbt_toolkit.register), or "
                                    "assume_aligned=True if the views are registered already (only the resolution "
                                    "differs)")
        h_rgb_to_t = np.diag([t_size[0] / size[0], t_size[1] / size[1], 1.0])
    elif calibration is not None:
        from rgbt_toolkit.registration.calib import check_frame_sizes

        check_frame_sizes(calib_name, (calibration.rgb_size, calibration.thermal_size), size, t_size)
    h_rgb_to_t = np.asarray(h_rgb_to_t, dtype=float)
    to_8bit = FixedRange("rgb frames"), FixedRange("thermal frames")
    if init is not None:
        box = init if init_modality == "rgb" else map_box(np.linalg.inv(h_rgb_to_t), init)
        source = f"init ({init_modality})"
    else:
        box = map_box(np.linalg.inv(h_rgb_to_t), salient_warm_object(FixedRange("thermal frames")(t0)))
        source = "automatic (most salient warm object)"
    box = check_input_box(np.asarray(box, dtype=float), size, "rgb frames")
    inputs = FrameInputs("frames", iter(()), size, t_size, FPS, 0, h_rgb_to_t, box, source, notes,
                         {"rgb": "numpy frames", "t": "numpy frames"},
                         np.asarray(init, dtype=float) if init is not None and init_modality == "t" else None)
    inputs._to_8bit = to_8bit

    def pairs() -> Iterator[tuple[np.ndarray, np.ndarray, float]]:
        stream = zip(itertools.chain([first[0]], rgb_frames), itertools.chain([first[1]], t_frames))
        for index, (a, b) in enumerate(stream):
            yield (*inputs.convert(a, b, index), index / FPS)

    inputs.pairs = pairs()
    return inputs

