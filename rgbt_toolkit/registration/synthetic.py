"""Test pairs with a known RGB->thermal transform, from real aligned pairs or from a procedural scene.

Used by the tests and by ``benchmarks/bench_registration.py``. A real aligned (visible, infrared) pair becomes a
registration problem by warping the infrared image with a random similarity and cropping the largest centred
rectangle that holds only valid pixels, as a narrower thermal camera would see it; the truth is the warp composed with
the crop. The procedural scene needs no data: random blobs and bars, rendered once as "visible" and once with an
inverted, non-linear intensity map as "thermal".
"""

from __future__ import annotations

import cv2
import numpy as np

from rgbt_toolkit.registration.transforms import similarity


def random_similarity(rng: np.random.Generator, size: tuple[int, int], *, scale=(0.8, 1.25), max_rotation_deg=5.0,
                      max_shift=0.1) -> np.ndarray:
    """Random similarity about the image centre: log-uniform scale, uniform rotation, shift up to a size fraction."""
    w, h = size
    s = float(np.exp(rng.uniform(np.log(scale[0]), np.log(scale[1]))))
    angle = float(np.deg2rad(rng.uniform(-max_rotation_deg, max_rotation_deg)))
    shift = (rng.uniform(-max_shift, max_shift) * w, rng.uniform(-max_shift, max_shift) * h)
    centre = ((w - 1) / 2, (h - 1) / 2)
    return similarity(s, angle, centre, centre, shift)


def rig_homography(size: tuple[int, int], *, hfov_deg: float, yaw_deg: float, pitch_deg: float) -> np.ndarray:
    """Image-to-image homography ``K R K^-1`` of a camera turned by a small yaw and pitch about its centre.

    Why: two cameras of a real rig are rarely parallel; a relative yaw/pitch of a degree or two adds a perspective
    (keystone) term that no similarity captures. ``K`` is a pinhole with the focal length of ``hfov_deg`` at the
    image's width and the principal point at its centre.
    """
    w, h = size
    f = (w / 2) / np.tan(np.deg2rad(hfov_deg) / 2)
    k = np.array([[f, 0, (w - 1) / 2], [0, f, (h - 1) / 2], [0, 0, 1.0]])
    yaw, pitch = np.deg2rad(yaw_deg), np.deg2rad(pitch_deg)
    r_yaw = np.array([[np.cos(yaw), 0, np.sin(yaw)], [0, 1, 0], [-np.sin(yaw), 0, np.cos(yaw)]])
    r_pitch = np.array([[1, 0, 0], [0, np.cos(pitch), -np.sin(pitch)], [0, np.sin(pitch), np.cos(pitch)]])
    matrix = k @ r_pitch @ r_yaw @ np.linalg.inv(k)
    return matrix / matrix[2, 2]


def random_rig_warp(rng: np.random.Generator, size: tuple[int, int], *, max_tilt_deg: float = 1.5,
                    hfov_deg: tuple[float, float] = (50.0, 70.0), **similarity_ranges) -> np.ndarray:
    """Random rig geometry: a random similarity (:func:`random_similarity`) after a relative yaw and pitch.

    Yaw and pitch are uniform in +-``max_tilt_deg``, seen through a lens of a uniform horizontal field of view in
    ``hfov_deg`` at the image's native width (perspective terms of about 1e-5 to 5e-5 per pixel).
    """
    tilt = rig_homography(size, hfov_deg=float(rng.uniform(*hfov_deg)),
                          yaw_deg=float(rng.uniform(-max_tilt_deg, max_tilt_deg)),
                          pitch_deg=float(rng.uniform(-max_tilt_deg, max_tilt_deg)))
    matrix = random_similarity(rng, size, **similarity_ranges) @ tilt
    return matrix / matrix[2, 2]


