"""Pictures of one tracking run: where the box went and, frame by frame, why (``track.png``, ``track-single --plot``).

A user looks at these before reading ``track.json``: the centre path over a faint first frame, and beside it the
per-frame signals (MAX-PSR q, appearance/motion mode, w_G, the camera-motion flag; or ECO's peak and PSR) with the
frames that were not plain appearance tracking shaded. Drawn only from the per-frame records the run writes, so a
picture can be re-made from ``track.json`` alone. Drawn with OpenCV (``raster_chart``; no matplotlib: importing and
laying it out cost 0.45 s at the end of every ``rgbt track``); PNGs are written atomically.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence

import numpy as np

from rgbt_toolkit.raster_chart import COLOURS, Axes, Canvas, padded_limits

# what track.png reads of each track.json record
TRACK_FIELDS = ("frame", "box_rgb", "mode", "present", "q", "w_g", "camera_motion")
MODE_COLOURS = {"init": COLOURS["tab:blue"], "appearance": COLOURS["tab:green"], "motion": COLOURS["tab:orange"],
                "skipped": COLOURS["grey"]}
_CAMERA = COLOURS["tab:red"]
_ABSENT = COLOURS["tab:red"]
_OTHER = (77, 77, 77)  # a mode without its own colour
WIDTH = 1200  # pixels; 12 x 5.5 in at 100 dpi, as the matplotlib pictures were


def plot_track(records: Sequence[dict], path: str | os.PathLike, *, background: np.ndarray | None = None,
               title: str = "", background_scale: float = 1.0) -> None:
    """Draw ``track.png`` from ``track.json``'s per-frame records (``frame``, ``box_rgb``, ``mode``, ``q``, ...).

    ``background`` (the first RGB frame, possibly shrunk by ``background_scale``) is shown faintly under the centre
    path so the path has a place.
    """
    frames = np.array([r["frame"] for r in records], dtype=float)
    centres = _centres([r["box_rgb"] for r in records])
    modes = [r["mode"] for r in records]
    canvas, path_rect, (q_rect, mode_rect, wg_rect, cm_rect) = _layout([1.5, 0.45, 1.0, 0.45], 550,
                                                                        title or "rgbt track")
    path_ax = _centre_path(canvas, path_rect, centres, [MODE_COLOURS.get(m, _OTHER) for m in modes], background,
                           "RGB ", background_scale)
    path_ax.legend([(mode, MODE_COLOURS[mode], "dot") for mode in ("appearance", "motion", "skipped")], title="mode")
    xlim = padded_limits(frames)

    motion = np.array([m == "motion" for m in modes])
    lost = np.array([r.get("present", True) is False for r in records])  # re-acquisition: the target counted as lost
    q = _floats(r.get("q") for r in records)
    q_ax = Axes(canvas, q_rect, xlim, padded_limits(q))
    _shade(q_ax, frames, motion, MODE_COLOURS["motion"])
    _shade(q_ax, frames, lost, _ABSENT)
    q_ax.line(frames, q, COLOURS["black"])
    q_ax.frame(ylabel="MAX-PSR q", xtick_labels=False)
    q_ax.legend(([("motion mode", MODE_COLOURS["motion"], "shade")] if motion.any() else [])
                + ([("target judged absent", _ABSENT, "shade")] if lost.any() else []))

    mode_ax = Axes(canvas, mode_rect, xlim, (0, 1))
    for mode in ("appearance", "motion", "skipped", "init"):
        _shade(mode_ax, frames, np.array([m == mode for m in modes]), MODE_COLOURS[mode], alpha=0.85)
    mode_ax.frame(ylabel="mode", yticks=[], xtick_labels=False)

    wg_ax = Axes(canvas, wg_rect, xlim, (-0.02, 1.02))
    _shade(wg_ax, frames, motion, MODE_COLOURS["motion"])
    wg_ax.line(frames, _floats(r.get("w_g") for r in records), COLOURS["tab:purple"])
    wg_ax.frame(ylabel="w_G (RGB)", yticks=[0.0, 0.5, 1.0], xtick_labels=False)

    camera = np.array([bool(r.get("camera_motion")) for r in records])
    cm_ax = Axes(canvas, cm_rect, xlim, (0, 1.05))
    _shade(cm_ax, frames, camera, _CAMERA, alpha=0.6, y=(0, 1))
    cm_ax.frame(ylabel="camera\nmotion", yticks=[0, 1], ytick_labels=["no", "yes"], xlabel="frame index")
    canvas.save(path)


def plot_track_json(track_json: str | os.PathLike, path: str | os.PathLike, *,
                    background: np.ndarray | None = None) -> None:
    """Re-make ``track.png`` at ``path`` from a finished (or interrupted) run's ``track.json``."""
    with open(track_json, encoding="utf-8") as handle:
        track = json.load(handle)
    plot_track(track["frames"], path, background=background, title=os.path.basename(os.path.dirname(
        os.path.abspath(track_json))))  # the run's output folder, e.g. track_<name>


