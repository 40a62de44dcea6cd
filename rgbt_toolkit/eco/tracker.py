"""The ECO tracker for one modality, with an API shaped for JMMAC's two-tracker fusion.

>>> tracker = EcoTracker(preset("hc"))
>>> tracker.initialize(frame0, np.array([x, y, w, h]))
>>> pred = tracker.predict(frame)          # search; the model is not changed
>>> tracker.update(frame, pred.box)        # learn from the sample at that box (a caller may skip it)

``pred.response`` is the translation score at the best scale sampled on a square grid: grid index ``(i, j)`` is the
image point ``(x, y) = pred.grid_origin + (j, i) * pred.grid_step``. The grid size and step depend only on the
initial box and the search settings, so an RGB and a thermal tracker built from the same settings and box produce
maps that can be fused element-wise and handed back to :meth:`EcoTracker.localize_from_response`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import NamedTuple

import cv2
import numpy as np

from rgbt_toolkit.eco import optimize as opt
from rgbt_toolkit.eco.extent import target_extent
from rgbt_toolkit.eco.fourier import half_weights, sample_grid, sample_scaled_grid, shift_half
from rgbt_toolkit.eco.model import base_patch_size, build_blocks, build_features, compute_blocks, to_fourier
from rgbt_toolkit.eco.params import EcoParams, preset
from rgbt_toolkit.eco.sample_space import SampleSpace
from rgbt_toolkit.eco.sampling import extract_patches, parabolic_peak, refine_peaks
from rgbt_toolkit.eco.scale import sample_geometry, scale_factors
from rgbt_toolkit.eco.training import train_filter, train_first_frame
from rgbt_toolkit.errors import InputError


class _Detection(NamedTuple):
    """What :meth:`EcoTracker.predict` leaves for the :meth:`EcoTracker.update` that may follow on the same frame."""

    frame: np.ndarray        # the array searched (the update reuses the sample only for this very object)
    search_pos: np.ndarray   # [y, x] search centre
    scale_index: int         # the winning scale
    scale: float             # ... its absolute scale
    samples: list            # projected Fourier samples per block, all scales searched
    predicted_pos: np.ndarray  # [y, x] the predicted centre
    scales_searched: bool    # a full scale search (counts for scale_search_interval)


@dataclass
class TrackResult:
    """One search: box estimate, response map on the documented grid, and quality figures.

    Attributes
    ----------
    box : ndarray
        ``[x, y, w, h]`` estimate (top-left corner, pixel coordinates of the input).
    center : ndarray
        ``[x, y]`` estimated target centre (pixel-centre coordinates: pixel ``(r, c)`` is at ``(c, r)``).
    scale : float
        Image pixels per patch pixel at the best scale; ``scale_index`` is its index in the scale set.
    response : ndarray
        ``(G, G)`` float32 translation score at the best scale, read on the grid of the tracker's current scale
        (the scale before this search), so two trackers given the same centre and boxes share the grid.
    grid_origin, grid_step : ndarray, float
        Image point ``[x, y]`` of grid index ``(0, 0)`` and the grid step in image pixels (same on both axes).
    search_center : ndarray
        ``[x, y]`` centre of the searched region (grid index ``((G-1)/2, (G-1)/2)``).
    peak, psr : float
        Refined peak score; peak-to-sidelobe ratio ``(peak - mean) / std`` of ``response``.
    timings : dict
        Seconds spent in "features" and "detection".
    """

    box: np.ndarray
    center: np.ndarray
    scale: float
    scale_index: int
    response: np.ndarray
    grid_origin: np.ndarray
    grid_step: float
    search_center: np.ndarray
    peak: float
    psr: float
    timings: dict = field(default_factory=dict)

    @property
    def response_extent(self) -> float:
        """Side of the response grid in image pixels (``G * grid_step``)."""
        return float(self.response.shape[0] * self.grid_step)

    @property
    def psr_variance(self) -> float:
        """``(max - mean) / var`` of ``response``: the PSR form of the JMMAC code and the paper's equation."""
        r = self.response.astype(np.float64)
        return float((r.max() - r.mean()) / (r.var() + 1e-12))

    def grid_to_image(self, i: float, j: float) -> np.ndarray:
        """Image point ``[x, y]`` of (fractional) grid index ``(i, j)`` (row, column)."""
        return self.grid_origin + np.array([j, i]) * self.grid_step


