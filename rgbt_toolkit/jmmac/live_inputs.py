"""``rgbt track`` inputs from live sources: cameras, streams, named pipes, files still being written.

Such a source is read once, forward only (:mod:`rgbt_toolkit.io.live`): no frame count, no seeking, no second look
at the first frame. So the geometry must be known up front (a calibration, or ``--assume-aligned``): a registration
estimate needs frames spread over the whole recording. The first frame pair, taken from the stream once, gives the
frame sizes and (without ``--init``) the automatic target; it is then tracked like every later pair.
"""

from __future__ import annotations

import itertools
import os
import re
from pathlib import Path

import numpy as np

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.io.live import LivePairs, is_live, open_live
from rgbt_toolkit.jmmac.track_inputs import (
    TrackInputs, check_input_box, first_init_box, map_box, unregistered_message)


def _name(source: str) -> str:
    """A file-name-safe run name from a URL, device or pipe (``rtsp://cam/stream1`` -> ``stream1``)."""
    last = re.split(r"[/\\?#]", source.rstrip("/"))[-1] or "live"
    stem = Path(last).stem.removesuffix("_rgb").removesuffix("_visible") or last
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", stem) or "live"


def resolve_live_inputs(rgb: str | os.PathLike, thermal: str | os.PathLike | None, *,
                        init: np.ndarray | None = None, init_modality: str = "rgb",
                        h_rgb_to_t: np.ndarray | None = None, time_offset: float = 0.0, assume_aligned: bool = False,
                        realtime: bool = False) -> TrackInputs:
    """:class:`~rgbt_toolkit.jmmac.track_inputs.TrackInputs` reading two live sources (see the module docstring).

    With ``realtime`` regular files are followed while they grow (the run ends once no data came for
    :data:`~rgbt_toolkit.io.live.STALL_SECONDS`) and the tracker always gets the newest pair, older ones dropped and
    counted (``inputs.live.dropped``); without it, nothing is dropped.
    """
    from rgbt_toolkit.jmmac.autoinit import salient_warm_object

    rgb, thermal_text = os.fspath(rgb), None if thermal is None else os.fspath(thermal)
    if thermal_text is None:
        raise InputError(f"{rgb}: a live source needs its thermal partner too (give RGB and thermal sources)")
    for source in (rgb, thermal_text):
        if not is_live(source) and Path(source).is_dir():
            raise InputError(f"{source}: --realtime and live sources read videos, streams, cameras or pipes, "
                             "not frame folders")
    if not np.isfinite(time_offset):
        raise InputError(f"the thermal clock offset must be a finite number of seconds, got {-time_offset}")
    if h_rgb_to_t is not None and assume_aligned:
        raise InputError("give either a calibration (--calib) or --assume-aligned, not both")
    if h_rgb_to_t is None and not assume_aligned:
        raise RegistrationError(unregistered_message(
            rgb, thermal_text, "a live source is read once, so its registration cannot be estimated from frames "
            "spread over the recording"))
    sources = [open_live(s, follow=realtime and not is_live(s)) for s in (rgb, thermal_text)]
    pairs = LivePairs(*sources, offset=time_offset, realtime=realtime)
    try:
        stream = iter(pairs)
        first = next(stream, None)
        if first is None:
            why = "; ".join(pairs.notes) or "one of them ended first"
            raise InputError(f"{rgb} / {thermal_text}: no RGB and thermal frames arrived together ({why}); check "
                             "the sources and --offset")
        rgb_size, t_size = first[0].shape[1::-1], first[1].shape[1::-1]
        if assume_aligned:
            h_rgb_to_t = np.diag([t_size[0] / rgb_size[0], t_size[1] / rgb_size[1], 1.0])
        h_rgb_to_t = np.asarray(h_rgb_to_t, dtype=float)
        init_file = _init_file_beside(rgb)
        if init is not None:
            box = init if init_modality == "rgb" else map_box(np.linalg.inv(h_rgb_to_t), init)
            init_source = f"--init ({init_modality})"
        elif init_file is not None:
            box, init_source = first_init_box(init_file, rgb_size), str(init_file)
        else:
            box = map_box(np.linalg.inv(h_rgb_to_t), salient_warm_object(first[1]))
            init_source = "automatic (most salient warm object)"
        box = check_input_box(np.asarray(box, dtype=float), rgb_size, rgb)
    except BaseException:
        pairs.close()
        raise
    notes = ["live sources: read once, paired by their timestamps (nearest within half a thermal frame); "
             "both streams are taken to start together" + (f", thermal offset {-time_offset:+.3f} s" if time_offset
                                                            else "")]
    if assume_aligned:
        notes.append("--assume-aligned: the views are taken as registered, differing only in resolution")
    if realtime:
        notes.append("--realtime: when tracking falls behind, older frames are dropped (counted in track.json)")
    given_t = np.asarray(init, dtype=float) if init is not None and init_modality == "t" else None
    return TrackInputs(_name(rgb), itertools.chain([first], stream), rgb_size, t_size, sources[0].fps or 30.0, 0,
                       h_rgb_to_t, box, init_source, notes,
                       {"rgb": rgb, "t": thermal_text, "live": True, "realtime": realtime}, given_t, live=pairs)


def _init_file_beside(source: str) -> Path | None:
    """``<name>.init.txt`` beside a pipe or file (never for a URL or device)."""
    if is_live(source) and not Path(source).exists() or source.startswith("/dev/"):
        return None
    candidate = Path(source).with_name(Path(source).stem + ".init.txt")
    return candidate if candidate.is_file() else None
