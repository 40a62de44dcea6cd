"""Independent check of an estimated RGB->thermal transform: do the parts of the view agree with it?

The global search and refinement maximise one correlation over the whole view, so a mismatch (two unrelated scenes)
can still reach a modest score: the transform bends to line up whatever edges it can. A right transform is
different in kind: cut the view into blocks and let each block find its own best shift against the warped thermal
frame, and the blocks that hold structure agree, each peaking at (almost) zero shift. For a mismatch the blocks'
peaks scatter over the search window. Counting the agreeing blocks is therefore evidence that does not come from
the objective the estimate was fitted to, and it lets weakly correlated but right answers (night scenes, low
contrast) be accepted without letting chance alignments in.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from rgbt_toolkit.registration.features import orientation_field, resize_to
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.transforms import normalize, pixel_scaling


@dataclass(frozen=True)
class BlockAgreement:
    """How many textured blocks peak at the estimate's position (within ``radius`` level pixels)."""

    agreeing: int
    textured: int
    shifts: np.ndarray  # (textured, 2) best shift of each textured block, level pixels (dx, dy)
    peaks: np.ndarray  # (textured,) peak correlation of each textured block

    @property
    def fraction(self) -> float:
        return self.agreeing / self.textured if self.textured else 0.0


def _warped_fields(rgb: np.ndarray, thermal: np.ndarray, matrix: np.ndarray, longer: int):
    """RGB orientation field at the level and the thermal frame warped into it (field and valid mask)."""
    factor = min(1.0, longer / max(rgb.shape))
    small_a = resize_to(rgb, factor)
    h, w = small_a.shape
    # shrink the thermal frame to about the level's pixel size first, so the warp does not alias (the matrix maps
    # one RGB pixel to ``thermal_per_rgb`` thermal pixels)
    thermal_per_rgb = float(np.sqrt(abs(np.linalg.det(normalize(matrix)[:2, :2]))))
    t_factor = min(1.0, factor / max(thermal_per_rgb, 1e-6))
    small_t = resize_to(thermal, t_factor)
    to_a = pixel_scaling(w / rgb.shape[1], h / rgb.shape[0])
    to_t = pixel_scaling(small_t.shape[1] / thermal.shape[1], small_t.shape[0] / thermal.shape[0])
    level = to_t @ matrix @ np.linalg.inv(to_a)
    warped = cv2.warpPerspective(small_t, level, (w, h), flags=cv2.WARP_INVERSE_MAP | cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_REFLECT)
    valid = cv2.warpPerspective(np.ones_like(small_t, np.uint8), level, (w, h),
                                flags=cv2.WARP_INVERSE_MAP | cv2.INTER_NEAREST)
    return orientation_field(small_a), orientation_field(warped), valid > 0


def block_agreement(
    rgb: list[np.ndarray],
    thermal: list[np.ndarray],
    matrix: np.ndarray,
    *,
    longer: int = 320,
    grid: tuple[int, int] = (4, 4),
    search: float = 0.06,
    radius: float = 2.0,
    min_energy: float = 0.02,
) -> BlockAgreement:
    """Count the blocks of the view whose own best shift agrees with ``matrix``.

    Parameters
    ----------
    rgb, thermal : equally long lists of float32 grey frames in [0, 1] (one size per side); the correlation surfaces
        of all pairs are summed per block, so a video votes with every pair.
    matrix : RGB->thermal homography, full-resolution pixels.
    longer : longer RGB side at which the blocks are compared.
    grid : blocks across and down the shared view.
    search : largest shift searched per block, as a fraction of ``longer`` (level pixels).
    radius : a block agrees when its peak lies within this many level pixels of zero shift.
    min_energy : a block is textured when the mean squared orientation magnitude of both fields exceeds this.

    Notes
    -----
    Only blocks inside the warped thermal view are scored, and only at shifts that keep them inside it (beyond lies
    mirrored border, whose copies of edges near the boundary could draw a block's peak away).
    """
    if len(rgb) != len(thermal):
        raise InputError(f"got {len(rgb)} RGB frames but {len(thermal)} thermal frames; pair them first")
    reach = max(2, int(round(search * longer)))
    surfaces: dict[tuple[int, int], np.ndarray] = {}
    counts: dict[tuple[int, int], int] = {}  # frame pairs that scored each block
    for a, t in zip(rgb, thermal):
        field_a, field_t, valid = _warped_fields(a, t, matrix, longer)
        rows, cols = np.nonzero(valid)
        if rows.size == 0:
            continue
        y0, y1, x0, x1 = rows.min() + reach, rows.max() - reach, cols.min() + reach, cols.max() - reach
        if y1 - y0 < 4 * grid[1] or x1 - x0 < 4 * grid[0]:
            continue
        ys = np.linspace(y0, y1, grid[1] + 1).astype(int)
        xs = np.linspace(x0, x1, grid[0] + 1).astype(int)
        for i in range(grid[1]):
            for j in range(grid[0]):
                ya, yb, xa, xb = ys[i], ys[i + 1], xs[j], xs[j + 1]
                if not valid[ya:yb, xa:xb].all():
                    continue
                template = field_a[ya:yb, xa:xb]
                region = field_t[ya - reach:yb + reach, xa - reach:xb + reach]
                energy = min(float((template ** 2).sum(2).mean()), float((region ** 2).sum(2).mean()))
                if energy < min_energy:
                    continue
                surface = cv2.matchTemplate(region, template, cv2.TM_CCOEFF_NORMED)
                # shifts whose window reaches outside the thermal view would compare with mirrored border: never a peak
                window = np.ones(template.shape[:2], np.float32)
                inside = cv2.matchTemplate(valid[ya - reach:yb + reach, xa - reach:xb + reach].astype(np.float32),
                                           window, cv2.TM_CCORR)
                surface[inside < window.size - 0.5] = -1.0
                surfaces[(i, j)] = surfaces.get((i, j), 0) + surface
                counts[(i, j)] = counts.get((i, j), 0) + 1
    shifts, peaks = [], []
    for key, surface in surfaces.items():
        surface = surface / counts[key]
        iy, ix = np.unravel_index(int(np.argmax(surface)), surface.shape)
        shifts.append((ix - reach, iy - reach))
        peaks.append(float(surface[iy, ix]))
    shifts_arr = np.array(shifts, float).reshape(-1, 2)
    agreeing = int((np.hypot(shifts_arr[:, 0], shifts_arr[:, 1]) <= radius).sum())
    return BlockAgreement(agreeing, len(shifts), shifts_arr, np.array(peaks))