def check_box(box, name: str = "box", frame_shape: tuple[int, ...] | None = None) -> np.ndarray:
    """``[x, y, w, h]`` as float64, or :class:`InputError` when it is malformed, has no area or (given the frame's
    ``(h, w, ...)`` shape) lies wholly outside the frame."""
    b = np.asarray(box, dtype=np.float64).ravel()
    if b.size != 4 or not np.all(np.isfinite(b)):
        raise InputError(f"{name} must be four finite numbers x,y,w,h; got {np.asarray(box).tolist()}")
    if b[2] <= 0 or b[3] <= 0:
        raise InputError(f"{name} {b.tolist()} has zero or negative size; give width and height of at least 1 pixel")
    if frame_shape is not None:
        h, w = frame_shape[:2]
        if b[0] >= w or b[1] >= h or b[0] + b[2] <= 0 or b[1] + b[3] <= 0:
            raise InputError(f"{name} {b.tolist()} lies outside the {w}x{h} frame")
    return b


def _is_colour(frame: np.ndarray) -> bool:
    """A 3-channel frame whose channels differ (a grey image stored as RGB counts as grey, as in ECO)."""
    if frame.ndim != 3:
        return False
    sub = frame[::4, ::4].astype(np.int16)
    return bool(np.any(sub[..., 0] != sub[..., 1]) or np.any(sub[..., 0] != sub[..., 2]))


def normalise_exposure(frame: np.ndarray, target: float, min_gain: float) -> np.ndarray:
    """Brighten a dark colour frame so its mean grey is ``target`` (saturating), as a camera's auto-exposure would.

    Colour names are defined on absolute colours: at night every pixel falls in "black" and the colour feature
    carries nothing, so ECO on a darkening RGB stream drifts. Frames needing less than ``min_gain`` pass unchanged.
    """
    gain = target / max(float(frame[::4, ::4].mean()), 1.0)
    if gain <= min_gain:
        return frame
    return cv2.convertScaleAbs(frame, alpha=gain)


def _scale_choice(evidence: np.ndarray, penalty: float, step_to_peak: bool) -> int:
    """Index of the scale the search settles on, from each scale's bias-corrected peak (the centre is the current
    scale): another scale must beat the centre by ``penalty`` per step and, with ``step_to_peak``, also be the one
    whose peak is highest before the penalty - a tilt whose plain maximum lies further out is the filter's own
    preference, not a size change (docs/eco.md, "Scale on real footage")."""
    centre = (len(evidence) - 1) // 2
    k = int(np.argmax(evidence * penalty ** np.abs(np.arange(len(evidence)) - centre)))
    if step_to_peak and k != int(np.argmax(evidence)):
        return centre
    return k


