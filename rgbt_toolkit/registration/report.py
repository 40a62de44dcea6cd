"""Human-readable output of a registration: summary lines and the preview image (used by ``rgbt register``)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from rgbt_toolkit._atomic import check_writable
from rgbt_toolkit.errors import InputError, RegistrationError
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
    elif cal.time_offset != 0:
        rows.append(f"time offset {cal.time_offset:+.3f} s (given; thermal = RGB + offset)")
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


def check_outputs(output, preview=None, inputs=(), *, force: bool = False) -> None:
    """Refuse unusable output paths before a long registration runs (one line naming the path as given).

    ``output`` is the calibration JSON, ``preview`` the optional check image; ``inputs`` are the recordings, which
    neither may overwrite (nor may a preview land inside an input frame folder, where it would become a frame).
    """
    from rgbt_toolkit.io.images import IMAGE_SUFFIXES

    if preview is not None and Path(preview).suffix.lower() not in IMAGE_SUFFIXES:
        raise InputError(f"{preview}: the preview is an image; give it one of the suffixes {', '.join(IMAGE_SUFFIXES)}")
    targets = [(output, "calibration")] + ([(preview, "preview")] if preview is not None else [])
    if preview is not None and _same(output, preview):
        raise InputError(f"{output}: the calibration and the preview cannot be the same file")
    for path, what in targets:
        for source in inputs:
            if _same(path, source):
                raise InputError(f"{path}: the {what} would overwrite an input recording; choose another name")
            if what == "preview" and Path(source).is_dir() and Path(path).resolve().parent == Path(source).resolve():
                raise InputError(f"{path}: the preview would become a frame of the input folder {source}")
        check_writable(path, what, overwrite=force)


def _same(a, b) -> bool:
    return Path(a).resolve() == Path(b).resolve()


def _frame_at(path, t: float, *, fps: float | None, grey: bool) -> np.ndarray | None:
    """The frame of a recording nearest to time ``t`` (stops reading once past it)."""
    from rgbt_toolkit.io.frames import open_frames

    best, best_gap = None, np.inf
    for frame, ft in open_frames(path, fps=fps, grey=grey):
        gap = abs(ft - t)
        if gap < best_gap:
            best, best_gap = frame, gap
        elif ft > t:
            break
    return best


def write_preview(path: str | os.PathLike, rgb_path, thermal_path, calibration: Calibration, *,
                  times: tuple[float, float] | None = None, mode: str = "checkerboard", fps: float | None = None,
                  rgb_fps: float | None = None, thermal_fps: float | None = None) -> None:
    """Check image of one frame pair, written atomically as an image file.

    ``times`` are the (RGB, thermal) timestamps of a pair the estimate used (``Registration.preview_times``), so the
    picture shows what was registered; without them the first RGB frame and its partner under the calibration's
    offset are drawn. The thermal frame is read grey at its full bit depth (16-bit thermal stretched for display).
    """
    from rgbt_toolkit.io.images import write_image

    rgb_t, thermal_t = times if times is not None else (0.0, calibration.time_offset)
    rgb_frame = _frame_at(rgb_path, rgb_t, fps=rgb_fps or fps, grey=False)
    thermal_frame = _frame_at(thermal_path, thermal_t, fps=thermal_fps or fps, grey=True)
    if rgb_frame is None or thermal_frame is None:
        raise RegistrationError("no frames to draw the preview from")
    write_image(path, preview(rgb_frame, thermal_frame, calibration, mode=mode))
