"""Render one synthetic scene through the RGB and the thermal camera at any time.

Objects are drawn into a world canvas (RGB reflectance and temperature) with anti-aliased signed-distance shapes, then
warped into each camera: RGB sees the world through the camera-motion affine A(t); thermal through H @ A(t), where H
is the fixed RGB->T homography of the rig. Ground-truth boxes are the extents of each object's exact outline under
the same transforms, so they are right to a fraction of a pixel in both cameras.

Box convention (as the benchmarks, and ECO's ``pos = xy + (sz - 1) / 2``): x, y is the first pixel column / row the
object touches; its continuous extent is [x - 0.5, x - 0.5 + w].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from rgbt_toolkit.registration.transforms import project
from rgbt_toolkit.synth.config import VISIBILITY_CHALLENGES, SceneConfig
from rgbt_toolkit.synth.osd import draw_osd
from rgbt_toolkit.synth.sensor import SensorPattern, apply_sensor, make_pattern
from rgbt_toolkit.synth.stream import SkipBlockStream
from rgbt_toolkit.synth.textures import rounded_rect_outline, rounded_rect_sdf, sky_background, world_background
from rgbt_toolkit.synth.timeline import Timeline, build_timeline

TARGET_TEMPERATURE = 0.92
TARGET_TOP = np.array([0.85, 0.15, 0.10], np.float32)  # red jacket
TARGET_BOTTOM = np.array([0.10, 0.15, 0.45], np.float32)  # blue trousers
THERMAL_DISTRACTOR_COLOUR = np.array([0.35, 0.42, 0.30], np.float32)
OCCLUDER_COLOUR = np.array([0.30, 0.35, 0.48], np.float32)
OCCLUDER_TEMPERATURE = 0.42
FAR_TARGET_COLOUR = np.array([0.12, 0.12, 0.14], np.float32)  # a dark drone body against the sky
FAR_TARGET_HALF_PX = ((6.0, 9.0), (5.0, 7.0))  # ranges of the far target's half (width, height), RGB pixels


@dataclass
class RenderedFrame:
    """One camera's frame with its truth."""

    image: np.ndarray  # RGB uint8 (H, W, 3) or thermal uint8 (H, W)
    box: np.ndarray  # x, y, w, h of the target in this camera
    time: float
    flags: dict[str, bool] = field(default_factory=dict)
    absent: bool = False  # no target pixel in this frame: wholly outside the view or wholly hidden


def _affine3(m: np.ndarray) -> np.ndarray:
    return np.vstack([m, [0.0, 0.0, 1.0]])


def outline_box(points: np.ndarray) -> np.ndarray:
    """x, y, w, h of a point set's extent in the first-pixel convention of the module docstring."""
    lo, hi = points.min(axis=0), points.max(axis=0)
    return np.array([lo[0] + 0.5, lo[1] + 0.5, hi[0] - lo[0], hi[1] - lo[1]])


def clip_box(box: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, bool]:
    """The part of ``box`` inside a ``size`` image, and whether none is: a wholly outside box becomes 0, 0, 0, 0
    (the benchmarks' row for an absent target)."""
    lo = np.maximum(box[:2] - 0.5, -0.5)
    hi = np.minimum(box[:2] - 0.5 + box[2:], np.array(size, float) - 0.5)
    if np.any(hi <= lo):
        return np.zeros(4), True
    return np.r_[lo + 0.5, hi - lo], False


