"""The default box refiner: an MDNet-style bounding-box regressor trained on the first frame.

The authors' public code refines the tracker's box with a box regressor trained on 1000 frame-1 samples with
IoU > 0.6 (MDNet's bbreg): ridge regression from a sample's CNN features to the deltas that take it to the true box.
We do the same on the project's frozen backbone, so refinement needs no third-party detector weights:

* frame 1: draw the samples, cut a scale-normalised context patch around the target at three zooms (one batched
  backbone pass), RoI-align each sample's region (the box grown by ``roi_context``) into a small grid, fit ridge
  regression in closed form (weight chosen by leave-one-out error), and enable refinement only when the regressor
  beats the identity clearly on held-out boxes of a degraded copy of frame 1;
* each frame: one backbone pass on a 96 px patch normalised on the tracker's box, one RoI-align, one matrix
  product; corrections smaller than the regressor's own held-out error are ignored, larger ones must pass the
  authors' sanity limits.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np
import torch

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.refinement.boxes import apply_deltas, as_box, centres, encode_deltas, sample_boxes
from rgbt_toolkit.refinement.ridge import RidgeModel, fit_ridge
from rgbt_toolkit.refinement.roi import boxes_to_regions, crop_patch, patch_transform, roi_align
from rgbt_toolkit.refinement.sanity import SanityLimits, check_correction


@dataclass(frozen=True)
class RegressorSettings:
    """Settings of :class:`RegressionRefiner`; the source of each value is noted beside it."""

    backbone: str = "efficientnet-lite0"  # the project's frozen ImageNet backbone
    # ours, measured on generated scale-change scenes (docs/refinement.md): stride-8 features alone beat adding the
    # stride-16 ones (IoU after refinement 0.79 vs 0.75) and deep-only (0.60), at half the cost
    layers: tuple[str, ...] = ("mid",)
    grids: tuple[int, ...] = (6,)  # ours: RoI-align bins per side for each layer
    roi_context: float = 1.25  # ours: pool the box grown 1.25x so the features see where the target's edges are
    target_px: float = 32.0  # ours: the box's sqrt(area) in the patch (scale normalisation)
    patch_size: int = 96  # ours: patch side in pixels, 3x the normalised target
    n_samples: int = 1000  # authors' code: 1000 frame-1 samples
    min_iou: float = 0.6  # authors' code: samples with IoU > 0.6
    sample_shift: float = 0.3  # MDNet bbreg sampler: centre shift up to 0.3x the size
    sample_scale: float = 1.5  # ours: sides scaled within [1/1.5, 1.5]
    sample_aspect: float = 1.5  # ours: aspect ratio changed within [1/1.5, 1.5]
    flip: bool = False  # ours: also train on the mirrored frame (half the samples each)
    train_zooms: tuple[float, ...] = (0.8, 1.0, 1.25)  # ours: frame-1 patches normalised on these box scales
    alphas: tuple[float, ...] = (0.01, 0.03, 0.1, 0.3, 1.0, 3.0)  # ridge weights tried (relative)
    min_alpha: float = 0.1  # ours: frame-1 samples are alike, so the leave-one-out choice is floored
    n_check: int = 24  # ours: held-out frame-1 boxes, each pooled as refine() pools, to judge the regressor
    check_noise: float = 8.0  # ours: grey levels of fresh noise in the degraded frame-1 copy used for the check
    min_gain: float = 0.3  # ours: enable only if their squared error <= (1 - min_gain) x the identity's
    max_brightness: float = 185.0  # authors' code: disable when the 2x patch's mean grey is >= 185
    min_target_px: float = 8.0  # ours: disable on low-resolution targets (the paper's "low resolution" case)
    iterations: int = 1  # MDNet applies the regressor once; more passes chase larger errors (one pass each)
    step: float = 1.0  # ours: fraction of the accepted correction applied (< 1 damps it; the tracker carries it on)
    max_reversal: float | None = 0.5  # ours: refuse when a second pass would undo more than this share of the first
    dead_zone: float = 1.0  # ours: ignore corrections (largest |delta|) below this many held-out RMS errors
    limits: SanityLimits = field(default_factory=SanityLimits)  # authors' acceptance limits

    def __post_init__(self) -> None:
        if len(self.layers) != len(self.grids) or not self.layers:
            raise InputError("RegressorSettings: give one grid size per layer")
        if self.iterations < 1:
            raise InputError(f"RegressorSettings: iterations must be at least 1, got {self.iterations}")
        if self.n_samples < 10:
            raise InputError(f"RegressorSettings: n_samples must be at least 10, got {self.n_samples}")


_GREY = np.array([0.2989, 0.5870, 0.1140])  # MATLAB rgb2gray weights, as rgbt_toolkit.io.images


def as_rgb(image: np.ndarray) -> np.ndarray:
    """Check a visible frame: ``HxWx3`` (or ``HxW`` grey, repeated) uint8."""
    image = np.asarray(image)
    if image.dtype != np.uint8:
        raise InputError(f"refinement needs a uint8 image, got dtype {image.dtype}")
    if image.ndim == 2:
        image = np.repeat(image[:, :, None], 3, axis=2)
    if image.ndim != 3 or image.shape[2] != 3 or min(image.shape[:2]) < 8:
        raise InputError(f"refinement needs an HxWx3 RGB frame, got shape {image.shape}")
    return image


def patch_brightness(image: np.ndarray, box: np.ndarray, factor: float = 2.0) -> float:
    """Mean grey level of the box grown ``factor`` times (clipped to the frame); NaN when it lies outside."""
    c, half = centres(box), box[2:] * factor / 2
    h, w = image.shape[:2]
    x0, y0 = (np.floor(c - half)).astype(int)
    x1, y1 = (np.ceil(c + half)).astype(int) + 1
    patch = image[max(y0, 0):min(y1, h), max(x0, 0):min(x1, w)]
    if patch.size == 0:
        return float("nan")
    return float((patch.reshape(-1, 3).astype(np.float64) @ _GREY).mean())


def degrade(image: np.ndarray, rng: np.random.Generator, noise: float) -> np.ndarray:
    """A copy of ``image`` as another frame might show it: slight blur, lower contrast, fresh sensor noise."""
    out = cv2.GaussianBlur(image, (0, 0), 0.8).astype(np.float32) * 0.9 + 12.0
    out += rng.normal(0.0, noise, out.shape).astype(np.float32)
    return np.clip(out, 0, 255).astype(np.uint8)


class RegressionRefiner:
    """:class:`~rgbt_toolkit.jmmac.parts.BoxRefiner` with a frame-1 box regressor on backbone features.

    Parameters
    ----------
    settings : RegressorSettings
    seed : int
        Seed of the frame-1 sample draw (the only randomness).
    backbone : Backbone, optional
        A loaded backbone (default: ``load_backbone(settings.backbone)``, cached per process).

    Attributes
    ----------
    enabled : bool
        Whether frame 1 allowed refinement; ``disabled_reason`` says why not.
    model : RidgeModel or None
        The fitted regressor (kept even when disabled, for inspection).
    last_reason : str or None
        Why the last :meth:`refine` returned None.
    """

    def __init__(self, settings: RegressorSettings = RegressorSettings(), seed: int = 0, backbone=None):
        self.settings = settings
        self.seed = seed
        if backbone is None:
            from rgbt_toolkit.backbones import load_backbone

            backbone = load_backbone(settings.backbone)
        self.backbone = backbone
        self.enabled = False
        self.disabled_reason: str | None = "not initialised"
        self.model: RidgeModel | None = None
        self.last_reason: str | None = None
        self.gain = float("nan")  # 1 - held-out error / identity error on frame 1
        self.check_error = self.check_identity = float("nan")

    # ------------------------------------------------------------------------------------------------------------
    def patch_maps(self, image: np.ndarray, anchors: list[np.ndarray]) -> tuple[dict, list[np.ndarray]]:
        """Backbone maps of patches centred and scale-normalised on each anchor box (one batched pass).

        Returns the maps (name -> ``[len(anchors), C, h, w]``) and each patch's image-to-patch affine.
        """
        s = self.settings
        patches, transforms = [], []
        for anchor in anchors:
            scale = s.target_px / np.sqrt(anchor[2] * anchor[3])
            transforms.append(patch_transform(centres(anchor), scale, s.patch_size))
            patches.append(crop_patch(image, centres(anchor), scale, s.patch_size))
        batch = torch.from_numpy(np.stack(patches)).permute(0, 3, 1, 2).float().div_(255.0)
        return self.backbone.extract(batch, tuple(s.layers)), transforms

    def pool(self, maps: dict, index: int, transform: np.ndarray, boxes: np.ndarray) -> np.ndarray:
        """RoI features ``(N, D)`` of image boxes ``(N, 4)`` from patch ``index`` of :meth:`patch_maps`."""
        s = self.settings
        regions = boxes_to_regions(boxes, transform, s.roi_context)
        parts = [roi_align(maps[name][index:index + 1], regions, self.backbone.strides[name], grid).flatten(1)
                 for name, grid in zip(s.layers, s.grids)]
        return torch.cat(parts, dim=1).numpy()

    def features(self, image: np.ndarray, groups: list[tuple[np.ndarray, np.ndarray]]) -> list[np.ndarray]:
        """RoI features of boxes, one backbone pass for all groups.

        ``groups`` pairs an anchor box (the patch is centred and scale-normalised on it) with the ``(N, 4)`` boxes
        pooled from that patch; returns one ``(N, D)`` float array per group.
        """
        maps, transforms = self.patch_maps(image, [anchor for anchor, _ in groups])
        return [self.pool(maps, i, transforms[i], boxes) for i, (_, boxes) in enumerate(groups)]

    def _training_set(self, image: np.ndarray, box: np.ndarray, n: int,
                      rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Features ``(n, D)`` and regression targets ``(n, 4)`` of ``n`` samples around ``box``."""
        s = self.settings
        samples = sample_boxes(box, n, rng, s.min_iou, s.sample_shift, s.sample_scale, s.sample_aspect)
        # each sample is pooled from the patch whose zoom is nearest its own scale, so that the per-frame patch
        # (normalised on the tracker's box itself) sees the target at a scale the regressor was trained on
        rel = np.log(np.sqrt(samples[:, 2] * samples[:, 3] / (box[2] * box[3])))
        zooms = np.asarray(s.train_zooms, dtype=float)
        nearest = np.argmin(np.abs(rel[:, None] - np.log(zooms)[None, :]), axis=1)
        groups, order = [], []
        for k, z in enumerate(zooms):
            idx = np.flatnonzero(nearest == k)
            if len(idx):
                anchor = np.concatenate([centres(box) - (box[2:] * z - 1) / 2, box[2:] * z])
                groups.append((anchor, samples[idx]))
                order.append(idx)
        x = np.concatenate(self.features(image, groups))
        return x, encode_deltas(samples[np.concatenate(order)], box)

    def initialize(self, rgb: np.ndarray, box: np.ndarray) -> None:
        """Train the regressor on the first frame and decide whether refinement is enabled."""
        s = self.settings
        image, box = as_rgb(rgb), as_box(box, "initial box")
        self.model, self.enabled, self.disabled_reason = None, False, None
        size = float(np.sqrt(box[2] * box[3]))
        brightness = patch_brightness(image, box)
        if size < s.min_target_px:
            self.disabled_reason = f"target too small ({size:.1f} px < {s.min_target_px})"
            return
        if not brightness < s.max_brightness:
            self.disabled_reason = f"target over-bright (mean grey {brightness:.0f} >= {s.max_brightness})"
            return
        rng = np.random.default_rng(self.seed)
        views = [(image, box)]
        if s.flip:  # the mirrored frame: the same target on a mirrored background, twice the appearance variety
            views.append((np.ascontiguousarray(image[:, ::-1]),
                          np.array([image.shape[1] - box[0] - box[2], box[1], box[2], box[3]])))
        parts = [self._training_set(v, b, s.n_samples // len(views), rng) for v, b in views]
        x = np.concatenate([p[0] for p in parts])
        y = np.concatenate([p[1] for p in parts])
        alphas = tuple(a for a in s.alphas if a >= s.min_alpha) or (s.min_alpha,)
        self.model = fit_ridge(x, y, alphas)
        # Leave-one-out on samples of one patch is far too optimistic (they share every pixel, down to the noise);
        # the check uses held-out boxes pooled exactly as refine() pools them (each from a patch normalised on
        # itself) on a degraded copy of the frame (blur, contrast, fresh noise), which only real structure survives.
        check = sample_boxes(box, s.n_check, rng, s.min_iou, s.sample_shift, s.sample_scale, s.sample_aspect)
        feats = self.features(degrade(image, rng, s.check_noise), [(b, b[None]) for b in check])
        pred = self.model.predict(np.concatenate(feats))
        truth = encode_deltas(check, box)
        self.check_error = float(np.mean((pred - truth) ** 2))
        self.check_identity = float(np.mean(truth**2))
        self.gain = 1.0 - self.check_error / max(self.check_identity, 1e-12)
        if self.gain < s.min_gain:
            self.disabled_reason = (f"regressor not better than identity on held-out frame-1 boxes "
                                    f"(gain {max(self.gain, -99.0):.2f} < {s.min_gain})")
            return
        self.enabled = True

    def predict(self, rgb: np.ndarray, box: np.ndarray) -> np.ndarray:
        """The regressor's box for ``box`` without any limit (raises when not trained)."""
        if self.model is None:
            raise InputError(f"the regressor is not trained ({self.disabled_reason}); call initialize first")
        box = as_box(box)
        (feat,) = self.features(as_rgb(rgb), [(box, box[None])])
        return apply_deltas(box, self.model.predict(feat)[0])

    def refine(self, rgb: np.ndarray, box: np.ndarray, occluded: bool = False) -> np.ndarray | None:
        """A corrected box, or None (disabled; correction too small, inconsistent, or beyond the authors' limits)."""
        s = self.settings
        self.last_reason = None
        if not self.enabled:
            self.last_reason = f"disabled: {self.disabled_reason}"
            return None
        image, box = as_rgb(rgb), as_box(box)
        if np.sqrt(box[2] * box[3]) < s.min_target_px:
            self.last_reason = "target too small"
            return None
        maps, (transform,) = self.patch_maps(image, [box])
        new = box
        for _ in range(s.iterations):  # further passes re-pool the moved box from the same patch
            new = apply_deltas(new, self.model.predict(self.pool(maps, 0, transform, new[None]))[0])
        rms = float(np.sqrt(self.check_error))
        step = float(np.max(np.abs(encode_deltas(box, new))))
        if step < s.dead_zone * rms:
            self.last_reason = f"correction {step:.3f} within the regressor's own error"
            return None
        if s.max_reversal is not None:
            # re-pool the moved box from the same patch: a correction the regressor itself would largely undo is a
            # guess (e.g. a box grown onto a look-alike neighbour); one it would continue is an under-correction
            first = encode_deltas(box, new)
            again = self.model.predict(self.pool(maps, 0, transform, new[None]))[0]
            reversal = -float(first @ again) / max(float(first @ first), 1e-12)
            if reversal > s.max_reversal:
                self.last_reason = f"inconsistent: the regressor would undo {reversal:.0%} of its own correction"
                return None
        if s.step != 1.0:
            new = apply_deltas(box, s.step * encode_deltas(box, new))
        self.last_reason = check_correction(box, new, s.limits, occluded)
        return None if self.last_reason else new
