"""What real cameras add to a frame (real_sensor challenge): fixed-pattern noise, vignetting, dead and hot pixels,
temporal noise, codec blocking and a burned-in on-screen timestamp.

The fixed parts (stripes, vignetting, defect positions) are drawn once per camera and kept, as a sensor's are; the
temporal parts are drawn per frame from the frame's own random stream.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

CODEC_QUALITY = 30  # JPEG quality per frame: 8x8 blocking like a low-bit-rate H.264 stream
DEFECT_FRACTION = 1 / 4000  # share of pixels that are dead (0) or hot (255)


@dataclass(frozen=True)
class SensorPattern:
    """The fixed imperfections of one camera."""

    offset: np.ndarray  # (H, W) float32 grey levels added to every frame: column stripes + vignetting
    drift: np.ndarray  # (H, W) float32 a left-right gradient whose weight drifts slowly with time (thermal only)
    defect_rows: np.ndarray
    defect_cols: np.ndarray
    defect_values: np.ndarray  # uint8 0 (dead) or 255 (hot)
    label: str  # camera name burned into the overlay


def make_pattern(size: tuple[int, int], thermal: bool, rng: np.random.Generator) -> SensorPattern:
    """Draw one camera's fixed pattern: microbolometers have strong column stripes, CMOS mostly vignetting."""
    w, h = size
    ys, xs = np.mgrid[0:h, 0:w].astype(np.float32)
    radius2 = ((xs - (w - 1) / 2) / (w / 2)) ** 2 + ((ys - (h - 1) / 2) / (h / 2)) ** 2
    if thermal:
        stripes = rng.normal(0, 4.0, w).astype(np.float32)[None, :]
        offset = stripes + 10.0 * (1 - 0.5 * radius2)  # column offsets and a warm centre (narcissus)
        drift = (xs / max(w - 1, 1) - 0.5) * 16.0
    else:
        offset = -28.0 * radius2 / 2  # lens vignetting: corners darker
        drift = np.zeros_like(xs)
    n = max(3, int(round(w * h * DEFECT_FRACTION)))
    rows, cols = rng.integers(h // 6, h, n), rng.integers(0, w, n)  # below the overlay band
    values = np.where(rng.random(n) < 0.5, 0, 255).astype(np.uint8)
    return SensorPattern(offset.astype(np.float32), drift.astype(np.float32), rows, cols, values,
                         "IR" if thermal else "EO")


def overlay_text(image: np.ndarray, t: float, frame_index: int, label: str) -> np.ndarray:
    """Burn a telemetry line (camera, frame counter, timestamp) into the top-left corner, as recorders do."""
    h, w = image.shape[:2]
    seconds = 3600 * 14 + 22 * 60 + t
    text = (f"{label} {int(seconds // 3600):02d}:{int(seconds // 60 % 60):02d}:{seconds % 60:05.2f} "
            f"#{frame_index:05d}")
    width_at_1 = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 1.0, 1)[0][0]
    scale = max(0.25, min(h / 600, 0.7 * w / width_at_1))  # readable, within the left 70 % of the frame
    origin = (3, 3 + int(22 * scale))
    white, black = (255, 255, 255) if image.ndim == 3 else 255, (0, 0, 0) if image.ndim == 3 else 0
    out = image.copy()
    cv2.putText(out, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, black, 3, cv2.LINE_AA)
    cv2.putText(out, text, origin, cv2.FONT_HERSHEY_SIMPLEX, scale, white, 1, cv2.LINE_AA)
    return out


def apply_sensor(image: np.ndarray, pattern: SensorPattern, t: float, frame_index: int,
                 rng: np.random.Generator) -> np.ndarray:
    """Add the pattern, temporal and row noise, the overlay and codec blocking; defects last, so they stay fixed."""
    value = image.astype(np.float32)
    fixed = pattern.offset + np.sin(0.4 * t) * pattern.drift
    value = value + (fixed[:, :, None] if value.ndim == 3 else fixed)
    row_noise = rng.normal(0, 1.5, (value.shape[0], 1)).astype(np.float32)
    noise = rng.normal(0, 3.0, value.shape).astype(np.float32)
    value = value + noise + (row_noise[:, :, None] if value.ndim == 3 else row_noise)
    frame = overlay_text(np.clip(value, 0, 255).astype(np.uint8), t, frame_index, pattern.label)
    ok, data = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, CODEC_QUALITY])
    frame = cv2.imdecode(data, cv2.IMREAD_UNCHANGED)
    frame[pattern.defect_rows, pattern.defect_cols] = (pattern.defect_values[:, None] if frame.ndim == 3
                                                       else pattern.defect_values)
    return frame