def narrower_view(image: np.ndarray, matrix: np.ndarray, *, fov_fraction: float, size: tuple[int, int]):
    """Crop the centre ``fov_fraction`` of ``image``'s width (aspect of ``size``) and resize it to ``size``.

    Why: a thermal camera beside a wider visible one sees a narrower field of view at a different resolution (a
    640x512 core beside a 1080p visible camera). ``matrix`` maps some frame to ``image``'s pixels; returns the new
    image and the matrix from that frame to the new image's pixels.
    """
    h, w = image.shape[:2]
    out_w, out_h = size
    crop_w = min(w, fov_fraction * w)
    crop_h = min(h, crop_w * out_h / out_w)
    crop_w = crop_h * out_w / out_h
    x0, y0 = (w - crop_w) / 2, (h - crop_h) / 2
    # crop box [x0, x0 + crop_w] (outer pixel edges) -> [0, out_w]; pixel centres per cv2.resize's convention
    fx, fy = out_w / crop_w, out_h / crop_h
    to_out = np.array([[fx, 0, fx * (0.5 - x0) - 0.5], [0, fy, fy * (0.5 - y0) - 0.5], [0, 0, 1.0]])
    if fx < 1:  # shrinking: low-pass first, as a lower-resolution sensor would
        image = cv2.GaussianBlur(image, (0, 0), 0.5 / fx)
    out = cv2.warpPerspective(image, to_out, (out_w, out_h), flags=cv2.INTER_LINEAR)
    return out, to_out @ matrix


def largest_centred_box(valid: np.ndarray) -> tuple[int, int, int, int]:
    """(x0, y0, x1, y1) of the largest rectangle of the image's aspect, centred on the valid area, holding only
    valid (non-zero) pixels of the uint8 mask ``valid``."""
    h, w = valid.shape
    ys, xs = np.nonzero(valid)
    if ys.size == 0:
        return 0, 0, 0, 0
    cy, cx = int(np.median(ys)), int(np.median(xs))
    integral = cv2.integral((valid == 0).astype(np.uint8))

    def box(fraction):
        hw, hh = fraction * w / 2, fraction * h / 2
        return int(cx - hw), int(cy - hh), int(cx + hw), int(cy + hh)

    def fits(x0, y0, x1, y1):
        inside = x0 >= 0 and y0 >= 0 and x1 <= w and y1 <= h
        return inside and integral[y1, x1] - integral[y0, x1] - integral[y1, x0] + integral[y0, x0] == 0

    lo, hi = 0.0, 1.0  # binary search on the rectangle's size
    for _ in range(20):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if fits(*box(mid)) else (lo, mid)
    return box(lo)


def warp_and_crop(image: np.ndarray, matrix: np.ndarray, *, min_size: int = 32) -> tuple[np.ndarray, np.ndarray]:
    """Warp ``image`` by ``matrix`` and crop the largest centred all-valid rectangle.

    Returns the cropped image and the matrix from the input's pixels to the crop's pixels.
    """
    h, w = image.shape[:2]
    warped = cv2.warpPerspective(image, matrix, (w, h), flags=cv2.INTER_LINEAR)
    valid = cv2.warpPerspective(np.ones((h, w), np.uint8), matrix, (w, h), flags=cv2.INTER_NEAREST)
    x0, y0, x1, y1 = largest_centred_box(cv2.erode(valid, np.ones((3, 3), np.uint8)))
    if x1 - x0 < min_size or y1 - y0 < min_size:
        raise ValueError("warp leaves too small a valid region")
    crop = np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1.0]])
    return warped[y0:y1, x0:x1], crop @ matrix


