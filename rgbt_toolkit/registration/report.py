"""Human-readable output of a registration: summary lines and the preview image (used by ``rgbt register``)."""

from __future__ import annotations

import os

import numpy as np

from rgbt_toolkit.errors import RegistrationError
from rgbt_toolkit.registration.apply import preview
from rgbt_toolkit.registration.calib import Calibration
from rgbt_toolkit.registration.pipeline import Registration
from rgbt_toolkit.registration.spatial import SpatialSettings
from rgbt_toolkit.registration.transforms import decompose


def summary_lines(result: Registration) -> list[str]:
    """A few lines: the matrix, its decomposition, quality, time offset and pairing."""
    cal = result.calibration
    parts = decompose(cal.matrix)
    rows = ["RGB -> thermal " + cal.model + ":"]
    rows += ["  [" + "  ".join(f"{v:12.6g}" for v in row) + " ]" for row in cal.matrix]
    rows.append(
        f"  scale {parts['scale']:.4f}, rotation {parts['rotation_deg']:+.2f} deg, shift "
        f"({parts['shift_x']:+.1f}, {parts['shift_y']:+.1f}) px; RGB {cal.rgb_size[0]}x{cal.rgb_size[1]} -> "
        f"thermal {cal.thermal_size[0]}x{cal.thermal_size[1]}"
    )
    rows.append(
        f"quality {cal.quality:.3f} (edge-orientation correlation: 0 chance, 1 identical), peak ratio "
        f"{cal.peak_ratio:.2f}, overlap {cal.overlap:.0%}, {cal.pairs_used} frame pair(s)"
    )
    rows.append(evidence_line(result.spatial.details))
    if result.offset is not None:
        rows.append(
            f"time offset {cal.time_offset:+.3f} s (thermal = RGB + offset; motion correlation "
            f"{result.offset.correlation:.2f}, z {result.offset.significance:.1f}; next peak "
            f"{result.offset.runner_up:.2f}, z {result.offset.next_significance:.1f})"
        )
    else:
        rows.append("time offset +0.000 s (not estimated; pass --sync for videos)")
    rows.append(
        f"pairing: {len(result.pairing)} pairs from {result.rgb_frames} RGB and {result.thermal_frames} thermal "
        f"frames (max gap {np.abs(result.pairing.gap).max(initial=0) * 1000:.1f} ms)"
    )
    return rows


def evidence_line(details: dict, clear_match: float = SpatialSettings.min_evidence) -> str:
    """Why the estimate was trusted: its evidence, and the blocks or second look it needed.

    ``clear_match`` is the evidence accepted without further checks (``SpatialSettings.min_evidence``).
    """
    if "evidence" not in details:
        return "evidence: not recorded"
    line = f"evidence {details['evidence']:.2f} (similarity fit x coarse z; {clear_match:g} or more is a clear match)"
    if "blocks_agreeing" in details:
        line += f", {details['blocks_agreeing']} of {details.get('blocks_textured', '?')} blocks agree on their own"
    if details.get("second_look") is True:
        line += "; found on a second look with locally equalised contrast (night scene)"
    return line


def write_preview(path: str | os.PathLike, rgb_path, thermal_path, calibration: Calibration, *,
                  mode: str = "checkerboard", fps: float | None = None) -> None:
    """Check image from the first time-paired frames of the two sources, written atomically as an image file."""
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.io.images import write_image

    rgb_frame = thermal_frame = None
    for frame, t in open_frames(rgb_path, fps=fps):
        rgb_frame, rgb_t = frame, t
        break
    best = None
    for frame, t in open_frames(thermal_path, fps=fps):
        gap = abs(t - (rgb_t + calibration.time_offset))
        if best is None or gap < best:
            best, thermal_frame = gap, frame
        elif gap > best:
            break
    if rgb_frame is None or thermal_frame is None:
        raise RegistrationError("no frames to draw the preview from")
    write_image(path, preview(rgb_frame, thermal_frame, calibration, mode=mode))
