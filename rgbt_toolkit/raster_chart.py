"""Small charts drawn straight into an image with OpenCV: axes with ticks, lines, dots, shaded spans, labels, legends.

Why not matplotlib for the run pictures (``run_plots``): ``rgbt track`` draws ``track.png`` after its last frame, and
importing matplotlib then drawing cost about 0.45 s there (0.3 s import, 0.2 s tick and text layout) on a 10-s 1080p
run, as much as 15 tracked frames. These pictures need lines, dots, spans and labels only; OpenCV, already loaded,
draws one in a few tens of milliseconds. Benchmark plots that people compare across papers stay with matplotlib
(``evaluation.plots``).

Colours are RGB tuples; :data:`COLOURS` holds matplotlib's ``tab:`` palette so the pictures keep their look.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence

import cv2
import numpy as np

from rgbt_toolkit._atomic import atomic_path

Colour = tuple[int, int, int]
COLOURS: dict[str, Colour] = {
    "tab:blue": (31, 119, 180), "tab:orange": (255, 127, 14), "tab:green": (44, 160, 44),
    "tab:red": (214, 39, 40), "tab:purple": (148, 103, 189), "black": (0, 0, 0), "grey": (140, 140, 140),
    "dark grey": (64, 64, 64), "light grey": (205, 205, 205), "white": (255, 255, 255),
}
FONT = cv2.FONT_HERSHEY_SIMPLEX
SMALL, NORMAL, LARGE = 0.36, 0.42, 0.55  # font scales: tick labels and legends, axis labels, titles
_SUB = 4  # fractional bits of the points handed to OpenCV's line drawing (1/16 pixel)


def nice_ticks(low: float, high: float, count: int = 5) -> np.ndarray:
    """About ``count`` round tick values (steps of 1, 2, 2.5 or 5 times a power of ten) within ``[low, high]``."""
    if not (math.isfinite(low) and math.isfinite(high)) or high <= low:
        return np.array([low]) if math.isfinite(low) else np.array([])
    raw = (high - low) / max(count, 1)
    power = 10.0 ** math.floor(math.log10(raw))
    step = next(m * power for m in (1, 2, 2.5, 5, 10) if m * power >= raw)
    first = math.ceil(low / step - 1e-9) * step
    return np.arange(first, high + step * 1e-9, step)


def tick_label(value: float, ticks: np.ndarray) -> str:
    """``value`` with as many decimals as the spacing of ``ticks`` needs (``250``, ``0.5``, ``0.25``)."""
    step = float(np.min(np.diff(ticks))) if len(ticks) > 1 else 1.0
    decimals = 0
    while decimals < 6 and abs(step * 10**decimals - round(step * 10**decimals)) > 1e-6:
        decimals += 1
    return f"{value:.{decimals}f}" if decimals else f"{int(round(value))}"


class Canvas:
    """A white RGB image to draw charts on, written as PNG atomically."""

    def __init__(self, width: int, height: int) -> None:
        self.image = np.full((int(height), int(width), 3), 255, np.uint8)

    def text(self, x: float, y: float, text: str, *, scale: float = NORMAL, colour: Colour = (0, 0, 0),
             align: str = "left", valign: str = "centre", vertical: bool = False) -> None:
        """Dark text at ``(x, y)``; ``align`` left / centre / right and ``valign`` top / centre / bottom say which
        point of the text's box that is. ``vertical``: read bottom to top (y-axis labels)."""
        (w, h), base = cv2.getTextSize(text, FONT, scale, 1)
        stamp = np.full((h + base + 2, w + 2, 3), 255, np.uint8)
        cv2.putText(stamp, text, (1, h + 1), FONT, scale, colour, 1, cv2.LINE_AA)
        if vertical:
            stamp = cv2.rotate(stamp, cv2.ROTATE_90_COUNTERCLOCKWISE)
        sh, sw = stamp.shape[:2]
        left = x - {"left": 0, "centre": sw / 2, "right": sw}[align]
        top = y - {"top": 0, "centre": sh / 2, "bottom": sh}[valign]
        self._stamp_darker(stamp, int(round(left)), int(round(top)))

    def _stamp_darker(self, stamp: np.ndarray, left: int, top: int) -> None:
        """Keep the darker of stamp and canvas per pixel: text drawn on white lands on any light background."""
        h, w = self.image.shape[:2]
        y0, x0, y1, x1 = max(top, 0), max(left, 0), min(top + stamp.shape[0], h), min(left + stamp.shape[1], w)
        if y1 > y0 and x1 > x0:
            region = self.image[y0:y1, x0:x1]
            np.minimum(region, stamp[y0 - top:y1 - top, x0 - left:x1 - left], out=region)

    def blend_rect(self, x0: float, y0: float, x1: float, y1: float, colour: Colour, alpha: float) -> None:
        """Paint a rectangle with ``colour`` at opacity ``alpha`` over what is there."""
        h, w = self.image.shape[:2]
        xa, xb = int(round(max(min(x0, x1), 0))), int(round(min(max(x0, x1), w)))
        ya, yb = int(round(max(min(y0, y1), 0))), int(round(min(max(y0, y1), h)))
        if xb > xa and yb > ya:
            region = self.image[ya:yb, xa:xb].astype(np.float32)
            region += alpha * (np.asarray(colour, np.float32) - region)
            self.image[ya:yb, xa:xb] = np.round(region).astype(np.uint8)

    def save(self, path: str | os.PathLike) -> None:
        """Write the PNG under a temporary name and rename it: an interrupted write leaves no partial picture."""
        ok, data = cv2.imencode(".png", cv2.cvtColor(self.image, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_PNG_COMPRESSION, 1])
        if not ok:
            raise OSError(f"{path}: the PNG could not be encoded")
        with atomic_path(path, suffix=".png") as tmp:
            write_bytes(tmp, data.tobytes())


