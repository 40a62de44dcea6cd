"""Tracking from Python: :func:`track` for a whole recording, :class:`Tracker` for a live loop.

Both build the tracker with :func:`tracker_from_options` (the one way, shared with ``rgbt track``) and feed it
through the same frame loop (:func:`rgbt_toolkit.jmmac.run.run_tracking`) or the same per-frame step, so a recording
tracked here, streamed frame by frame, or tracked on the command line gives the same boxes.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import weakref
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Union

import numpy as np

from rgbt_toolkit.api.frames import FrameRecord, as_calibration, frame_inputs, is_path
from rgbt_toolkit.errors import InputError, MissingFileError
from rgbt_toolkit.registration.calib import Calibration

Source = Union[str, os.PathLike, Iterable[np.ndarray]]  # video, frame folder, sequence folder, or numpy frames
# the files of `rgbt track`, keyed as run_tracking reports them
RESULT_FILES = {"boxes_rgb": "boxes_rgb.txt", "boxes_t": "boxes_t.txt", "track": "track.json", "video": "annotated.mp4"}


def tracker_from_options(preset: str = "default", *, features: str = "hc", motion_model: str = "affine",
                         mfnet_weights: str | os.PathLike | None = None, detector: str | os.PathLike | None = None,
                         parallel_trackers: bool = True):
    """The JMMAC tracker that ``rgbt track --preset ... --features ... --motion-model ...`` runs.

    Parameters
    ----------
    preset : str
        ``default``, ``full`` or an ablation variant (see :data:`rgbt_toolkit.jmmac.config.PRESETS`).
    features : {'hc', 'hc+cnn', 'deep'}
        ECO features: hand-crafted (fast), hand-crafted plus the backbone's first layer, or deep.
    motion_model : {'translation', 'similarity', 'affine', 'projective'}
        Camera-motion transform estimated on the thermal stream.
    mfnet_weights, detector : path, optional
        MFNet head weights (default: the shipped tracking heads); an ONNX detector, which switches box refinement on.
    parallel_trackers : bool
        Run the RGB and the thermal ECO tracker on two threads (see :func:`rgbt_toolkit.runtime.split_tracker_threads`).

    Returns
    -------
    rgbt_toolkit.jmmac.JmmacTracker
    """
    from rgbt_toolkit.jmmac import api as jmmac_api  # looked up at call time: tests replace build_tracker there
    from rgbt_toolkit.jmmac.config import preset as named_preset

    for name, value in (("mfnet_weights", mfnet_weights), ("detector", detector)):
        if value is not None and not Path(value).is_file():
            raise MissingFileError(f"{value}: {name} file not found")
    refine = {"refine": True} if detector else {}  # a detector is what makes box refinement pay off
    config = named_preset(preset, eco_preset=features, motion_model=motion_model, parallel_trackers=parallel_trackers,
                          **refine)
    return jmmac_api.build_tracker(config, mfnet_weights=mfnet_weights, detector=detector)


def open_inputs(rgb: Source, thermal: Source | None = None, *, init: Any = None, init_modality: str = "rgb",
                calib: str | os.PathLike | Calibration | None = None, calib_name: str | os.PathLike | None = None,
                offset: float | None = None, assume_aligned: bool = False, realtime: bool = False,
                masks: tuple[np.ndarray | None, np.ndarray | None] = (None, None)):
    """Resolve what to track, as ``rgbt track`` does: pairing, the RGB->T transform and the first box.

    Live sources (``rtsp://``/``udp://``... URLs, ``/dev/video*``, named pipes), and every path with ``realtime``,
    are read once by background threads (:mod:`rgbt_toolkit.io.live`); they need ``calib`` or ``assume_aligned``.

    Without ``calib`` the transform is estimated from the frames (paths), or, with ``assume_aligned``, a
    resolution-only scaling (views registered already); when neither works a ``RegistrationError`` says what to give.

    Paths go through :func:`rgbt_toolkit.jmmac.inputs.resolve_inputs` (with the calibration's size check and, when
    there is no calibration, a registration estimate); numpy frames are paired one to one. ``calib_name`` names a
    calibration given loaded, in error messages (default: its path, or "calibration"). ``masks`` (RGB, thermal;
    non-zero = leave out) are left out of the registration estimate, beside the overlays it finds itself.
    """
    from rgbt_toolkit.features.colornames import build_table_in_background
    from rgbt_toolkit.jmmac import api as jmmac_api
    from rgbt_toolkit.jmmac.inputs import resolve_inputs
    from rgbt_toolkit.registration.calib import check_frame_sizes

    build_table_in_background()  # the trackers' first frame needs it; a core is idle while the inputs open
    calibration = as_calibration(calib)
    calib_name = calib_name if calib_name is not None else (calib if is_path(calib) else "calibration")
    h = None if calibration is None else np.asarray(calibration.matrix, dtype=float)
    box = None if init is None else _as_box(init)
    if not is_path(rgb) or (thermal is not None and not is_path(thermal)):
        if realtime:
            raise InputError("realtime: frames from memory are not a live source; give paths, URLs or devices")
        if offset is not None:
            raise InputError("offset: frames from memory are paired one to one; pair them in time before passing "
                             "them")
        return frame_inputs(rgb, thermal, init=box, init_modality=init_modality, h_rgb_to_t=h,
                            calibration=calibration, calib_name=calib_name, assume_aligned=assume_aligned)
    calib_offset = 0.0 if calibration is None else -float(calibration.time_offset)
    estimate = None if (h is not None or thermal is None or assume_aligned) else jmmac_api.registration_estimator(masks)
    inputs = resolve_inputs(rgb, thermal, init=box, init_modality=init_modality, h_rgb_to_t=h,
                            time_offset=calib_offset if offset is None else -offset, estimate_registration=estimate,
                            assume_aligned=assume_aligned, realtime=realtime)
    if calibration is not None:
        sizes = (tuple(calibration.rgb_size), tuple(calibration.thermal_size))
        try:
            check_frame_sizes(calib_name, sizes, inputs.rgb_size, inputs.t_size,
                              **({"names": (str(rgb), str(thermal))} if thermal is not None else {}))
        except BaseException:
            if inputs.live is not None:  # stop the readers of live sources before reporting
                inputs.live.close()
            raise
    return inputs


def _as_box(box: Any) -> np.ndarray:
    """An ``x, y, w, h`` box from a string ``"x,y,w,h"`` or four numbers."""
    from rgbt_toolkit.io.boxes import parse_box

    if isinstance(box, str):
        return parse_box(box)
    values = np.asarray(box, dtype=float).ravel()
    if values.size != 4:
        raise InputError(f"init: a box is 4 numbers x, y, w, h; got {values.size}")
    return values


@dataclass
class TrackResult:
    """One tracking run held in memory; :meth:`save` writes the files ``rgbt track`` writes."""

    name: str
    boxes_rgb: np.ndarray  # (N, 4) x, y, w, h in RGB pixels
    boxes_t: np.ndarray  # (N, 4) in thermal pixels
    frames: list[FrameRecord]
    summary: dict
    notes: list[str] = field(default_factory=list)
    _files: Path | None = field(default=None, repr=False)  # the run's files, removed with this object

    def save(self, outdir: str | os.PathLike, *, force: bool = False) -> dict[str, Path]:
        """Write ``boxes_rgb.txt``, ``boxes_t.txt``, ``track.json`` (and ``annotated.mp4`` if made) into ``outdir``.

        An earlier run's results there are refused unless ``force`` (never overwritten silently).
        """
        from rgbt_toolkit._atomic import check_folder

        check_folder(outdir, "results")
        out = Path(outdir)
        earlier = [name for name in RESULT_FILES.values() if (out / name).exists()]
        if earlier and not force:
            raise InputError(f"{outdir}: holds results of an earlier run ({', '.join(earlier)}); "
                             "choose another folder or pass force=True")
        out.mkdir(parents=True, exist_ok=True)
        written = {}
        for key, name in RESULT_FILES.items():
            source = self._files / name
            if source.exists():
                shutil.copyfile(source, out / f".{name}.partial")
                os.replace(out / f".{name}.partial", out / name)
                written[key] = out / name
            elif (out / name).exists():  # forced: do not leave the earlier run's video beside these boxes
                (out / name).unlink()
        return written


def track(rgb: Source, thermal: Source | None = None, *, init: Any = None,
          calib: str | os.PathLike | Calibration | None = None, preset: str = "default", init_modality: str = "rgb",
          offset: float | None = None, max_frames: int | None = None, features: str = "hc",
          motion_model: str = "affine", mfnet_weights: str | os.PathLike | None = None,
          detector: str | os.PathLike | None = None, video: bool = False, show_weights: bool = False,
          progress: Callable[[int], None] | None = None, assume_aligned: bool = False,
          realtime: bool = False) -> TrackResult:
    """Track one target through paired RGB and thermal recordings (what ``rgbt track`` does, in memory).

    Parameters
    ----------
    rgb, thermal : path or iterable of numpy frames
        Two videos or frame folders, one benchmark sequence folder (``thermal`` omitted), or two iterables of
        frames (H x W grey or H x W x 3 RGB, any dtype ``rgbt track`` reads), paired one to one.
    init : str or 4 numbers, optional
        First box ``x, y, w, h`` in the pixels of ``init_modality`` (default: the sequence's ``init.txt``, a
        ``<video stem>.init.txt`` file, else the most salient warm object).
    calib : path or Calibration, optional
        RGB->T calibration (``rgbt register``); default: estimated from the recordings (paths; numpy frames need
        ``calib`` or ``assume_aligned``). An estimate that fails raises ``RegistrationError``.
    assume_aligned : bool
        The views are registered already and differ only in resolution (``rgbt track --assume-aligned``).
    preset, features, motion_model, mfnet_weights, detector :
        As :func:`tracker_from_options`.
    offset : float, optional
        Thermal clock offset in seconds (t_thermal = t_rgb + offset), paths only.
    realtime : bool
        Read the sources once as live feeds (files followed while they grow) and, when tracking falls behind,
        track only the newest frame pair; ``summary["dropped_frames"]`` counts the others (``rgbt track
        --realtime``). Live sources (URLs, ``/dev/video*``, named pipes) are read once either way.
    max_frames : int, optional
        Stop after this many frames.
    video, show_weights : bool
        Also make ``annotated.mp4`` (with the W_F overlay) for :meth:`TrackResult.save`.
    progress : callable, optional
        Called with 1 per frame.

    Returns
    -------
    TrackResult
        ``boxes_rgb``, ``boxes_t``, per-frame ``frames`` records, the run ``summary``; ``save(outdir)``.
    """
    from rgbt_toolkit.jmmac.run import run_tracking

    if show_weights and not video:
        raise InputError("show_weights draws on annotated.mp4; it needs video=True")
    if max_frames is not None and max_frames < 1:
        raise InputError(f"max_frames must be at least 1, got {max_frames}")
    from rgbt_toolkit.io.live import is_live

    from rgbt_toolkit.runtime import split_tracker_threads

    def make_tracker():  # two tracker threads only when cores are left beside run_tracking's reader and writer
        return tracker_from_options(preset, features=features, motion_model=motion_model,
                                    mfnet_weights=mfnet_weights, detector=detector,
                                    parallel_trackers=split_tracker_threads(io_threads=True)[1])

    # a live source plays on while the tracker loads its models: load them before opening it
    live = realtime or any(is_path(s) and is_live(s) for s in (rgb, thermal) if s is not None)
    tracker = make_tracker() if live else None
    inputs = open_inputs(rgb, thermal, init=init, init_modality=init_modality, calib=calib, offset=offset,
                         assume_aligned=assume_aligned, realtime=realtime)
    tracker = tracker if tracker is not None else make_tracker()
    records: list[FrameRecord] = []

    def keep(result, box_t: np.ndarray, time_s: float) -> None:
        records.append(FrameRecord.of(result, box_t, time_s))

    files = Path(tempfile.mkdtemp(prefix="rgbt_track_"))
    try:
        summary = run_tracking(inputs, tracker, files, video=video, show_weights=show_weights, progress=progress,
                               max_frames=max_frames, on_result=keep, plot=False)  # save() copies no picture
    except BaseException:
        shutil.rmtree(files, ignore_errors=True)
        raise
    if summary["interrupted"]:  # the caller's Ctrl-C: its outputs are complete up to here, but the caller stops
        shutil.rmtree(files, ignore_errors=True)
        raise KeyboardInterrupt
    summary.pop("outputs", None)  # temporary paths; save() writes the real ones
    result = TrackResult(inputs.name, _stack([r.box_rgb for r in records]), _stack([r.box_t for r in records]),
                         records, summary, list(inputs.notes), files)
    weakref.finalize(result, shutil.rmtree, files, True)
    return result


def _stack(boxes: list[np.ndarray]) -> np.ndarray:
    return np.asarray(boxes, dtype=float).reshape(-1, 4)


class Tracker:
    """Streaming JMMAC for a live loop: one object per target, no global state.

    Parameters
    ----------
    preset : str
        As :func:`tracker_from_options`, like ``features``, ``motion_model``, ``mfnet_weights`` and ``detector``.
    calib : path or Calibration, optional
        RGB->T calibration (``rgbt register``); without one, ``assume_aligned=True`` must say the views are
        registered already (only the resolution differs), else ``initialize`` raises ``RegistrationError``.

    Examples
    --------
    >>> tracker = Tracker()                                         # doctest: +SKIP
    >>> first = tracker.initialize(rgb0, t0, (10, 20, 30, 40))      # doctest: +SKIP
    >>> for rgb, t in camera: print(tracker.track(rgb, t).box_rgb)  # doctest: +SKIP
    """

    def __init__(self, preset: str = "default", calib: str | os.PathLike | Calibration | None = None, *,
                 features: str = "hc", motion_model: str = "affine",
                 mfnet_weights: str | os.PathLike | None = None, detector: str | os.PathLike | None = None,
                 assume_aligned: bool = False):
        self._assume_aligned = assume_aligned
        self._calib_name = calib if is_path(calib) else "calibration"
        self._calibration = as_calibration(calib)  # a bad file fails here, not at the first frame
        self._tracker = tracker_from_options(preset, features=features, motion_model=motion_model,
                                             mfnet_weights=mfnet_weights, detector=detector)
        self._inputs = None
        self._frames: Iterator | None = None
        self._index = -1

    def initialize(self, rgb: np.ndarray, thermal: np.ndarray, box: Any) -> FrameRecord:
        """Start on the first frame pair (a later call starts over, on a new target).

        Parameters
        ----------
        rgb, thermal : ndarray
            H x W grey or H x W x 3 RGB frames; later frames must keep these sizes.
        box : str or 4 numbers
            The target's ``x, y, w, h`` in RGB pixels.

        Returns
        -------
        FrameRecord
            Mode ``"init"``, the box in both cameras.
        """
        self._inputs = frame_inputs([rgb], [thermal], init=_as_box(box),
                                    h_rgb_to_t=None if self._calibration is None else self._calibration.matrix,
                                    calibration=self._calibration, calib_name=self._calib_name,
                                    assume_aligned=self._assume_aligned)
        self._convert = self._inputs.convert
        rgb8, t8, _ = next(self._inputs.pairs)
        result = self._tracker.initialize(rgb8, self._inputs.thermal_in_rgb(t8), self._inputs.init_box)
        self._index = 0
        return FrameRecord.of(result, self._inputs.box_in_t(result.box), 0.0)

    def track(self, rgb: np.ndarray, thermal: np.ndarray) -> FrameRecord:
        """Follow the target into the next frame pair.

        Returns
        -------
        FrameRecord
            ``box_rgb``, ``box_t``, ``mode`` (appearance or motion), ``q``, ``present``, ``w_g``, timings.
        """
        if self._inputs is None:
            raise InputError("Tracker.track called before initialize; give the first frame pair and box there")
        self._index += 1
        rgb8, t8 = self._convert(rgb, thermal, self._index)
        result = self._tracker.track(rgb8, self._inputs.thermal_in_rgb(t8))
        return FrameRecord.of(result, self._inputs.box_in_t(result.box), self._index / self._inputs.fps)
