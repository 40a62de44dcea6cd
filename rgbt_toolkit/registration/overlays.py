"""Burned-in overlays (on-screen text, clocks, reticles, logos) found in one camera's frames, so that registration
and camera-motion estimation can leave them out.

Each camera of a rig draws its own on-screen display (OSD). It is sharp, high-contrast and fixed in the frame, and
over a featureless scene (a night sky) it is the only structure the two views share: matched against the other
camera's OSD it yields a confident, wrong transform. Two cues find it in one camera on its own:

* in a video, pixels that keep their value while the scene behind them changes (:func:`static_mask`,
  :class:`StaticOverlayMask`); a camera that does not move leaves the whole scene fixed, and then this cue says
  nothing;
* in any frame, text-like strokes: thin, high-contrast marks a few pixels wide (a morphological top-hat / black-hat),
  in components of character size lined up along a row, and thin straight horizontal or vertical lines such as a
  reticle's brackets (:func:`text_mask`).

Masked pixels are then given no structure (:func:`blank_out`): every stage that measures edges (coarse search,
refinement, block verification) sees a smooth patch there, and a block with nothing left does not vote.
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.features import to_grey

ANALYSIS_LONGER = 320  # px: static detection works on frames shrunk to this longer side (cheap, and noise averages)
STATIC_TOLERANCE = 6.0  # grey levels (of 255) a fixed pixel may wander at 320 px: sensor noise, codec blocking
STATIC_EDGE = 24.0  # grey levels: a fixed pixel counts only on a strong edge (overlays are high-contrast marks)
# fewer of the strong edges than this changing by a strong edge's contrast: the camera does not move (sensor noise
# alone moves a pixel by a few grey levels), and fixed pixels cannot be told from the scene
MIN_MOVING_EDGES = 0.35
STROKE_CONTRAST = 48.0  # grey levels a stroke stands out from what surrounds it (OSD text is white or black)
# an OSD is drawn at full intensity: a bright stroke reaches this grey level, a dark one stays below 255 minus it
# (JPEG ringing keeps a white glyph above 220); road markings and lit windows seldom do both this and the rest
STROKE_LEVEL = 200
LINE_GAP = 1.2  # characters of one line are less than this many character heights apart
MIN_LINE_CHARS = 5  # a line of OSD text holds at least this many marks (a clock's digits, a camera's name)
MARGIN = 2  # px (full size) added around every mask: anti-aliasing and codec ringing of the overlay's edges
TEXT_LONGER = 960  # px: text is looked for on frames shrunk to this longer side (a 1080p OSD's text stays 9+ px high)
# an OSD covers a few per cent of the frame; a mask larger than this is a fine texture (foliage, gravel, noise)
# taken for strokes, and is dropped rather than blanking the scene
MAX_MASK_FRACTION = 0.15
FILL_LONGER = 160  # px: the smooth fill of blank_out is computed at this size (its blur is wide; shrinking is cheap)


def _grey_u8(image: np.ndarray) -> np.ndarray:
    return np.round(to_grey(image) * 255).astype(np.uint8)


def _grow(mask: np.ndarray, radius: int) -> np.ndarray:
    if radius <= 0:
        return mask
    return cv2.dilate(mask.astype(np.uint8), np.ones((2 * radius + 1,) * 2, np.uint8)) > 0


def _strokes(grey: np.ndarray, stroke: int) -> np.ndarray:
    """Pixels of thin (at most ``stroke`` px) marks of high contrast drawn at full intensity: near white on darker
    surroundings, or near black on brighter ones."""
    kernel = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * stroke + 1, 2 * stroke + 1))
    bright = cv2.morphologyEx(grey, cv2.MORPH_TOPHAT, kernel) >= STROKE_CONTRAST
    dark = cv2.morphologyEx(grey, cv2.MORPH_BLACKHAT, kernel) >= STROKE_CONTRAST
    return _reaching(bright, grey, STROKE_LEVEL) | _reaching(dark, 255 - grey, STROKE_LEVEL)


def _reaching(marks: np.ndarray, level_of: np.ndarray, level: int) -> np.ndarray:
    """The connected parts of ``marks`` whose brightest pixel in ``level_of`` reaches ``level`` (a thin glyph's
    anti-aliased edge is dimmer than its core; the whole glyph is kept when its core is drawn at full intensity)."""
    count, labels = cv2.connectedComponents(marks.astype(np.uint8), connectivity=8)
    peak = np.zeros(count, np.int32)
    np.maximum.at(peak, labels[marks], level_of[marks].astype(np.int32))
    keep = peak >= level
    keep[0] = False
    return keep[labels]


def _text_lines(strokes: np.ndarray, char_height: tuple[int, int]) -> np.ndarray:
    """Stroke components of character size that line up, at least :data:`MIN_LINE_CHARS` to a row."""
    count, labels, stats, _ = cv2.connectedComponentsWithStats(strokes.astype(np.uint8), connectivity=8)
    low, high = char_height
    h, w = stats[:, cv2.CC_STAT_HEIGHT], stats[:, cv2.CC_STAT_WIDTH]
    chars = np.flatnonzero((np.arange(count) > 0) & (h >= low) & (h <= high) & (w <= 2 * high))
    if len(chars) < MIN_LINE_CHARS:
        return np.zeros(strokes.shape, bool)
    marks = np.isin(labels, chars)
    # join the characters of a row: close horizontally by LINE_GAP character heights, then count marks per group
    gap = max(3, int(LINE_GAP * high))
    joined = cv2.dilate(marks.astype(np.uint8), cv2.getStructuringElement(cv2.MORPH_RECT, (gap, 1)))
    groups, group_of = cv2.connectedComponents(joined, connectivity=8)
    members = np.bincount(group_of[stats[chars, cv2.CC_STAT_TOP] + h[chars] // 2,
                                   stats[chars, cv2.CC_STAT_LEFT] + w[chars] // 2], minlength=groups)
    lines = np.flatnonzero(members >= MIN_LINE_CHARS)
    lines = lines[lines > 0]
    return marks & np.isin(group_of, lines)


def _straight_lines(strokes: np.ndarray, length: int) -> np.ndarray:
    """Thin strokes that run straight, horizontally or vertically, for at least ``length`` px (a reticle)."""
    along = cv2.morphologyEx(strokes.astype(np.uint8), cv2.MORPH_OPEN, np.ones((1, length), np.uint8))
    down = cv2.morphologyEx(strokes.astype(np.uint8), cv2.MORPH_OPEN, np.ones((length, 1), np.uint8))
    return (along | down) > 0


def text_mask(image: np.ndarray) -> np.ndarray:
    """Where one still frame carries burned-in text or a reticle: a boolean (H, W) mask.

    Conservative by design: only thin marks of high contrast, in lined-up groups of character size (between 1/60
    and 1/12 of the frame height: a 1080-line OSD's 18-90 px, a 240-line one's 4-20 px), or straight horizontal or
    vertical strokes at least 1/40 of the frame height long. Scene edges between two areas are not strokes; a row
    of lit windows or a thin straight mast can be taken, which only leaves a little of the scene out.
    """
    grey = _grey_u8(image)
    height = grey.shape[0]
    stroke = max(2, int(round(height / 160)))
    strokes = _strokes(grey, stroke)
    text = _text_lines(strokes, (max(3, height // 60), max(6, height // 12)))
    lines = _straight_lines(strokes, max(6, height // 40))
    mask = _grow(text | lines, MARGIN + stroke // 2)
    return mask if mask.mean() <= MAX_MASK_FRACTION else np.zeros_like(mask)


def _shrunk(grey: np.ndarray) -> np.ndarray:
    factor = min(1.0, ANALYSIS_LONGER / max(grey.shape))
    if factor >= 1.0:
        return grey.astype(np.float32)
    size = (max(1, int(round(grey.shape[1] * factor))), max(1, int(round(grey.shape[0] * factor))))
    return cv2.resize(grey.astype(np.float32), size, interpolation=cv2.INTER_AREA)


class StaticOverlayMask:
    """Accumulates, frame by frame, which pixels stay fixed on a strong edge while the rest of the view changes.

    Cheap enough for a per-frame loop: each frame is shrunk to :data:`ANALYSIS_LONGER` px and only a running
    minimum, maximum and sum are kept. :meth:`mask` answers at the frames' full size, or None while it cannot tell
    (fewer than two frames, or a camera that does not move so most of the view is fixed).
    """

    def __init__(self) -> None:
        self.count = 0
        self.shape: tuple[int, int] | None = None
        self._low = self._high = self._sum = None

    def update(self, frame: np.ndarray) -> np.ndarray | None:
        """Take one frame (grey or colour, any dtype :func:`to_grey` reads) and return :meth:`mask`."""
        grey = _grey_u8(frame)
        if self.shape is None:
            self.shape = grey.shape
        elif grey.shape != self.shape:
            raise InputError(f"frames differ in size ({grey.shape[1]}x{grey.shape[0]} after "
                             f"{self.shape[1]}x{self.shape[0]}); one camera has one resolution")
        small = _shrunk(grey)
        if self._low is None:
            self._low, self._high, self._sum = small.copy(), small.copy(), small.copy()
        else:
            np.minimum(self._low, small, out=self._low)
            np.maximum(self._high, small, out=self._high)
            self._sum += small
        self.count += 1
        return self.mask()

    def mask(self, shape: tuple[int, int] | None = None) -> np.ndarray | None:
        """The fixed strong-edge pixels and their neighbourhood at (height, width) ``shape`` (default: the frames'
        size; a motion estimator working on shrunk frames asks for its own size); None while the cue cannot tell."""
        if self.count < 2:
            return None
        spread = self._high - self._low
        mean = self._sum / self.count
        edge = cv2.morphologyEx(mean, cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) >= STATIC_EDGE
        if not edge.any() or (spread[edge] >= STATIC_EDGE).mean() < MIN_MOVING_EDGES:
            return None  # most edges stay put: the camera does not move (an overlay is a small part of the edges)
        fixed = spread <= STATIC_TOLERANCE
        mask = _at_size(_grow(fixed & edge, 1), self.shape if shape is None else shape)
        return None if mask.mean() > MAX_MASK_FRACTION else mask  # specks of a still scene or noise, no overlay


class OverlayMask(StaticOverlayMask):
    """:class:`StaticOverlayMask` with the text cue as well: :func:`text_mask` on the running mean of the shrunk
    frames (the overlay stays sharp in it while a moving scene blurs), so an OSD is found over a still camera, and
    over a featureless sky where the OSD holds most of the view's strong edges and the fixed-mark cue cannot tell.
    The mask for a per-frame estimator (camera motion): cheap, since everything runs at :data:`ANALYSIS_LONGER` px."""

    def mask(self, shape: tuple[int, int] | None = None) -> np.ndarray | None:
        """Overlay pixels at (height, width) ``shape`` (default: the frames' size); None before the first frame."""
        if self.count == 0:
            return None
        shape = self.shape if shape is None else shape
        mean = np.round(self._sum / self.count).astype(np.uint8)
        text = text_mask(mean)
        found = _at_size(text, shape) if text.any() else np.zeros(shape, bool)
        fixed = super().mask(shape)
        return found if fixed is None else found | fixed


def _at_size(mask: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A mask found on shrunk frames at (height, width) ``shape``, grown by a shrunk pixel and :data:`MARGIN`."""
    if mask.shape == tuple(shape):
        return _grow(mask, MARGIN + 1)
    full = cv2.resize(mask.astype(np.uint8), (shape[1], shape[0]), interpolation=cv2.INTER_NEAREST) > 0
    return _grow(full, MARGIN + int(np.ceil(max(shape) / max(mask.shape))))


def static_mask(frames) -> np.ndarray | None:
    """Pixels of a camera's ``frames`` that stay fixed on a strong edge while the scene changes, at full size;
    None when the frames cannot tell (fewer than two, or a camera that does not move)."""
    accumulator = StaticOverlayMask()
    for frame in frames:
        accumulator.update(frame)
    return accumulator.mask()


def overlay_mask(frames) -> np.ndarray:
    """Everything one camera's ``frames`` (a video's samples, or one still) show as an overlay: the fixed marks of
    :func:`static_mask` and the text and reticle strokes :func:`text_mask` finds in their per-pixel median (over a
    moving scene the median keeps the overlay sharp and blurs the scene)."""
    frames = list(frames)
    if not frames:
        raise InputError("no frames given to look for overlays in")
    greys = [_grey_u8(f) for f in frames]
    factor = min(1.0, TEXT_LONGER / max(greys[0].shape))
    small = greys if factor == 1.0 else [cv2.resize(g, None, fx=factor, fy=factor, interpolation=cv2.INTER_AREA)
                                         for g in greys]
    median = small[0] if len(small) == 1 else np.median(np.stack(small), axis=0).astype(np.uint8)
    mask = text_mask(median)
    mask = mask if factor == 1.0 else _at_size(mask, greys[0].shape)
    if mask.mean() > MAX_MASK_FRACTION:  # grown back to full size, a fine texture's specks can cover the frame
        mask[:] = False
    fixed = static_mask(greys)
    return mask if fixed is None else mask | fixed


def blank_out(frame: np.ndarray, mask: np.ndarray | None) -> np.ndarray:
    """``frame`` as a float32 grey image in [0, 1] with the masked pixels replaced by a smooth fill of what
    surrounds them (normalised convolution), so they hold no edge for any stage to measure."""
    grey = to_grey(frame)
    if mask is None or not mask.any():
        return grey
    if mask.shape != grey.shape:
        raise InputError(f"a {mask.shape[1]}x{mask.shape[0]} mask does not fit {grey.shape[1]}x{grey.shape[0]} frames")
    valid = (~mask).astype(np.float32)
    factor = min(1.0, FILL_LONGER / max(grey.shape))
    size = (max(1, round(grey.shape[1] * factor)), max(1, round(grey.shape[0] * factor)))
    small_valid = cv2.resize(valid, size, interpolation=cv2.INTER_AREA)
    small_sum = cv2.resize(grey * valid, size, interpolation=cv2.INTER_AREA)
    weight = cv2.GaussianBlur(small_valid, (0, 0), 2.5)  # a fiftieth of the frame: wider than any stroke
    small_fill = cv2.GaussianBlur(small_sum, (0, 0), 2.5) / np.maximum(weight, 1e-6)
    small_fill = np.where(weight > 1e-3, small_fill, float(grey[~mask].mean()) if (~mask).any() else 0.5)
    fill = cv2.resize(small_fill.astype(np.float32), (grey.shape[1], grey.shape[0]), interpolation=cv2.INTER_LINEAR)
    out = grey.copy()
    out[mask] = fill[mask]
    return out


def feature_mask(mask: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray | None:
    """OpenCV's detector mask (uint8, 255 where features may be found) at (height, width) ``shape`` from an overlay
    ``mask`` (True = overlay), for ``cv2.goodFeaturesToTrack(..., mask=)`` and ``SIFT.detectAndCompute(image, mask)``;
    None (no restriction) when there is no mask. Features next to an overlay are left out too: a corner detector's
    window would still see the overlay's edge."""
    if mask is None:
        return None
    allowed = ~_grow(fitted(mask, shape), 3)
    return allowed.astype(np.uint8) * 255


def read_mask(path) -> np.ndarray:
    """A mask drawn by hand: an image file, non-zero where frames are to be left out (any size: resized later)."""
    from rgbt_toolkit.io.images import read_image

    mask = read_image(path)
    return fitted(mask, mask.shape[:2])


def fitted(mask: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """A mask (any non-zero = masked) resized to frames of (height, width) ``shape``, keeping every masked pixel."""
    mask = np.asarray(mask)
    if mask.ndim == 3:
        mask = mask.max(axis=2)
    if mask.ndim != 2:
        raise InputError(f"a mask is a 2-D image, got shape {mask.shape}")
    small = (mask != 0).astype(np.uint8)
    if small.shape == tuple(shape):
        return small > 0
    scaled = cv2.resize(small * 255, (shape[1], shape[0]), interpolation=cv2.INTER_AREA)
    return scaled > 0


__all__ = ["OverlayMask", "StaticOverlayMask", "blank_out", "feature_mask", "fitted", "overlay_mask", "read_mask",
           "static_mask", "text_mask"]