def warp_onto_canvas(image: np.ndarray, matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Warp ``image`` by ``matrix`` onto a canvas just large enough to hold the whole warped view (zero fill).

    Returns the canvas and the matrix from the input's pixels to the canvas's. Why: cropping a warped view to its
    valid rectangle loses a different part of the scene for every warp, and on real pairs (parallax, lens distortion)
    the best transform depends on the part in view; with the whole view kept, a registration of the warped pair and
    one of the unwarped pair see the same content, so the warp composed with the latter is the exact truth of the
    former whatever the scene's depth.
    """
    h, w = image.shape[:2]
    outline = cv2.perspectiveTransform(np.array([[[0, 0], [w, 0], [w, h], [0, h]]], np.float64), matrix)[0]
    x0, y0 = np.floor(outline.min(axis=0))
    x1, y1 = np.ceil(outline.max(axis=0))
    to_canvas = np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1.0]]) @ matrix
    canvas = cv2.warpPerspective(image, to_canvas, (int(x1 - x0), int(y1 - y0)), flags=cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return canvas, to_canvas / to_canvas[2, 2]


def same_content_box(truth: np.ndarray, source_shape: tuple[int, int], crop_shape: tuple[int, int]):
    """Box (x0, y0, x1, y1) of the *unwarped* image showing about what the warped crop shows.

    ``truth`` maps source pixels to crop pixels (as :func:`warp_and_crop` returns it). Registering the unwarped pair
    on this box instead of the whole image gives a reference that saw the same part of the scene as the warped crop,
    which separates errors of recovering the warp from the scene's own departure from a similarity (parallax, lens
    distortion), whose best fit depends on the part of the view in sight.
    """
    h, w = source_shape
    seen = cv2.warpPerspective(np.ones(crop_shape, np.uint8), np.linalg.inv(truth), (w, h), flags=cv2.INTER_NEAREST)
    return largest_centred_box(cv2.erode(seen, np.ones((3, 3), np.uint8)))


def rig_view_crop(image: np.ndarray, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """The part of ``image`` a random rig warp (:func:`random_rig_warp`, same draw) leaves in sight, cut out unwarped.

    Returns the crop and the matrix from ``image``'s pixels to the crop's (a translation). Why: a registration
    benchmark that warps one image of a real pair measures against a reference registered on the whole view; on
    pairs that are not one homography apart a fit on less of the view lands elsewhere. An integer crop is the
    easiest "warp" there is, so what crops lose against that reference is the reference's part of the error.
    """
    h, w = image.shape[:2]
    warped, truth = warp_and_crop(image, random_rig_warp(rng, (w, h)))
    x0, y0, x1, y1 = same_content_box(truth, (h, w), warped.shape[:2])
    return image[y0:y1, x0:x1], np.array([[1, 0, -x0], [0, 1, -y0], [0, 0, 1.0]])


def procedural_scene(rng: np.random.Generator, size: tuple[int, int] = (320, 240)) -> tuple[np.ndarray, np.ndarray]:
    """A textured scene as an aligned (visible uint8 RGB, thermal uint8 grey) pair with unrelated intensities."""
    w, h = size
    labels = np.zeros((h, w), np.int32)
    for k in range(1, 40):
        colour_id = k
        if rng.random() < 0.5:
            centre = (int(rng.uniform(0, w)), int(rng.uniform(0, h)))
            axes = (int(rng.uniform(5, w / 6)), int(rng.uniform(5, h / 6)))
            cv2.ellipse(labels, centre, axes, float(rng.uniform(0, 180)), 0, 360, colour_id, -1)
        else:
            x0, y0 = int(rng.uniform(0, w)), int(rng.uniform(0, h))
            cv2.rectangle(labels, (x0, y0), (x0 + int(rng.uniform(8, w / 4)), y0 + int(rng.uniform(8, h / 4))),
                          colour_id, -1)
    vis_value = rng.uniform(0, 1, 40)
    th_value = rng.uniform(0, 1, 40)
    base_v = vis_value[labels]
    base_t = th_value[labels]
    # thermal: inverted, gamma-distorted region temperatures, blurrier optics and its own noise
    thermal = 1.0 - base_t ** 2.2
    thermal = cv2.GaussianBlur(thermal.astype(np.float32), (0, 0), 1.2) + rng.normal(0, 0.02, (h, w))
    tint = rng.uniform(0.6, 1.0, 3)
    visible = base_v[..., None] * tint + rng.normal(0, 0.02, (h, w, 3))
    to8 = lambda x: np.clip(x * 255, 0, 255).astype(np.uint8)  # noqa: E731
    return to8(visible), to8(thermal)