def write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` (one place, so a test can make the disk fill up here)."""
    with open(path, "wb") as handle:
        handle.write(data)


class Axes:
    """One chart panel: a pixel rectangle ``(left, top, right, bottom)`` on a canvas showing ``xlim`` x ``ylim``.

    Draw the data first (spans, image, lines, dots), then :meth:`frame` for the border, ticks and labels.
    """

    def __init__(self, canvas: Canvas, rect: Sequence[float], xlim: Sequence[float], ylim: Sequence[float],
                 *, invert_y: bool = False) -> None:
        self.canvas = canvas
        self.left, self.top, self.right, self.bottom = (float(v) for v in rect)
        self.xlim = (float(xlim[0]), float(xlim[1]))
        self.ylim = (float(ylim[0]), float(ylim[1]))
        self.invert_y = invert_y

    def px(self, x, y) -> tuple[np.ndarray, np.ndarray]:
        """Pixel coordinates of data points."""
        (x0, x1), (y0, y1) = self.xlim, self.ylim
        u = self.left + (np.asarray(x, float) - x0) / (x1 - x0) * (self.right - self.left)
        frac = (np.asarray(y, float) - y0) / (y1 - y0)
        height = self.bottom - self.top
        v = self.top + frac * height if self.invert_y else self.bottom - frac * height
        return u, v

    def _clip(self):
        """A view of the canvas limited to this panel, and its offset: drawing stays inside the frame."""
        t, b = int(math.floor(self.top)), int(math.ceil(self.bottom)) + 1
        l, r = int(math.floor(self.left)), int(math.ceil(self.right)) + 1
        return self.canvas.image[t:b, l:r], l, t

    def line(self, x, y, colour: Colour, thickness: int = 1) -> None:
        """A polyline through the finite points; a NaN breaks it."""
        u, v = self.px(x, y)
        finite = np.isfinite(u) & np.isfinite(v)
        view, l, t = self._clip()
        for run in np.split(np.arange(len(u)), np.flatnonzero(np.diff(finite.astype(np.int8)) != 0) + 1):
            if len(run) > 1 and finite[run[0]]:
                pts = np.round(np.c_[u[run] - l, v[run] - t] * (1 << _SUB)).astype(np.int32)
                cv2.polylines(view, [pts], False, colour, thickness, cv2.LINE_AA, _SUB)

    def dots(self, x, y, colours: Sequence[Colour], radius: int = 2) -> None:
        """A filled dot per finite point, each in its own colour."""
        u, v = self.px(x, y)
        view, l, t = self._clip()
        for ui, vi, c in zip(u, v, colours):
            if math.isfinite(ui) and math.isfinite(vi):
                cv2.circle(view, (int(round((ui - l) * (1 << _SUB))), int(round((vi - t) * (1 << _SUB)))),
                           radius << _SUB, c, -1, cv2.LINE_AA, _SUB)

    def marker_x(self, x: float, y: float, colour: Colour = (0, 0, 0), size: int = 5) -> None:
        """An x-shaped mark at one data point (the end of a path)."""
        u, v = self.px(x, y)
        for du in (-size, size):
            cv2.line(self.canvas.image, (int(u - du), int(v - size)), (int(u + du), int(v + size)), colour, 2,
                     cv2.LINE_AA)

    def vspan(self, x0: float, x1: float, colour: Colour, alpha: float, y0: float | None = None,
              y1: float | None = None) -> None:
        """A band from ``x0`` to ``x1`` over the panel's height (or from ``y0`` to ``y1``)."""
        u0, _ = self.px(max(x0, self.xlim[0]), 0)
        u1, _ = self.px(min(x1, self.xlim[1]), 0)
        top, bottom = self.top, self.bottom
        if y0 is not None and y1 is not None:
            _, va = self.px(0, y0)
            _, vb = self.px(0, y1)
            top, bottom = max(min(va, vb), self.top), min(max(va, vb), self.bottom)
        self.canvas.blend_rect(u0, top, u1, bottom, colour, alpha)

    def image(self, grey: np.ndarray, alpha: float) -> None:
        """A grey image (0..255) stretched over the whole panel, at opacity ``alpha`` over white."""
        w, h = int(round(self.right - self.left)), int(round(self.bottom - self.top))
        shown = cv2.resize(np.asarray(grey, np.float32), (w, h), interpolation=cv2.INTER_AREA)
        faint = np.round(255 + alpha * (np.clip(shown, 0, 255) - 255)).astype(np.uint8)
        t, l = int(round(self.top)), int(round(self.left))
        self.canvas.image[t:t + h, l:l + w] = faint[..., None]

    def frame(self, *, xlabel: str = "", ylabel: str = "", title: str = "", xtick_labels: bool = True,
              yticks: Sequence[float] | None = None, ytick_labels: Sequence[str] | None = None,
              grid: bool = True) -> None:
        """Border, ticks (round values, or ``yticks`` with ``ytick_labels``), light grid lines and the labels."""
        c = self.canvas
        img = c.image
        grid_colour, tick_colour = (232, 232, 232), (0, 0, 0)
        xs = nice_ticks(*sorted(self.xlim))
        ys = nice_ticks(*sorted(self.ylim)) if yticks is None else np.asarray(yticks, float)
        ylabels = [tick_label(v, ys) for v in ys] if ytick_labels is None else list(ytick_labels)
        top, bottom, left, right = (int(round(v)) for v in (self.top, self.bottom, self.left, self.right))
        ux, _ = self.px(xs, np.zeros(len(xs)))
        _, vy = self.px(np.zeros(len(ys)), ys)
        if grid:
            for u in ux:
                img[top:bottom, int(round(u))] = np.minimum(img[top:bottom, int(round(u))], grid_colour)
            for v in vy:
                img[int(round(v)), left:right] = np.minimum(img[int(round(v)), left:right], grid_colour)
        cv2.rectangle(img, (left, top), (right, bottom), tick_colour, 1)
        for u, value in zip(ux, xs):
            cv2.line(img, (int(round(u)), bottom), (int(round(u)), bottom + 4), tick_colour, 1)
            if xtick_labels:
                c.text(u, bottom + 7, tick_label(value, xs), scale=SMALL, align="centre", valign="top")
        widest = 0
        for v, label in zip(vy, ylabels):
            cv2.line(img, (left - 4, int(round(v))), (left, int(round(v))), tick_colour, 1)
            c.text(left - 7, v, label, scale=SMALL, align="right")
            widest = max(widest, cv2.getTextSize(label, FONT, SMALL, 1)[0][0])
        if xlabel:
            c.text((left + right) / 2, bottom + (24 if xtick_labels and len(xs) else 8), xlabel, align="centre",
                   valign="top")
        if ylabel:
            lines = ylabel.split("\n")
            for k, line in enumerate(lines):  # two-line labels: the first further out
                c.text(left - widest - 14 - 14 * (len(lines) - 1 - k), (top + bottom) / 2, line, align="right",
                       vertical=True)
        if title:
            c.text((left + right) / 2, top - 6, title, align="centre", valign="bottom")

    def legend(self, entries: Sequence[tuple[str, Colour, str]], *, title: str = "", corner: str = "upper right"
               ) -> None:
        """A boxed key in a corner: ``(label, colour, kind)`` with kind ``"dot"`` (a path's dots) or ``"shade"`` (a
        faint patch, as the shaded spans it names)."""
        if not entries:
            return
        c = self.canvas
        sizes = [cv2.getTextSize(label, FONT, SMALL, 1)[0] for label, _, _ in entries]
        row = max(h for _, h in sizes) + 7
        width = 30 + max(w for w, _ in sizes + [cv2.getTextSize(title, FONT, SMALL, 1)[0]])
        height = row * (len(entries) + bool(title)) + 6
        x0 = self.right - width - 6 if "right" in corner else self.left + 6
        y0 = self.top + 6 if "upper" in corner else self.bottom - height - 6
        c.blend_rect(x0, y0, x0 + width, y0 + height, COLOURS["white"], 0.85)
        cv2.rectangle(c.image, (int(x0), int(y0)), (int(x0 + width), int(y0 + height)), COLOURS["light grey"], 1)
        y = y0 + 3 + row / 2
        if title:
            c.text(x0 + width / 2, y, title, scale=SMALL, align="centre")
            y += row
        for label, colour, kind in entries:
            if kind == "dot":
                cv2.circle(c.image, (int(x0 + 12), int(y)), 3, colour, -1, cv2.LINE_AA)
            else:
                c.blend_rect(x0 + 5, y - 5, x0 + 20, y + 5, colour, 0.3)
            c.text(x0 + 25, y, label, scale=SMALL)
            y += row


def padded_limits(values: np.ndarray, margin: float = 0.05, default: tuple[float, float] = (0.0, 1.0)
                  ) -> tuple[float, float]:
    """The finite values' range widened by ``margin`` of it on each side (matplotlib's automatic limits)."""
    finite = np.asarray(values, float)
    finite = finite[np.isfinite(finite)]
    if not finite.size:
        return default
    low, high = float(finite.min()), float(finite.max())
    if high == low:
        return low - 0.5, high + 0.5
    pad = (high - low) * margin
    return low - pad, high + pad


__all__ = ["COLOURS", "Axes", "Canvas", "nice_ticks", "padded_limits", "tick_label", "write_bytes"]