def plot_single_run(boxes: np.ndarray, peaks: np.ndarray, psrs: np.ndarray, present: np.ndarray | None,
                    path: str | os.PathLike, *, background: np.ndarray | None = None, title: str = "") -> None:
    """Draw a ``track-single`` run: centre path, ECO's peak score and PSR, frames judged absent shaded."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    frames = np.arange(len(boxes), dtype=float)
    absent = ~np.asarray(present, bool) if present is not None and len(present) == len(boxes) \
        else np.zeros(len(boxes), bool)
    canvas, path_rect, panels = _layout([1.0, 1.0], 500, title or "rgbt track-single")
    colours = [_ABSENT if a else COLOURS["tab:green"] for a in absent]
    path_ax = _centre_path(canvas, path_rect, _centres(boxes), colours, background)
    path_ax.legend([("tracked", COLOURS["tab:green"], "dot")]
                   + ([("judged absent (box held)", _ABSENT, "dot")] if absent.any() else []))
    xlim = padded_limits(frames)
    for k, (rect, values, label) in enumerate(zip(panels, (peaks, psrs), ("peak score", "PSR"))):
        values = np.asarray(values, dtype=float)
        ax = Axes(canvas, rect, xlim, padded_limits(values))
        _shade(ax, frames, absent, _ABSENT)
        ax.line(frames, values, COLOURS["black"])
        last = k == len(panels) - 1
        ax.frame(ylabel=label, xtick_labels=last, xlabel="frame index" if last else "")
        if absent.any():
            ax.legend([("target judged absent", _ABSENT, "shade")])
    canvas.save(path)


# --------------------------------------------------------------------------------------------------------------------
def _layout(heights: list[float], height: int, title: str) -> tuple[Canvas, tuple, list[tuple]]:
    """A canvas with the path's rectangle on the left and frame-indexed panels of relative ``heights`` stacked on
    the right (the margins of the matplotlib version: room for tick labels and two-line axis labels)."""
    canvas = Canvas(WIDTH, height)
    left, right, top, bottom = 0.065 * WIDTH, 0.985 * WIDTH, 0.1 * height, 0.905 * height
    widths = (right - left) / 1.1 * np.array([1.0, 1.25]) / 2.25  # wspace 0.2 of the mean width between them
    gap_x = right - left - widths.sum()
    path_rect = (left, top, left + widths[0], bottom)
    share = np.asarray(heights, float) / np.sum(heights)
    gap_y = 0.12 * (bottom - top) / (len(heights) + 0.12 * (len(heights) - 1))  # hspace 0.12 of the mean height
    tall = (bottom - top - gap_y * (len(heights) - 1)) * share
    panels, y = [], top
    for h in tall:
        panels.append((left + widths[0] + gap_x, y, right, y + h))
        y += h + gap_y
    canvas.text(WIDTH / 2, 0.045 * height, title, scale=0.6, align="centre")
    return canvas, path_rect, panels


def _centre_path(canvas: Canvas, rect: tuple, centres: np.ndarray, colours: list, background: np.ndarray | None,
                 camera: str = "", background_scale: float = 1.0) -> Axes:
    """The box centre per frame as coloured dots joined by a thin line, over a faint first frame (shown in the
    full-resolution pixel coordinates of the boxes whatever its own size, ``background_scale`` x theirs)."""
    left, top, right, bottom = rect
    if background is not None:
        grey = background.mean(axis=2) if background.ndim == 3 else np.asarray(background, float)
        h, w = grey.shape
        xlim = (-0.5, w / background_scale - 0.5)
        ylim = (-0.5, h / background_scale - 0.5)
    else:
        xlim, ylim = padded_limits(centres[:, 0]), padded_limits(centres[:, 1])
    # equal scale on both axes: the rectangle shrinks to the image's shape, or the limits grow to the rectangle's
    data_aspect = (ylim[1] - ylim[0]) / (xlim[1] - xlim[0])
    box_aspect = (bottom - top) / (right - left)
    if background is not None:
        if data_aspect < box_aspect:
            middle, half = (top + bottom) / 2, (right - left) * data_aspect / 2
            top, bottom = middle - half, middle + half
        else:
            middle, half = (left + right) / 2, (bottom - top) / data_aspect / 2
            left, right = middle - half, middle + half
    elif data_aspect < box_aspect:
        middle, half = sum(ylim) / 2, (xlim[1] - xlim[0]) * box_aspect / 2
        ylim = (middle - half, middle + half)
    else:
        middle, half = sum(xlim) / 2, (ylim[1] - ylim[0]) / box_aspect / 2
        xlim = (middle - half, middle + half)
    ax = Axes(canvas, (left, top, right, bottom), xlim, ylim, invert_y=True)  # image rows grow downwards
    if background is not None:
        ax.image(grey, alpha=0.35)  # shrunk to the panel by area averaging
    ax.line(centres[:, 0], centres[:, 1], COLOURS["dark grey"])
    ax.dots(centres[:, 0], centres[:, 1], colours)
    finite = np.flatnonzero(np.all(np.isfinite(centres), axis=1))
    if finite.size:
        u, v = ax.px(*centres[finite[0]])
        canvas.text(u + 6, v - 6, "start", scale=0.36, valign="bottom")
        ax.marker_x(*centres[finite[-1]])
        u, v = ax.px(*centres[finite[-1]])
        canvas.text(u + 6, v + 6, "end", scale=0.36, valign="top")
    ax.frame(xlabel=f"x ({camera}pixels)", ylabel=f"y ({camera}pixels)", title="box centre path", grid=False)
    return ax


def _centres(boxes) -> np.ndarray:
    """Box centres in the first-pixel convention (``xy + (wh - 1) / 2``); missing values become NaN."""
    array = np.array([[np.nan if v is None else float(v) for v in box] for box in boxes], dtype=float).reshape(-1, 4)
    return array[:, :2] + (array[:, 2:] - 1) / 2


def _floats(values) -> np.ndarray:
    return np.array([np.nan if v is None else float(v) for v in values], dtype=float)


def _runs(frames: np.ndarray, mask: np.ndarray) -> list[tuple[float, float]]:
    """``(first - 0.5, last + 0.5)`` frame spans of each stretch where ``mask`` holds."""
    if not mask.any():
        return []
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    return [(frames[a] - 0.5, frames[b] + 0.5) for a, b in zip(starts, stops)]


def _shade(ax: Axes, frames: np.ndarray, mask: np.ndarray, colour, alpha: float = 0.2,
           y: tuple[float, float] | None = None) -> None:
    for start, stop in _runs(frames, mask):
        ax.vspan(start, stop, colour, alpha, *(y or (None, None)))
