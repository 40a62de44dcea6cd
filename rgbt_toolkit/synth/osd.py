"""Each camera's on-screen display (OSD), burned into its frames as real rigs do (the ``overlays`` challenge).

A gimbal rig's visible and thermal cameras each draw their own OSD: the date and time at the top right, the camera's
name and its azimuth / elevation at the top left, each in that camera's own font, size and margins; the visible
camera also draws a white reticle of corner brackets around the image centre. The OSD is fixed in the frame while the
scene moves behind it, and it is the only structure two views of an empty sky share, which is what makes it a trap
for registration (docs/registration.md, "Overlays"). The ground truth does not change: the OSD is drawn over the
picture, never over the target's truth.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class OsdStyle:
    """How one camera draws its OSD; sizes are fractions of the frame height so any resolution gets the same look."""

    name: str  # the camera's name, drawn top left
    font: int  # a cv2 Hershey font
    height: float  # text cap height, fraction of the frame height
    margin: tuple[float, float]  # (x, y) margin of the text from the frame corner, fractions of the frame height
    reticle: bool  # corner brackets around the image centre


# the two cameras' OSDs differ in font, size and margins, as two makers' firmware do
STYLES: dict[str, OsdStyle] = {
    "rgb": OsdStyle("EO-1 DAY", cv2.FONT_HERSHEY_SIMPLEX, 0.035, (0.03, 0.03), True),
    "t": OsdStyle("IR-1 LWIR", cv2.FONT_HERSHEY_PLAIN, 0.045, (0.05, 0.06), False),
}
START_SECONDS = 3600 * 21 + 14 * 60 + 5  # the clock drawn at scene time 0: 21:14:05
RETICLE_SIZE = (0.22, 0.18)  # the reticle's (half width, half height) as fractions of the frame height
RETICLE_ARM = 0.35  # each bracket's arm as a fraction of the reticle's half height


def osd_lines(t: float, modality: str) -> tuple[str, str, str]:
    """The OSD's three text lines at scene time ``t``: the clock (whole seconds), the camera's name, az / el."""
    seconds = int(START_SECONDS + np.floor(t))
    clock = f"2026-12-06 {seconds // 3600 % 24:02d}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"
    return clock, STYLES[modality].name, f"AZ {123.4 + 0.1 * np.floor(t):05.1f} EL {-2.5:+05.1f}"


def _text_scale(style: OsdStyle, frame_height: int) -> float:
    """cv2's font scale that gives ``style.height`` of the frame height as the cap height."""
    cap = cv2.getTextSize("0", style.font, 1.0, 1)[0][1]
    return style.height * frame_height / cap


def draw_osd(image: np.ndarray, t: float, modality: str) -> np.ndarray:
    """``image`` with camera ``modality``'s OSD at scene time ``t`` drawn in white (a copy; grey or colour)."""
    style = STYLES[modality]
    out = image.copy()
    h, w = out.shape[:2]
    white = (255, 255, 255) if out.ndim == 3 else 255
    scale = _text_scale(style, h)
    thickness = max(1, int(round(scale * (1.2 if style.font == cv2.FONT_HERSHEY_PLAIN else 1.6))))
    mx, my = int(style.margin[0] * h), int(style.margin[1] * h)
    clock, name, angles = osd_lines(t, modality)
    (cw, ch), _ = cv2.getTextSize(clock, style.font, scale, thickness)
    line = int(1.6 * ch)
    cv2.putText(out, clock, (w - mx - cw, my + ch), style.font, scale, white, thickness, cv2.LINE_AA)
    cv2.putText(out, name, (mx, my + ch), style.font, scale, white, thickness, cv2.LINE_AA)
    cv2.putText(out, angles, (mx, my + ch + line), style.font, scale, white, thickness, cv2.LINE_AA)
    if style.reticle:
        _draw_reticle(out, white, max(1, int(round(0.004 * h))))
    return out


def _draw_reticle(image: np.ndarray, colour, thickness: int) -> None:
    """Four corner brackets around the image centre, in place."""
    h, w = image.shape[:2]
    cx, cy = w / 2, h / 2
    hx, hy = RETICLE_SIZE[0] * h, RETICLE_SIZE[1] * h
    arm = RETICLE_ARM * hy
    for sx in (-1, 1):
        for sy in (-1, 1):
            corner = (int(round(cx + sx * hx)), int(round(cy + sy * hy)))
            cv2.line(image, corner, (int(round(corner[0] - sx * arm)), corner[1]), colour, thickness, cv2.LINE_AA)
            cv2.line(image, corner, (corner[0], int(round(corner[1] - sy * arm))), colour, thickness, cv2.LINE_AA)


def osd_pixels(size: tuple[int, int], t: float, modality: str) -> np.ndarray:
    """Boolean (H, W) mask of the pixels camera ``modality``'s OSD touches at time ``t`` in a (width, height) frame:
    the truth an overlay detector is measured against."""
    blank = np.zeros((size[1], size[0]), np.uint8)
    return draw_osd(blank, t, modality) > 0