class SceneRenderer:
    """A deterministic scene: the same config always renders the same frames."""

    def __init__(self, config: SceneConfig):
        self.config = config
        rng = np.random.default_rng(config.seed)
        w, h = config.rgb_size
        self.world_shape = (int(1.5 * h), int(1.5 * w))
        self.background_rgb, self.background_heat = world_background(self.world_shape, rng)
        self.timeline: Timeline = build_timeline(config, rng)
        self.target_half = 0.5 * np.array(config.target_size) * h
        self.h_rgb_to_t = self._rig_homography()
        self._noise_rng_seed = int(rng.integers(2**31))
        # fixed gain of the thermal camera, set as its AGC would for this scene: the coldest background at 10 grey
        # levels, the target's core at 250
        self._patterns: dict[str, SensorPattern] = {}
        self._streams: dict[str, SkipBlockStream] = {}
        self._new_challenge_parts(config)
        self._heat_low = float(np.percentile(self.background_heat, 1))
        self._heat_gain = 240.0 / (TARGET_TEMPERATURE - self._heat_low)

    def _new_challenge_parts(self, config: SceneConfig) -> None:
        """Sky, far target and sensor patterns, drawn from their own random stream so other scenes are unchanged."""
        rng = np.random.default_rng([config.seed, 20261202])
        if config.has("far_target"):
            self.background_rgb, self.background_heat = sky_background(self.world_shape, rng)
            self.target_half = np.array([rng.uniform(*FAR_TARGET_HALF_PX[0]), rng.uniform(*FAR_TARGET_HALF_PX[1])])
        if config.has("real_sensor"):
            self._patterns = {"rgb": make_pattern(config.rgb_size, False, rng),
                              "t": make_pattern(config.t_size, True, rng)}

    # ----- geometry -------------------------------------------------------------------------------------------
    def _rig_homography(self) -> np.ndarray:
        """RGB pixel -> thermal pixel: centre to centre, resolution and zoom, mounting roll, offset, slight keystone."""
        c = self.config
        (wr, hr), (wt, ht) = c.rgb_size, c.t_size
        k = c.t_zoom * wt / wr
        a = np.deg2rad(c.t_rotation_deg)
        to_centred = np.array([[1, 0, -(wr - 1) / 2], [0, 1, -(hr - 1) / 2], [0, 0, 1]])
        keystone = np.array([[1, 0, 0], [0, 1, 0], [c.t_keystone / wr, c.t_keystone / 3 / hr, 1]])
        rotate_scale = np.array([[k * np.cos(a), -k * np.sin(a), 0], [k * np.sin(a), k * np.cos(a), 0], [0, 0, 1]])
        to_thermal = np.array([[1, 0, (wt - 1) / 2 + c.t_shift[0]], [0, 1, (ht - 1) / 2 + c.t_shift[1]], [0, 0, 1]])
        return to_thermal @ rotate_scale @ keystone @ to_centred

    def camera_matrix(self, t: float) -> np.ndarray:
        """2x3 affine world -> RGB image at time ``t`` (camera motion)."""
        tl = self.timeline
        centre = tl.at("camera_centre", t)
        angle, zoom = tl.at("camera_angle", t), tl.at("camera_zoom", t)
        w, h = self.config.rgb_size
        rot = zoom * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        offset = np.array([(w - 1) / 2, (h - 1) / 2]) - rot @ centre
        return np.c_[rot, offset]

    def world_to_camera(self, t: float, modality: str) -> np.ndarray:
        """3x3 world -> image homography of one camera ('rgb' or 't')."""
        a = _affine3(self.camera_matrix(t))
        return a if modality == "rgb" else self.h_rgb_to_t @ a

    def target_box(self, t: float, modality: str) -> np.ndarray:
        """The target's exact box ``x, y, w, h`` in camera ``modality`` at time ``t``, unclipped, without rendering
        a frame (box-only evidence such as hand labels needs no pictures)."""
        return outline_box(project(self.world_to_camera(t, modality), self.target_outline(t)))

    def target_outline(self, t: float) -> np.ndarray:
        centre = self.timeline.at("target_xy", t)
        half = self.target_half * self.timeline.at("target_scale", t)
        return rounded_rect_outline(centre, half, 0.45 * half[0])

    # ----- scene state -----------------------------------------------------------------------------------------
    def _objects(self, t: float) -> list[dict]:
        """Objects to draw, back to front: distractors, target, occluder."""
        tl, cfg = self.timeline, self.config
        objects = []
        distractor = tl.at("distractor_xy", t)
        if not np.isnan(distractor).any():
            half = self.target_half * 0.95
            if cfg.has("distractor_color"):
                objects.append(dict(centre=distractor, half=half, top=TARGET_TOP, bottom=TARGET_BOTTOM,
                                    heat=self._local_heat(distractor)))
            if cfg.has("distractor_thermal"):
                mirrored = 2 * tl.at("camera_centre", 0.0) - distractor
                objects.append(dict(centre=mirrored, half=half, top=THERMAL_DISTRACTOR_COLOUR,
                                    bottom=THERMAL_DISTRACTOR_COLOUR, heat=TARGET_TEMPERATURE))
        if tl.crossing_xy is not None:  # passes behind the target
            crossing = tl.at("crossing_xy", t)
            half = self.target_half * 0.95 * tl.at("target_scale", t)
            if cfg.has("crossing_color"):
                objects.append(dict(centre=crossing, half=half, top=TARGET_TOP, bottom=TARGET_BOTTOM,
                                    heat=self._local_heat(crossing)))
            if cfg.has("crossing_thermal"):
                objects.append(dict(centre=crossing, half=half, top=THERMAL_DISTRACTOR_COLOUR,
                                    bottom=THERMAL_DISTRACTOR_COLOUR, heat=TARGET_TEMPERATURE))
        centre = tl.at("target_xy", t)
        heat = TARGET_TEMPERATURE + tl.at("crossover", t) * (self._local_heat(centre) - TARGET_TEMPERATURE)
        top, bottom = (FAR_TARGET_COLOUR, FAR_TARGET_COLOUR) if cfg.has("far_target") else (TARGET_TOP, TARGET_BOTTOM)
        turn = 0.0
        if cfg.has("appearance_change"):  # the other side shows gradually, from 20 % to 80 % of the sequence
            turn = float(np.clip((t / cfg.duration - 0.2) / 0.6, 0.0, 1.0))
            top, bottom = ((1 - turn) * np.asarray(top, float) + turn * np.asarray(bottom, float),
                           (1 - turn) * np.asarray(bottom, float) + turn * np.asarray(top, float))
        objects.append(dict(centre=centre, half=self.target_half * tl.at("target_scale", t), top=top,
                            bottom=bottom, heat=heat, is_target=True, turn=turn))
        for occluder in (self._occluder(t), self._long_occluder(t)):
            if occluder is not None:
                objects.append(occluder)
        return objects

    def _long_occluder(self, t: float) -> dict | None:
        """The long_occlusion vehicle: taller than the target at its largest, so alongside it hides it whole."""
        if self.timeline.long_occluder_xy is None:
            return None
        centre = self.timeline.at("long_occluder_xy", t)
        if np.isnan(centre).any():
            return None
        tallest = self.target_half[1] * float(self.timeline.target_scale.max())
        half = np.array([0.18 * self.config.rgb_size[0], 1.3 * tallest + 3])
        return dict(centre=centre, half=half, top=OCCLUDER_COLOUR, bottom=OCCLUDER_COLOUR * 0.7,
                    heat=OCCLUDER_TEMPERATURE, radius_fraction=0.15)

    def fully_hidden(self, t: float) -> bool:
        """True when the long_occlusion vehicle covers the target's whole outline (with a pixel of margin)."""
        occluder = self._long_occluder(t)
        if occluder is None:
            return False
        c, half = self.timeline.at("target_xy", t), self.target_half * self.timeline.at("target_scale", t)
        inner = occluder["half"] - occluder["radius_fraction"] * occluder["half"][0] - 1.0  # inside the round corners
        return bool(np.all(np.abs(c - occluder["centre"]) + half <= inner))

    def _occluder(self, t: float) -> dict | None:
        x = self.timeline.at("occluder_x", t)
        if np.isnan(x):
            return None
        y = self.timeline.at("target_xy", 0.5 * self.config.duration)[1]
        half = np.array([0.18 * self.config.rgb_size[0], 1.5 * self.target_half[1]])
        return dict(centre=np.array([x, y]), half=half, top=OCCLUDER_COLOUR, bottom=OCCLUDER_COLOUR * 0.7,
                    heat=OCCLUDER_TEMPERATURE, radius_fraction=0.15)

    def _local_heat(self, centre: np.ndarray) -> float:
        """Mean background temperature around a point (what a crossing target fades into)."""
        r = int(self.target_half[1] * 2)
        x, y = int(centre[0]), int(centre[1])
        patch = self.background_heat[max(0, y - r): y + r, max(0, x - r): x + r]
        return float(patch.mean()) if patch.size else 0.3

    def occlusion_fraction(self, t: float) -> float:
        """Fraction of the target's box area covered by the occluder's box (world coordinates)."""
        occluder = self._occluder(t)
        if occluder is None:
            return 0.0
        c, half = self.timeline.at("target_xy", t), self.target_half * self.timeline.at("target_scale", t)
        lo = np.maximum(c - half, occluder["centre"] - occluder["half"])
        hi = np.minimum(c + half, occluder["centre"] + occluder["half"])
        return float(np.prod(np.clip(hi - lo, 0, None)) / np.prod(2 * half))

    # ----- drawing -----------------------------------------------------------------------------------------------
    def _draw(self, rgb: np.ndarray | None, heat: np.ndarray | None, obj: dict) -> None:
        centre, half = obj["centre"], obj["half"]
        radius = obj.get("radius_fraction", 0.45) * half[0]
        x0, y0 = np.floor(centre - half - 2).astype(int)
        x1, y1 = np.ceil(centre + half + 2).astype(int)
        hh, ww = self.world_shape
        x0, y0, x1, y1 = max(x0, 0), max(y0, 0), min(x1, ww), min(y1, hh)
        if x1 <= x0 or y1 <= y0:
            return
        ys, xs = np.mgrid[y0:y1, x0:x1].astype(np.float32)
        alpha = np.clip(0.5 - rounded_rect_sdf(xs, ys, centre, half, radius), 0, 1)[:, :, None]
        if rgb is not None:
            upper = (ys < centre[1] + 0.1 * half[1])[:, :, None]
            # a turning target's stripes run across it by the end (appearance_change)
            turn = obj.get("turn", 0.0)
            phase = ((1 - turn) * (ys - centre[1]) / max(half[1], 1) + turn * (xs - centre[0]) / max(half[0], 1)) * 18
            stripes = 0.9 + 0.1 * np.sign(np.sin(phase))[:, :, None]
            colour = np.where(upper, obj["top"], obj["bottom"]) * stripes
            roi = rgb[y0:y1, x0:x1]
            roi[:] = roi * (1 - alpha) + colour * alpha
        if heat is not None:
            # a warm body is warmest in its core (and head), as a thermal camera sees a person
            radial = 1 - 0.1 * np.clip(((xs - centre[0]) / half[0]) ** 2 + ((ys - centre[1]) / half[1]) ** 2, 0, 2)
            value = obj["heat"] * radial if obj.get("is_target") else obj["heat"]
            roi = heat[y0:y1, x0:x1]
            roi[:] = roi * (1 - alpha[:, :, 0]) + value * alpha[:, :, 0]

    def _world(self, t: float, modality: str) -> np.ndarray:
        if modality == "rgb":
            canvas = self.background_rgb.copy()
            for obj in self._objects(t):
                self._draw(canvas, None, obj)
        else:
            canvas = self.background_heat.copy()
            for obj in self._objects(t):
                self._draw(None, canvas, obj)
        return canvas

    def render(self, t: float, modality: str, frame_index: int = 0) -> RenderedFrame:
        """Render camera ``modality`` ('rgb' or 't') at scene time ``t``."""
        cfg = self.config
        size = cfg.rgb_size if modality == "rgb" else cfg.t_size
        image = self._camera_image(t, modality, frame_index)
        if cfg.has("skip_blocks"):
            image = self._streamed(image, t, modality, frame_index)
        box = self.target_box(t, modality)
        flags = self.flags(t)
        if not cfg.challenges & VISIBILITY_CHALLENGES:
            return RenderedFrame(image, box, t, flags)
        box, outside = clip_box(box, size)
        flags["out_of_view"] = outside
        return RenderedFrame(image, box, t, flags, absent=outside or flags["long_occlusion"])

    def _camera_image(self, t: float, modality: str, frame_index: int) -> np.ndarray:
        """What camera ``modality`` records at scene time ``t``: the warped world through its sensor."""
        size = self.config.rgb_size if modality == "rgb" else self.config.t_size
        warped = cv2.warpPerspective(self._world(t, modality), self.world_to_camera(t, modality), size,
                                     flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        rng = np.random.default_rng((self._noise_rng_seed, frame_index, modality == "rgb"))
        image = self._sensor_rgb(warped, t, rng) if modality == "rgb" else self._sensor_thermal(warped, rng)
        if self._patterns:
            image = apply_sensor(image, self._patterns[modality], t, frame_index, rng)
        if self.config.has("overlays"):
            image = draw_osd(image, t, modality)
        return image

    def _streamed(self, image: np.ndarray, t: float, modality: str, frame_index: int) -> np.ndarray:
        """The picture a viewer of the low-bit-rate stream sees (skip_blocks). Frames asked for out of order are
        replayed from the last full refresh at this camera's frame rate, so the result does not depend on the order
        of the calls."""
        stream = self._streams.setdefault(modality, SkipBlockStream())
        if not stream.follows(frame_index):
            dt = 1.0 / (self.config.rgb_fps if modality == "rgb" else self.config.t_fps)
            for j in range(frame_index - frame_index % stream.gop, frame_index):
                stream.frame(self._camera_image(t - (frame_index - j) * dt, modality, j), j)
        return stream.frame(image, frame_index)

    def _sensor_rgb(self, reflectance: np.ndarray, t: float, rng: np.random.Generator) -> np.ndarray:
        light = self.timeline.at("light", t)
        grey = reflectance.mean(axis=2, keepdims=True)
        saturation = 0.3 + 0.7 * light  # colour fades at night
        image = (grey + saturation * (reflectance - grey)) * light * 255
        sigma = 1.5 + 8.0 * (1 - light)
        if self.config.has("degradation"):
            image = cv2.GaussianBlur(image, (0, 0), 1.2)
            sigma += 5.0
        image = image + rng.normal(0, sigma, image.shape).astype(np.float32)
        image = np.clip(image, 0, 255).astype(np.uint8)
        return self._compress(image) if self.config.has("degradation") else image

    def _sensor_thermal(self, heat: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        image = cv2.GaussianBlur(10 + self._heat_gain * (heat - self._heat_low), (0, 0), 0.8)  # softer optics
        sigma = 1.5 + (4.0 if self.config.has("degradation") else 0.0)
        if self.config.has("degradation"):
            image = cv2.GaussianBlur(image, (0, 0), 1.0)
        image = np.clip(image + rng.normal(0, sigma, image.shape).astype(np.float32), 0, 255).astype(np.uint8)
        return self._compress(image) if self.config.has("degradation") else image

    @staticmethod
    def _compress(image: np.ndarray) -> np.ndarray:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 25])
        return cv2.imdecode(data, cv2.IMREAD_UNCHANGED)

    # ----- truth ---------------------------------------------------------------------------------------------
    def flags(self, t: float) -> dict[str, bool]:
        """Per-frame challenge flags at time ``t`` (True while the challenge is in effect)."""
        tl, cfg = self.timeline, self.config
        dt = 1.0 / cfg.rgb_fps
        a_now, a_before = self.camera_matrix(t), self.camera_matrix(max(t - dt, 0.0))
        probe = np.array([[(cfg.rgb_size[0] - 1) / 2], [(cfg.rgb_size[1] - 1) / 2]])
        world_probe = np.linalg.solve(a_now[:, :2], probe - a_now[:, 2:])
        camera_shift = float(np.linalg.norm(a_before[:, :2] @ world_probe + a_before[:, 2:] - probe))
        target_step = float(np.linalg.norm(tl.at("target_xy", t) - tl.at("target_xy", max(t - dt, 0.0))))
        distractor = tl.at("distractor_xy", t)
        near = (not np.isnan(distractor).any()
                and float(np.linalg.norm(distractor - tl.at("target_xy", t))) < 4 * self.target_half[0])
        if tl.crossing_xy is not None:
            gap = float(np.linalg.norm(tl.at("crossing_xy", t) - tl.at("target_xy", t)))
            near = near or gap < 4 * self.target_half[0]
        scale_ratio = tl.at("target_scale", t)
        flags = {
            "occlusion": self.occlusion_fraction(t) > 0.3,
            "camera_motion": camera_shift > 3.0,
            "low_light": tl.at("light", t) < 0.5,
            "thermal_crossover": tl.at("crossover", t) > 0.6,
            "fast_motion": target_step > 0.6 * self.target_half[0] * 2,
            "scale_change": not (0.8 <= scale_ratio <= 1.25),
            "distractor": bool(near),
        }
        if cfg.challenges & VISIBILITY_CHALLENGES:
            flags["gimbal_jump"] = cfg.has("gimbal_jump") and camera_shift > 0.1 * cfg.rgb_size[0]
            flags["long_occlusion"] = self.fully_hidden(t)
        return flags
