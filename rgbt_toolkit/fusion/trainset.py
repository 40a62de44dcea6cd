"""Training pairs for MFNet made from real aligned visible/infrared images (e.g. RoadScene).

Each sample imitates two frames of a short RGB-T sequence (paper: "training pairs within an interval of 5 frames"):
an init frame, where the tracker learns the target, and a search frame 1-5 frames later, with camera motion, target
motion and a pasted target (a visible texture with a mask, warm in thermal). One modality is degraded so that the
right fusion weight differs from sample to sample:

- ``clean``: both modalities usable;
- ``rgb_dark``: night-time visible image (dim, noisy) in both frames -> trust thermal;
- ``rgb_glare``: a saturated glare blob over the target in the visible search frame -> trust thermal;
- ``t_crossover``: the target's thermal contrast vanishes in the search frame (thermal crossover) -> trust RGB;
- ``rgb_distractor`` / ``t_distractor``: a look-alike of the target in one modality only -> local weight matters.

Randomness comes only from the ``rng`` argument.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.images import read_image

KINDS = ("clean", "rgb_dark", "rgb_glare", "t_crossover", "rgb_distractor", "t_distractor")


@dataclass(frozen=True)
class SampleSettings:
    """How training pairs are drawn (values chosen to resemble GTOT/RGBT234 search regions)."""

    patch: int = 200  # paper: 200x200 patches
    target_min: int = 28  # target side range in patch pixels (search region ~ 4-6 x target)
    target_max: int = 56
    max_gap: int = 5  # paper: training pairs within 5 frames
    target_speed: float = 5.0  # px/frame, target motion relative to the previous estimate
    camera_speed: float = 3.0  # px/frame, camera shake
    min_side: int = 260  # images are upscaled so a patch plus motion fits
    # Conditions drawn in turn (equal shares). A subset shifts what the heads learn: without the two distractor kinds
    # the local head has less to correct, which was tried for image fusion (docs/fusion.md).
    kinds: tuple[str, ...] = KINDS


@dataclass
class Sample:
    """One training pair: RGB/T init and search patches and the target box in each (x, y, w, h)."""

    init_rgb: np.ndarray  # uint8 [P,P,3]
    init_t: np.ndarray  # uint8 [P,P]
    search_rgb: np.ndarray
    search_t: np.ndarray
    init_box: np.ndarray  # float [4]
    search_box: np.ndarray
    kind: str


class PairSource:
    """Sample source over aligned image pairs: every draw is a :func:`make_sample` pair with a random donor target.

    ``draw(k, rng)`` cycles the sample kinds with ``k`` so each condition gets an equal share.
    """

    def __init__(self, pairs: list[tuple[Path, Path]], s: SampleSettings = SampleSettings()):
        check_kinds(s.kinds)
        self.images = [load_pair(v, i, s.min_side) for v, i in pairs]
        self.settings = s

    def draw(self, k: int, rng: np.random.Generator) -> Sample:
        n = len(self.images)
        a = int(rng.integers(n))
        b = int(rng.integers(n)) if n > 1 else a
        kinds = self.settings.kinds
        return make_sample(*self.images[a], self.images[b], rng, kind=kinds[k % len(kinds)], s=self.settings)


def check_kinds(kinds: tuple[str, ...]) -> None:
    """One-line error for an empty or unknown set of sample conditions."""
    unknown = [k for k in kinds if k not in KINDS]
    if not kinds or unknown:
        raise InputError(f"sample kinds {', '.join(unknown) or '(none)'}: choose one or more of {', '.join(KINDS)}")


def load_pair(vis_path: Path, ir_path: Path, min_side: int) -> tuple[np.ndarray, np.ndarray]:
    """Read an aligned pair as RGB uint8 and grey uint8, upscaled so the short side is at least ``min_side``."""
    vis, ir = read_image(vis_path), read_image(ir_path, grey=True)
    if vis.ndim == 2:
        vis = np.repeat(vis[:, :, None], 3, axis=2)
    if vis.shape[:2] != ir.shape[:2]:
        raise InputError(f"{vis_path} and {ir_path} differ in size; training needs aligned pairs")
    scale = max(1.0, min_side / min(vis.shape[:2]))
    if scale > 1.0:
        size = (round(vis.shape[1] * scale), round(vis.shape[0] * scale))
        vis, ir = cv2.resize(vis, size, interpolation=cv2.INTER_LINEAR), cv2.resize(ir, size)
    return vis, ir


def _mask(h: int, w: int, rng: np.random.Generator) -> np.ndarray:
    """Soft target silhouette: an ellipse or a rounded box, feathered by one pixel."""
    m = np.zeros((h, w), np.float32)
    if rng.random() < 0.5:
        cv2.ellipse(m, (w // 2, h // 2), (max(1, w // 2 - 1), max(1, h // 2 - 1)), 0, 0, 360, 1.0, -1)
    else:
        r = max(1, min(h, w) // 5)
        cv2.rectangle(m, (r, 0), (w - 1 - r, h - 1), 1.0, -1)
        cv2.rectangle(m, (0, r), (w - 1, h - 1 - r), 1.0, -1)
        for cx, cy in ((r, r), (w - 1 - r, r), (r, h - 1 - r), (w - 1 - r, h - 1 - r)):
            cv2.circle(m, (cx, cy), r, 1.0, -1)
    return cv2.GaussianBlur(m, (3, 3), 0)


@dataclass
class _Target:
    rgb: np.ndarray  # float [h,w,3]
    t: np.ndarray  # float [h,w]
    mask: np.ndarray  # float [h,w]


def _make_target(donor_vis: np.ndarray, donor_ir: np.ndarray, s: SampleSettings, rng) -> _Target:
    w = int(rng.integers(s.target_min, s.target_max + 1))
    h = int(np.clip(w * rng.uniform(0.6, 1.8), s.target_min * 0.7, s.target_max * 1.3))
    y = int(rng.integers(0, donor_vis.shape[0] - h))
    x = int(rng.integers(0, donor_vis.shape[1] - w))
    rgb = donor_vis[y : y + h, x : x + w].astype(np.float32)
    rgb = (rgb - rgb.mean()) * rng.uniform(1.2, 2.0) + rng.uniform(40, 215, size=3)  # distinct colour, strong texture
    t = donor_ir[y : y + h, x : x + w].astype(np.float32)
    t = (t - t.mean()) * 0.5 + rng.uniform(170, 245)  # warm body with some structure
    return _Target(np.clip(rgb, 0, 255), np.clip(t, 0, 255), _mask(h, w, rng))


def _paste(img: np.ndarray, look: np.ndarray, mask: np.ndarray, cx: float, cy: float) -> None:
    """Alpha-blend ``look`` centred at (cx, cy) into float ``img`` in place, clipped at the borders."""
    h, w = mask.shape
    x0, y0 = int(round(cx - w / 2)), int(round(cy - h / 2))
    xa, ya, xb, yb = max(x0, 0), max(y0, 0), min(x0 + w, img.shape[1]), min(y0 + h, img.shape[0])
    if xb <= xa or yb <= ya:
        return
    m = mask[ya - y0 : yb - y0, xa - x0 : xb - x0]
    lk = look[ya - y0 : yb - y0, xa - x0 : xb - x0]
    region = img[ya:yb, xa:xb]
    if region.ndim == 3:
        m = m[:, :, None]
    region[...] = region * (1 - m) + lk * m


def _crop(img: np.ndarray, x: float, y: float, p: int) -> np.ndarray:
    xi, yi = int(round(x)), int(round(y))
    return img[yi : yi + p, xi : xi + p].astype(np.float32)


def make_sample(
    vis: np.ndarray, ir: np.ndarray, donor: tuple[np.ndarray, np.ndarray], rng: np.random.Generator,
    kind: str | None = None, s: SampleSettings = SampleSettings(),
) -> Sample:
    """Draw one init/search training pair from an aligned pair ``(vis, ir)`` with a target cut from ``donor``."""
    kind = kind if kind is not None else KINDS[int(rng.integers(len(KINDS)))]
    if kind not in KINDS:
        raise InputError(f"unknown sample kind {kind!r}; choose from {KINDS}")
    p, H, W = s.patch, vis.shape[0], vis.shape[1]
    gap = int(rng.integers(1, s.max_gap + 1))
    cam = rng.normal(0, s.camera_speed, 2) * np.sqrt(gap)
    motion = rng.normal(0, s.target_speed, 2) * np.sqrt(gap)
    motion = np.clip(motion, -p / 2 + s.target_max, p / 2 - s.target_max)
    margin = np.abs(cam).max() + 2
    ox = rng.uniform(margin, W - p - margin)
    oy = rng.uniform(margin, H - p - margin)
    target = _make_target(*donor, s, rng)
    th, tw = target.mask.shape
    frames = {}
    for name, (dx, dy) in (("init", (0.0, 0.0)), ("search", (cam[0], cam[1]))):
        frames[name] = [_crop(vis, ox + dx, oy + dy, p), _crop(ir, ox + dx, oy + dy, p)]
    c_init = np.array([p / 2, p / 2])
    c_search = c_init + motion
    _paste(frames["init"][0], target.rgb, target.mask, *c_init)
    _paste(frames["init"][1], target.t, target.mask, *c_init)
    _paste(frames["search"][0], target.rgb, target.mask, *c_search)
    if kind == "t_crossover":  # target at background temperature: only a faint outline remains
        smooth = cv2.GaussianBlur(frames["search"][1], (0, 0), 5)
        x0, y0 = int(round(c_search[0] - tw / 2)), int(round(c_search[1] - th / 2))
        look = np.pad(smooth, ((th, th), (tw, tw)), mode="edge")[y0 + th : y0 + 2 * th, x0 + tw : x0 + 2 * tw]
        _paste(frames["search"][1], look + rng.normal(0, 2, look.shape), target.mask, *c_search)
    else:
        _paste(frames["search"][1], target.t, target.mask, *c_search)
    if kind in ("rgb_distractor", "t_distractor"):
        away = rng.uniform(-1, 1, 2)
        away = away / (np.abs(away).max() + 1e-6) * rng.uniform(max(tw, th) + 4, max(tw, th) + 0.2 * p)
        c_d = np.clip(c_search + away, 0, p)
        if kind == "rgb_distractor":
            _paste(frames["search"][0], target.rgb * rng.uniform(0.9, 1.1), target.mask, *c_d)
        else:
            _paste(frames["search"][1], target.t, target.mask, *c_d)
    if kind == "rgb_dark":
        gain, noise = rng.uniform(0.03, 0.07), rng.uniform(8, 16)
        for name in frames:
            img = frames[name][0]
            frames[name][0] = img * gain + rng.normal(0, noise, img.shape)
    if kind == "rgb_glare":
        glare = np.zeros((p, p), np.float32)
        r = rng.uniform(1.3, 2.2) * max(tw, th) / 2
        centre = c_search + rng.normal(0, 4, 2)
        cv2.circle(glare, (int(centre[0]), int(centre[1])), int(r), 1.0, -1)
        glare = cv2.GaussianBlur(glare, (0, 0), r / 4)[:, :, None]
        frames["search"][0] = frames["search"][0] * (1 - glare) + 255 * glare
    out = {k: [np.clip(v + 0.5, 0, 255).astype(np.uint8) for v in vals] for k, vals in frames.items()}
    box = lambda c: np.array([c[0] - tw / 2, c[1] - th / 2, tw, th], dtype=np.float64)  # noqa: E731
    return Sample(out["init"][0], out["init"][1], out["search"][0], out["search"][1], box(c_init), box(c_search), kind)
