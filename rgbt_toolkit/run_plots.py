"""Pictures of one tracking run: where the box went and, frame by frame, why (``track.png``, ``track-single --plot``).

A user looks at these before reading ``track.json``: the centre path over a faint first frame, and beside it the
per-frame signals (MAX-PSR q, appearance/motion mode, w_G, the camera-motion flag; or ECO's peak and PSR) with the
frames that were not plain appearance tracking shaded. Drawn only from the per-frame records the run writes, so a
picture can be re-made from ``track.json`` alone. matplotlib's Agg backend (no display); PNGs are written atomically.
"""

from __future__ import annotations

import json
import os
from collections.abc import Sequence

import numpy as np

from rgbt_toolkit._atomic import atomic_path

# what track.png reads of each track.json record
TRACK_FIELDS = ("frame", "box_rgb", "mode", "present", "q", "w_g", "camera_motion")
MODE_COLOURS = {"init": "tab:blue", "appearance": "tab:green", "motion": "tab:orange", "skipped": "0.55"}
_CAMERA = "tab:red"
_ABSENT = "tab:red"


def plot_track(records: Sequence[dict], path: str | os.PathLike, *, background: np.ndarray | None = None,
               title: str = "", dpi: int = 100, background_scale: float = 1.0) -> None:
    """Draw ``track.png`` from ``track.json``'s per-frame records (``frame``, ``box_rgb``, ``mode``, ``q``, ...).

    ``background`` (the first RGB frame, possibly shrunk by ``background_scale``) is shown faintly under the centre
    path so the path has a place.
    """
    frames = np.array([r["frame"] for r in records], dtype=float)
    centres = _centres([r["box_rgb"] for r in records])
    modes = [r["mode"] for r in records]
    fig, path_ax, (q_ax, mode_ax, wg_ax, cm_ax) = _figure([1.5, 0.45, 1.0, 0.45], background, title or "rgbt track")
    _centre_path(path_ax, centres, [MODE_COLOURS.get(m, "0.3") for m in modes], background, "RGB ",
                 background_scale)
    for mode in ("appearance", "motion", "skipped"):
        path_ax.scatter([], [], s=12, color=MODE_COLOURS[mode], label=mode)
    path_ax.legend(title="mode", loc="best", fontsize=8, title_fontsize=8, framealpha=0.8)

    motion = np.array([m == "motion" for m in modes])
    q = _floats(r.get("q") for r in records)
    q_ax.plot(frames, q, color="k", linewidth=1.2)
    q_ax.set_ylabel("MAX-PSR q")
    _shade(q_ax, frames, motion, MODE_COLOURS["motion"], "motion mode")
    lost = np.array([r.get("present", True) is False for r in records])  # re-acquisition: the target counted as lost
    _shade(q_ax, frames, lost, _ABSENT, "target judged absent")
    if motion.any() or lost.any():
        q_ax.legend(loc="upper right", fontsize=8)

    for mode in ("appearance", "motion", "skipped", "init"):
        for start, stop in _runs(frames, np.array([m == mode for m in modes])):
            mode_ax.axvspan(start, stop, color=MODE_COLOURS[mode], alpha=0.85, linewidth=0,
                            label=mode if mode != "init" else None)
    mode_ax.set_yticks([])
    mode_ax.set_ylabel("mode")

    wg_ax.plot(frames, _floats(r.get("w_g") for r in records), color="tab:purple", linewidth=1.2)
    wg_ax.set_ylim(-0.02, 1.02)
    wg_ax.set_ylabel("w_G (RGB)")
    _shade(wg_ax, frames, motion, MODE_COLOURS["motion"])

    camera = np.array([bool(r.get("camera_motion")) for r in records])
    cm_ax.fill_between(frames, 0, camera.astype(float), step="mid", color=_CAMERA, alpha=0.6, linewidth=0)
    cm_ax.set_ylim(0, 1.05)
    cm_ax.set_yticks([0, 1], ["no", "yes"])
    cm_ax.set_ylabel("camera\nmotion")
    _save(fig, path, dpi)


def plot_track_json(track_json: str | os.PathLike, path: str | os.PathLike, *,
                    background: np.ndarray | None = None) -> None:
    """Re-make ``track.png`` at ``path`` from a finished (or interrupted) run's ``track.json``."""
    with open(track_json, encoding="utf-8") as handle:
        track = json.load(handle)
    plot_track(track["frames"], path, background=background, title=os.path.basename(os.path.dirname(
        os.path.abspath(track_json))))  # the run's output folder, e.g. track_<name>


