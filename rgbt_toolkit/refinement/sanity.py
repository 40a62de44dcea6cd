"""The authors' sanity limits on a refined box, shared by the regressor and the detector refiner.

The public JMMAC code accepts a detector box only when it changes the tracker's box by a plausible amount; the same
limits guard our frame-1 regressor, whose linear model can extrapolate wildly on a frame unlike the first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rgbt_toolkit.refinement.boxes import centres


@dataclass(frozen=True)
class SanityLimits:
    """Largest change of the tracker's box a refinement may make (authors' code, detector refinement)."""

    max_area_ratio: float = 2.5  # new area / old area (or its inverse) below this
    max_aspect_change: float = 3.0  # (new w/h) / (old w/h) (or its inverse) below this
    max_side_change: float = 1.5  # new w / old w and new h / old h (or their inverses) below this
    max_offset: float = 1.2  # |centre shift| per axis below this many times the old size (occluded)
    max_offset_visible: float = 0.9  # ... the same when the target is not occluded
    max_centre_distance: float = 40.0  # pixels, Euclidean centre shift when not occluded


def _ratio(a: float, b: float) -> float:
    """``max(a/b, b/a)`` for positive ``a``, ``b``."""
    return max(a / b, b / a)


def check_correction(old: np.ndarray, new: np.ndarray, limits: SanityLimits = SanityLimits(),
                     occluded: bool = False) -> str | None:
    """Why ``new`` is not an acceptable refinement of ``old`` (None when it is).

    Parameters
    ----------
    old, new : numpy.ndarray
        ``[x, y, w, h]`` before and after refinement.
    limits : SanityLimits
    occluded : bool
        The tracker considers the target occluded: only the looser limits apply (the authors' rule).

    Returns
    -------
    str or None
        A short reason such as ``"area ratio 3.1 >= 2.5"``, or None.
    """
    old, new = np.asarray(old, dtype=float), np.asarray(new, dtype=float)
    if not np.all(np.isfinite(new)) or new[2] <= 0 or new[3] <= 0:
        return "degenerate box"
    area = _ratio(new[2] * new[3], old[2] * old[3])
    if area >= limits.max_area_ratio:
        return f"area ratio {area:.2f} >= {limits.max_area_ratio}"
    aspect = _ratio(new[2] / new[3], old[2] / old[3])
    if aspect >= limits.max_aspect_change:
        return f"aspect change {aspect:.2f} >= {limits.max_aspect_change}"
    side = max(_ratio(new[2], old[2]), _ratio(new[3], old[3]))
    if side >= limits.max_side_change:
        return f"side change {side:.2f} >= {limits.max_side_change}"
    shift = np.abs(centres(new) - centres(old))
    offset = float(np.max(shift / old[2:]))
    bound = limits.max_offset if occluded else limits.max_offset_visible
    if offset >= bound:
        return f"offset {offset:.2f} sizes >= {bound}"
    if not occluded:
        dist = float(np.hypot(*shift))
        if dist >= limits.max_centre_distance:
            return f"centre moved {dist:.1f} px >= {limits.max_centre_distance}"
    return None