class EcoTracker:
    """ECO on one modality: parameters in, per-frame state carried between calls."""

    def __init__(self, params: EcoParams | None = None) -> None:
        self.params = preset("hc") if params is None else params
        self.initialized = False

    # ------------------------------------------------------------------------------------------------------------
    def _prepare(self, frame: np.ndarray) -> np.ndarray:
        frame = np.asarray(frame)
        if frame.ndim not in (2, 3) or (frame.ndim == 3 and frame.shape[2] not in (1, 3)) or frame.size == 0:
            raise InputError(f"frame must be an HxW grey or HxWx3 RGB image, got shape {frame.shape}")
        if frame.dtype != np.uint8:
            raise InputError(f"frame must be uint8, got {frame.dtype}; scale other types to 0..255 first")
        if frame.ndim == 3 and (frame.shape[2] == 1 or not self.colour):
            frame = np.ascontiguousarray(frame[..., 0])
        elif frame.ndim == 3 and self.params.exposure_target > 0:
            frame = normalise_exposure(frame, self.params.exposure_target, self.params.exposure_min_gain)
        return frame

    def _cells(self, frame, center_yx, scales) -> list:
        """Cell maps per block at each scale, from one base patch cut at the smallest scale."""
        a0 = float(np.min(scales))
        size = base_patch_size(self.geom.patch, float(np.max(scales)) / a0, self.features)
        patch = extract_patches(frame, center_yx, np.array([a0]), size)[0]
        return compute_blocks(self.features, patch, np.asarray(scales) / a0, self.geom.patch)

    def _fourier_samples(self, frame, center_yx, scales, projected: bool) -> list:
        maps = self._cells(frame, center_yx, scales)
        return [to_fourier(m, b, self.params.normalize_power, self.P[k] if projected else None)
                for k, (m, b) in enumerate(zip(maps, self.blocks))]

    # ------------------------------------------------------------------------------------------------------------
    def initialize(self, frame: np.ndarray, box) -> None:
        """Learn the first model (projection by PCA, then Gauss-Newton + CG) from the target at ``box``."""
        box = check_box(box, "initial box")  # a box partly or wholly outside the frame is clamped (tested)
        frame = source = np.asarray(frame)
        self.colour = _is_colour(frame)
        frame = self._prepare(frame)
        p = self.params
        self.image_hw = frame.shape[:2]
        self.pos = np.array([box[1] + (box[3] - 1) / 2, box[0] + (box[2] - 1) / 2])  # (cy, cx)
        self.geom = sample_geometry((box[3], box[2]), self.image_hw, search_area_scale=p.search_area_scale,
                                    min_area=p.min_sample_area, max_area=p.max_sample_area,
                                    sample_stride=p.sample_stride, response_stride=p.response_stride,
                                    scale_step=p.scale_step)
        self.scale = self.geom.init_scale
        self.scales = np.ones(1) if p.scale_filter else scale_factors(p.n_scales, p.scale_step)
        self.features = build_features(p, self.colour)
        # the filter's support: the box, or the blob inside a loose box (EcoParams.loose_box_share; off by default)
        self.extent = None
        if p.loose_box_share > 0:
            grey = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_RGB2GRAY)
            self.extent = target_extent(grey, box, max_share=p.loose_box_share, max_offset=p.loose_box_offset)
        support = self.geom.base_target if self.extent is None else tuple(self.extent / self.geom.init_scale)
        self.blocks = build_blocks(self.features, p, self.geom.patch, support)
        self.out_shape = (max(b.ny for b in self.blocks), max(b.nxh for b in self.blocks))
        maps = self._cells(frame, tuple(self.pos), np.array([self.scale]))
        self.P = [opt.pca_projection(m.reshape(-1, m.shape[-1]), b.spec.compressed_dim)
                  for m, b in zip(maps, self.blocks)]
        X = [to_fourier(m, b, p.normalize_power)[0] for m, b in zip(maps, self.blocks)]
        self.F, self.P = train_first_frame(X, self.P, self.blocks, self.out_shape, p)
        Z = opt.project(self.P, X)
        self.sample_energy = [np.abs(z) ** 2 for z in Z]
        self.layout = [(z.shape, z.size) for z in Z]
        ipw = np.concatenate([np.broadcast_to(half_weights(b.ny, b.nxh), z.shape).ravel()
                              for z, b in zip(Z, self.blocks)])
        min_weight = p.learning_rate * (1 - p.learning_rate) ** (2 * p.n_samples)
        self.space = SampleSpace(p.n_samples, ipw.size, ipw, p.learning_rate, min_weight)
        self.space.add(self._flatten(Z))
        self.cg_state = None
        self.frames_since_train = 0
        self.target_hw = np.array([box[3], box[2]], dtype=np.float64)
        self.scale_filter = None
        if p.scale_filter:
            from rgbt_toolkit.eco.scale_filter import ScaleFilter

            self.scale_filter = ScaleFilter(self.target_hw)
            self.scale_filter.initialize(frame, self.pos, self.target_hw)
        self._cache = None
        self._since_scale_search = p.scale_search_interval  # the first frame searches scales
        self.initialized = True
        self.scale_bias = np.ones(len(self.scales))
        if p.scale_bias_calibration and len(self.scales) > 1:
            self.scale_bias = self._first_frame_scale_bias(source)

    def _first_frame_scale_bias(self, frame: np.ndarray) -> np.ndarray:
        """Peak per search scale on the training frame itself, relative to the centre scale's.

        There the target has exactly the trained size, yet the peaks differ by a few per cent and not always in the
        centre's favour (windowing and per-sample normalisation reward some zoom levels; small, upsampled targets
        most): left in, that preference is read as a size change every frame and the box drifts.
        """
        self.predict(frame)
        self._cache = None
        val = self._last_peaks
        return np.maximum(val / val[(len(val) - 1) // 2], 1e-3)

    def _flatten(self, Z: list) -> np.ndarray:
        return np.concatenate([z.ravel() for z in Z])

    def _unflatten(self, flat: np.ndarray) -> list:
        out, start = [], 0
        for shape, size in self.layout:
            out.append(flat[..., start : start + size].reshape(flat.shape[:-1] + shape))
            start += size
        return out

    # ------------------------------------------------------------------------------------------------------------
    def predict(self, frame: np.ndarray, center=None, search_scales: bool = True) -> TrackResult:
        """Search ``frame`` around ``center`` (``[x, y]``; default: the last position). The model is not changed.

        ``search_scales=False`` looks at the current scale only (about a fifth of the feature cost): for checks that
        need the peak and position, not a size (re-acquisition), and for the frames between scale searches when
        ``params.scale_search_interval`` > 1.
        """
        if not self.initialized:
            raise InputError("call initialize(frame, box) before predict")
        source = frame
        frame = self._prepare(frame)
        p = self.params
        pos = self.pos.copy() if center is None else np.array([center[1], center[0]], dtype=np.float64)
        if not np.all(np.isfinite(pos)):
            raise InputError(f"search centre must be finite, got {center}")
        pos = np.clip(pos, 0, np.array(self.image_hw) - 1)
        t0 = time.perf_counter()
        searched = search_scales and len(self.scales) > 1 and self._since_scale_search + 1 >= p.scale_search_interval
        relative = self.scales if searched else np.ones(1)
        scales = self.scale * relative
        Z = self._fourier_samples(frame, tuple(pos), scales, projected=True)
        t1 = time.perf_counter()
        S = opt.scores(self.F, Z, self.out_shape)
        resp = sample_grid(S, self.geom.grid)
        ty, tx, val = refine_peaks(S, resp, self.geom.patch, p.newton_iter)
        self._last_peaks = val
        bias = self.scale_bias if searched else np.ones(1)
        k = _scale_choice(val / bias, p.scale_penalty, p.scale_step_to_peak)
        a = float(np.clip(scales[k], self.geom.min_scale, self.geom.max_scale))
        new_pos = pos + np.array([ty[k], tx[k]]) * scales[k]
        new_pos = np.clip(new_pos, 0, np.array(self.image_hw) - 1)
        if self.scale_filter is not None:
            rel = self.scale_filter.estimate(frame, new_pos, self.target_hw)
            a = float(np.clip(self.scale * rel, self.geom.min_scale, self.geom.max_scale))
        hw = self.target_hw * (a / self.scale)  # keeps the aspect of the last box given to update
        # the map is read on the grid of the current scale (not the best one), so trackers sharing search centre
        # and scale share the grid whatever scale each of them prefers
        factor = self.scale / scales[k]
        r = (resp[k] if abs(factor - 1) < 1e-12 else sample_scaled_grid(S[k], self.geom.grid, factor))
        r = r.astype(np.float32)
        origin, step = self._grid_at(pos)
        psr = float((r.max() - r.mean()) / (r.std() + 1e-12))
        box = np.array([new_pos[1] - (hw[1] - 1) / 2, new_pos[0] - (hw[0] - 1) / 2, hw[1], hw[0]])
        t2 = time.perf_counter()
        self._cache = _Detection(source, pos, k, float(scales[k]), Z, new_pos.copy(), searched)
        return TrackResult(box=box, center=new_pos[::-1].copy(), scale=a, scale_index=k, response=r,
                           grid_origin=origin, grid_step=float(step), search_center=pos[::-1].copy(),
                           peak=float(val[k]), psr=psr, timings={"features": t1 - t0, "detection": t2 - t1})

    def _grid_at(self, pos: np.ndarray) -> tuple[np.ndarray, float]:
        """Image point ``[x, y]`` of response grid index ``(0, 0)`` and the grid step, for a search at ``pos``
        (``[y, x]``, inside the frame) at the current scale."""
        step = self.geom.patch * self.scale / self.geom.grid
        return np.array([pos[1], pos[0]]) - (self.geom.grid - 1) // 2 * step, float(step)

    def response_grid(self, center) -> tuple[np.ndarray, float]:
        """``(grid_origin, grid_step)`` of the response that :meth:`predict` centred at ``center`` (``[x, y]``) will
        return, known before searching (the grid is read at the current scale whichever scale wins)."""
        pos = np.clip(np.array([center[1], center[0]], dtype=np.float64), 0, np.array(self.image_hw) - 1)
        return self._grid_at(pos)

    def localize_from_response(self, pred: TrackResult, response: np.ndarray) -> np.ndarray:
        """Box ``[x, y, w, h]`` at the peak of an externally fused ``response`` on ``pred``'s grid.

        The peak is refined by a parabola through its neighbours; the size is ``pred``'s. The model is not changed.
        """
        response = np.asarray(response, dtype=np.float64)
        if response.shape != pred.response.shape:
            raise InputError(f"fused response has shape {response.shape}, expected the grid {pred.response.shape}")
        i, j, _ = parabolic_peak(response)
        cx, cy = pred.grid_to_image(i, j)
        w, h = pred.box[2], pred.box[3]
        return np.array([cx - (w - 1) / 2, cy - (h - 1) / 2, w, h])

    # ------------------------------------------------------------------------------------------------------------
    def _update_plan(self, frame, box: np.ndarray) -> tuple[np.ndarray, float, np.ndarray | None]:
        """``(position, scale, shift)`` of :meth:`update` at ``box``. ``shift`` (patch pixels, ``[y, x]``) is set when
        the detection sample of the last :meth:`predict` on this very ``frame`` is shifted by it instead of extracting
        anew, else None."""
        new_pos = np.array([box[1] + (box[3] - 1) / 2, box[0] + (box[2] - 1) / 2])
        new_pos = np.clip(new_pos, 0, np.array(self.image_hw) - 1)
        base = np.array(self.geom.base_target)
        a = float(np.sqrt(box[2] * box[3] / (base[0] * base[1])))
        a = float(np.clip(a, self.geom.min_scale, self.geom.max_scale))
        last = self._cache
        if last is not None and frame is last.frame and abs(a / last.scale - 1) < 1e-3:
            d = (new_pos - last.search_pos) / last.scale
            # ECO always trains on its shifted detection sample; a box from elsewhere (a detector, a fused map) far
            # from the search centre would wrap around the period, so that one is re-extracted instead
            if np.allclose(new_pos, last.predicted_pos, atol=1e-6) or np.max(np.abs(d)) <= self.geom.patch / 8:
                return new_pos, a, d
        return new_pos, a, None

    def update_reads_frame(self, frame: np.ndarray, box) -> bool:
        """Whether :meth:`update` with these arguments reads the frame's pixels (rather than reusing the detection
        sample): a caller that runs the update in the background may do so only when it does not, since the frame's
        buffer may be refilled meanwhile."""
        return self.scale_filter is not None or self._update_plan(frame, check_box(box))[2] is None

    def update(self, frame: np.ndarray, box) -> dict:
        """Add the sample at ``box`` to the sample space and, every ``train_gap + 1`` calls, refine the filter.

        The box sets position, scale (``sqrt(w h)`` relative to the first box) and the box aspect that later
        predictions report (the filter itself keeps the first frame's aspect, as in ECO).

        When ``frame`` is the very array just passed to :meth:`predict`, the box keeps the predicted scale and is
        either the predicted box or within 1/8 of the patch of the search centre, the detection sample is reused,
        shifted in the Fourier domain (as ECO does); otherwise it is extracted anew.
        Returns the seconds spent (``{"update": ...}``).
        """
        if not self.initialized:
            raise InputError("call initialize(frame, box) before update")
        box = check_box(box)
        t0 = time.perf_counter()
        frame_in = frame
        p = self.params
        new_pos, a, d = self._update_plan(frame_in, box)
        last = self._cache
        if d is not None:  # reuse the search's sample, shifted
            Z = [shift_half(z[last.scale_index], -d[0], -d[1], self.geom.patch) for z in last.samples]
        else:
            frame = self._prepare(frame_in)
            Z = [z[0] for z in self._fourier_samples(frame, tuple(new_pos), np.array([a]), projected=True)]
        searched = last is not None and frame_in is last.frame and last.scales_searched
        self._since_scale_search = 0 if searched else self._since_scale_search + 1
        self._cache = None
        self.pos, self.scale = new_pos, a
        self.target_hw = np.array([box[3], box[2]], dtype=np.float64)
        self.space.add(self._flatten(Z))
        if self.scale_filter is not None:
            self.scale_filter.update(self._prepare(frame_in), new_pos, self.target_hw)
        lr = p.learning_rate
        self.sample_energy = [(1 - lr) * e + lr * np.abs(z) ** 2 for e, z in zip(self.sample_energy, Z)]
        if self.frames_since_train >= p.train_gap:
            n = self.space.count
            # one contiguous copy per block for the CG iterations (views of the flat store would be copied by the
            # compiled contractions at every iteration)
            samples = [np.ascontiguousarray(z) for z in self._unflatten(self.space.samples[:n])]
            self.F, self.cg_state = train_filter(self.F, samples, self.space.weights[:n], self.sample_energy,
                                                 self.blocks, self.out_shape, p, self.cg_state)
            self.frames_since_train = 0
        else:
            self.frames_since_train += 1
        return {"update": time.perf_counter() - t0}

    def track(self, frame: np.ndarray) -> TrackResult:
        """:meth:`predict` then :meth:`update` at the predicted box (single-modality tracking)."""
        pred = self.predict(frame)
        pred.timings.update(self.update(frame, pred.box))
        return pred