def plot_single_run(boxes: np.ndarray, peaks: np.ndarray, psrs: np.ndarray, present: np.ndarray | None,
                    path: str | os.PathLike, *, background: np.ndarray | None = None, title: str = "",
                    dpi: int = 100) -> None:
    """Draw a ``track-single`` run: centre path, ECO's peak score and PSR, frames judged absent shaded."""
    boxes = np.asarray(boxes, dtype=float).reshape(-1, 4)
    frames = np.arange(len(boxes), dtype=float)
    absent = ~np.asarray(present, bool) if present is not None and len(present) == len(boxes) \
        else np.zeros(len(boxes), bool)
    fig, path_ax, (peak_ax, psr_ax) = _figure([1.0, 1.0], background, title or "rgbt track-single")
    colours = [_ABSENT if a else "tab:green" for a in absent]
    _centre_path(path_ax, _centres(boxes), colours, background)
    path_ax.scatter([], [], s=12, color="tab:green", label="tracked")
    if absent.any():
        path_ax.scatter([], [], s=12, color=_ABSENT, label="judged absent (box held)")
    path_ax.legend(loc="best", fontsize=8, framealpha=0.8)
    for ax, values, label in ((peak_ax, peaks, "peak score"), (psr_ax, psrs, "PSR")):
        ax.plot(frames, np.asarray(values, dtype=float), color="k", linewidth=1.2)
        ax.set_ylabel(label)
        _shade(ax, frames, absent, _ABSENT, "target judged absent")
        if absent.any():
            ax.legend(loc="upper right", fontsize=8)
    _save(fig, path, dpi)


# --------------------------------------------------------------------------------------------------------------------
def _figure(heights: list[float], background: np.ndarray | None, title: str):
    """A figure with the path on the left and frame-indexed panels of relative ``heights`` stacked on the right."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure  # no pyplot: no global state, no display

    n_panels = len(heights)
    # fixed margins, room for the tick labels and two-line axis labels: matplotlib's constrained layout measured every
    # text on each save, 0.15-0.3 s of a 0.4 s track.png
    fig = Figure(figsize=(12, 5.5 if n_panels > 2 else 5))
    FigureCanvasAgg(fig)
    grid = fig.add_gridspec(n_panels, 2, width_ratios=[1.0, 1.25], height_ratios=heights, left=0.065, right=0.985,
                            bottom=0.095, top=0.9, wspace=0.2, hspace=0.12)
    path_ax = fig.add_subplot(grid[:, 0])
    panels = [fig.add_subplot(grid[0, 1])]
    panels += [fig.add_subplot(grid[k, 1], sharex=panels[0]) for k in range(1, n_panels)]
    for ax in panels:
        ax.grid(True, alpha=0.3)
    for ax in panels[:-1]:
        ax.tick_params(labelbottom=False)
    panels[-1].set_xlabel("frame index")
    fig.suptitle(title, fontsize=12)
    return fig, path_ax, panels


PLOT_BACKGROUND_WIDTH = 800  # a larger first frame is shrunk first: the picture is 12 in wide, and savefig of a
# 1080p image under the path took about 2 s


def _centre_path(ax, centres: np.ndarray, colours: list, background: np.ndarray | None, camera: str = "",
                 background_scale: float = 1.0) -> None:
    """The box centre per frame as coloured dots joined by a thin line, over a faint first frame (shown in the
    full-resolution pixel coordinates of the boxes whatever its own size, ``background_scale`` x theirs)."""
    if background is not None:
        grey = background.mean(axis=2) if background.ndim == 3 else background
        h, w = grey.shape
        full_w, full_h = w / background_scale, h / background_scale
        if w > PLOT_BACKGROUND_WIDTH:
            import cv2

            f = PLOT_BACKGROUND_WIDTH / w
            grey = cv2.resize(grey.astype(np.float32), (PLOT_BACKGROUND_WIDTH, max(1, int(round(h * f)))),
                              interpolation=cv2.INTER_AREA)
        ax.imshow(grey, cmap="gray", alpha=0.35, vmin=0, vmax=255, interpolation="nearest",
                  extent=(-0.5, full_w - 0.5, full_h - 0.5, -0.5))
    ax.plot(centres[:, 0], centres[:, 1], color="0.25", linewidth=0.8, alpha=0.8)
    ax.scatter(centres[:, 0], centres[:, 1], s=9, c=colours, zorder=3, linewidths=0)
    finite = np.flatnonzero(np.all(np.isfinite(centres), axis=1))
    if finite.size:
        ax.annotate("start", centres[finite[0]], xytext=(6, 6), textcoords="offset points", fontsize=8)
        ax.plot(*centres[finite[-1]], marker="x", color="k", markersize=8, zorder=4)
        ax.annotate("end", centres[finite[-1]], xytext=(6, -12), textcoords="offset points", fontsize=8)
    if background is None:
        ax.invert_yaxis()  # image rows grow downwards
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"x ({camera}pixels)")
    ax.set_ylabel(f"y ({camera}pixels)")
    ax.set_title("box centre path", fontsize=10)


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


def _shade(ax, frames: np.ndarray, mask: np.ndarray, colour: str, label: str | None = None) -> None:
    for k, (start, stop) in enumerate(_runs(frames, mask)):
        ax.axvspan(start, stop, color=colour, alpha=0.2, linewidth=0, label=label if k == 0 else None)


def _save(fig, path: str | os.PathLike, dpi: int) -> None:
    """Write the PNG under a temporary name and rename it: an interrupted write leaves no partial picture."""
    with atomic_path(path, suffix=".png") as tmp:
        # zlib level 1: 0.07 s less per picture than the default 6, for a file about 6 % larger
        fig.savefig(tmp, dpi=dpi, format="png", pil_kwargs={"compress_level": 1})
