"""The ECO tracker end to end on generated frames: translation accuracy, the JMMAC API, awkward boxes."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rgbt_toolkit.eco import EcoTracker, preset
from rgbt_toolkit.errors import InputError


def texture(shape=(240, 320), seed=0, colour=True) -> np.ndarray:
    """Smooth random texture (blurred noise), uint8."""
    rng = np.random.default_rng(seed)
    chans = 3 if colour else 1
    noise = rng.random((shape[0], shape[1], chans)).astype(np.float32)
    img = cv2.GaussianBlur(noise, (0, 0), 2.0).reshape(shape + (chans,))
    img = (img - img.min()) / (img.max() - img.min()) * 255
    out = img.astype(np.uint8)
    return out if colour else out[..., 0]


def shifted(img: np.ndarray, dx: float, dy: float) -> np.ndarray:
    """``img`` translated by (dx, dy) pixels with bilinear interpolation."""
    m = np.array([[1.0, 0.0, dx], [0.0, 1.0, dy]])
    return cv2.warpAffine(img, m, img.shape[1::-1], flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)


BOX = np.array([140.0, 100.0, 40.0, 36.0])


@pytest.fixture(scope="module")
def colour_tracker():
    tr = EcoTracker(preset("hc"))
    tr.initialize(texture(), BOX)
    return tr


@pytest.mark.parametrize("dx, dy", [(3.4, -2.6), (-6.25, 4.75)])
def test_recovers_a_known_translation_to_subpixel(colour_tracker, dx, dy):
    frame = shifted(texture(), dx, dy)
    pred = colour_tracker.predict(frame)
    centre0 = BOX[:2] + (BOX[2:] - 1) / 2
    err = pred.center - (centre0 + [dx, dy])
    assert np.hypot(*err) < 0.35, err
    assert abs(pred.scale_index - 3) <= 1  # at most one 1% scale step


def test_predict_does_not_change_the_model(colour_tracker):
    frame = shifted(texture(), 2.0, 1.0)
    f_before = [f.copy() for f in colour_tracker.F]
    pos_before = colour_tracker.pos.copy()
    a = colour_tracker.predict(frame)
    b = colour_tracker.predict(frame)
    np.testing.assert_array_equal(a.box, b.box)
    np.testing.assert_array_equal(a.response, b.response)
    assert all(np.array_equal(x, y) for x, y in zip(f_before, colour_tracker.F))
    np.testing.assert_array_equal(pos_before, colour_tracker.pos)


def test_response_grid_is_documented_and_localizes(colour_tracker):
    frame = shifted(texture(), 5.0, -3.0)
    pred = colour_tracker.predict(frame, center=[155.0, 112.0])
    g = pred.response.shape[0]
    assert pred.response.shape == (g, g) and g % 2 == 1
    np.testing.assert_allclose(pred.grid_to_image((g - 1) / 2, (g - 1) / 2), pred.search_center)
    np.testing.assert_allclose(pred.search_center, [155.0, 112.0])
    i, j = np.unravel_index(np.argmax(pred.response), pred.response.shape)
    assert np.hypot(*(pred.grid_to_image(i, j) - pred.center)) <= pred.grid_step
    box = colour_tracker.localize_from_response(pred, pred.response)
    centre = box[:2] + (box[2:] - 1) / 2
    assert np.hypot(*(centre - pred.center)) < 0.5 * pred.grid_step
    assert pred.psr > 5 and pred.peak > 0
    assert pred.response_extent == pytest.approx(g * pred.grid_step)
    r = pred.response.astype(float)
    assert pred.psr_variance == pytest.approx((r.max() - r.mean()) / r.var(), rel=1e-6)
    with pytest.raises(InputError, match="expected the grid"):
        colour_tracker.localize_from_response(pred, pred.response[1:])


def test_rgb_and_thermal_trackers_share_the_grid():
    rgb = texture(seed=1)
    thermal = texture(seed=2, colour=False)
    t_rgb, t_t = EcoTracker(preset("hc")), EcoTracker(preset("hc"))
    t_rgb.initialize(rgb, BOX)
    t_t.initialize(thermal, BOX)
    assert t_rgb.features[1].blocks[0].name == "colornames"
    assert t_t.features[1].blocks[0].name == "intensity"
    p_rgb = t_rgb.predict(shifted(rgb, 2.0, 1.0))
    p_t = t_t.predict(shifted(thermal, 2.0, 1.0))
    assert p_rgb.response.shape == p_t.response.shape
    # same search centre and scale -> identical grid geometry, so maps add element-wise
    np.testing.assert_allclose(p_rgb.grid_origin, p_t.grid_origin)
    assert p_rgb.grid_step == pytest.approx(p_t.grid_step)
    fused = 0.5 * p_rgb.response + 0.5 * p_t.response
    box = t_rgb.localize_from_response(p_rgb, fused)
    centre = box[:2] + (box[2:] - 1) / 2
    np.testing.assert_allclose(centre, BOX[:2] + (BOX[2:] - 1) / 2 + [2.0, 1.0], atol=1.0)


def test_tracks_a_moving_target_on_a_generated_sequence():
    rng = np.random.default_rng(5)
    bg = texture(seed=3)
    obj = texture((40, 30), seed=4)
    tr = EcoTracker(preset("hc"))
    x, y = 100.0, 90.0
    errors = []
    for k in range(25):
        frame = bg.copy()
        xi, yi = int(round(x)), int(round(y))
        frame[yi : yi + 40, xi : xi + 30] = obj
        box = np.array([xi, yi, 30, 40], float)
        if k == 0:
            tr.initialize(frame, box)
        else:
            res = tr.track(frame)
            errors.append(np.hypot(*(res.box[:2] + res.box[2:] / 2 - box[:2] - box[2:] / 2)))
        x += 3 + rng.normal()
        y += 1.5 + rng.normal()
    assert max(errors) < 3.0


def test_zero_size_box_is_a_clear_error():
    tr = EcoTracker(preset("hc"))
    with pytest.raises(InputError, match="zero or negative size"):
        tr.initialize(texture(), [10, 10, 0, 20])
    with pytest.raises(InputError, match="four finite numbers"):
        tr.initialize(texture(), [10, 10, 5])
    with pytest.raises(InputError, match="initialize"):
        tr.predict(texture())


def test_bad_frames_are_clear_errors(colour_tracker):
    with pytest.raises(InputError, match="uint8"):
        colour_tracker.predict(texture().astype(np.float32))
    with pytest.raises(InputError, match="HxW"):
        colour_tracker.predict(np.zeros((10, 10, 4), np.uint8))


@pytest.mark.parametrize("box", [[-15.0, -10.0, 40.0, 30.0], [300.0, 220.0, 40.0, 40.0], [-100.0, 50.0, 30.0, 30.0]])
def test_box_partly_or_wholly_outside_the_image(box):
    img = texture(seed=6)
    tr = EcoTracker(preset("hc"))
    tr.initialize(img, box)
    for k in range(3):
        res = tr.track(shifted(img, k, 0))
        assert np.all(np.isfinite(res.box))
        assert 0 <= res.center[0] <= img.shape[1] - 1 and 0 <= res.center[1] <= img.shape[0] - 1


def test_tiny_target():
    img = texture(seed=7)
    tr = EcoTracker(preset("hc"))
    tr.initialize(img, [150.0, 110.0, 5.0, 4.0])
    assert tr.geom.patch >= np.sqrt(tr.params.min_sample_area)  # upsampled to the minimum sample area (150 px)
    pred = tr.predict(shifted(img, 1.5, -1.0))
    np.testing.assert_allclose(pred.center, [152.0 + 1.5, 111.5 - 1.0], atol=0.5)
    tr.update(img, pred.box)


def test_update_reuses_or_reextracts_the_sample(colour_tracker):
    import copy

    tr = copy.deepcopy(colour_tracker)
    frame = shifted(texture(), 1.0, 1.0)
    pred = tr.predict(frame)
    tr.update(frame, pred.box)  # reuse path
    assert tr.space.count == 2
    tr.update(frame, pred.box * [1, 1, 1.2, 1.2])  # different scale: fresh extraction
    assert tr.space.count == 3
    for _ in range(6):
        tr.update(frame, pred.box)  # reaches train_gap: filter refined
    assert tr.cg_state is not None


def test_fdsst_scale_filter_measures_a_zoom():
    from rgbt_toolkit.eco.scale_filter import ScaleFilter

    img = texture(seed=8)
    centre = np.array([119.5, 159.5])
    sf = ScaleFilter((40.0, 30.0))
    sf.initialize(img, centre, (40.0, 30.0))
    zoom = 1.08
    m = cv2.getRotationMatrix2D((159.5, 119.5), 0.0, zoom)
    zoomed = cv2.warpAffine(img, m, img.shape[1::-1], flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    assert sf.estimate(zoomed, centre, (40.0, 30.0)) == pytest.approx(zoom, abs=0.025)
    assert sf.estimate(img, centre, (40.0, 30.0)) == pytest.approx(1.0, abs=0.01)
    tr = EcoTracker(preset("hc").with_(scale_filter=True))
    tr.initialize(img, BOX)
    res = tr.track(shifted(img, 1.0, 1.0))
    assert res.scale_index == 0 and np.all(np.isfinite(res.box))


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_stays_on_target_in_a_generated_rgbt_scene(modality):
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    cfg = SceneConfig(seed=1, duration=1.5)
    scene = SceneRenderer(cfg)
    fps = cfg.rgb_fps if modality == "rgb" else cfg.t_fps
    frames = [scene.render(i / fps, modality, i) for i in range(int(cfg.duration * fps))]
    tr = EcoTracker(preset("hc"))
    tr.initialize(frames[0].image, frames[0].box)
    for f in frames[1:]:
        b, g = tr.track(f.image).box, f.box
        ix = max(0.0, min(b[0] + b[2], g[0] + g[2]) - max(b[0], g[0]))
        iy = max(0.0, min(b[1] + b[3], g[1] + g[3]) - max(b[1], g[1]))
        assert ix * iy / (b[2] * b[3] + g[2] * g[3] - ix * iy) > 0.7


def test_dark_colour_frames_are_brightened_before_features():
    from rgbt_toolkit.eco.tracker import normalise_exposure

    dark = np.full((40, 40, 3), 20, np.uint8)
    dark[10:20, 10:20] = (30, 5, 5)
    bright = normalise_exposure(dark, 110.0, 1.2)
    assert abs(float(bright.mean()) - 110.0) < 3.0 and bright[15, 15, 0] > bright[15, 15, 1]  # hue kept
    day = np.full((8, 8, 3), 100, np.uint8)
    assert normalise_exposure(day, 110.0, 1.2) is day  # a gain of 1.1 is left alone


def test_rgb_tracker_keeps_the_target_when_the_light_fails():
    """Generated scene whose RGB drops to night (gain 0.18, strong noise): exposure normalisation keeps ECO-hc on."""
    from rgbt_toolkit.evaluation.metrics import iou_continuous
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer

    renderer = SceneRenderer(SceneConfig(seed=2, challenges=frozenset({"low_light"})))
    frames = [renderer.render(k / 15, "rgb", k) for k in range(0, 60, 2)]
    tracker = EcoTracker(preset("hc"))
    tracker.initialize(frames[0].image, frames[0].box)
    overlaps = [iou_continuous(tracker.track(f.image).box[None], f.box[None])[0] for f in frames[1:]]
    assert np.mean(overlaps[-8:]) > 0.6  # the last frames are deep in the night
