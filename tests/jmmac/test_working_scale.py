"""Large frames are tracked at a working scale (``jmmac.working_scale``): the scale rule, the box and warp geometry,
and a real run whose boxes agree with a full-resolution run while only shrunk frames reach the tracker."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

from rgbt_toolkit.evaluation.metrics import iou_continuous
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import VideoReader
from rgbt_toolkit.jmmac.inputs import resolve_inputs
from rgbt_toolkit.jmmac.working_scale import ScaledTracker, scale_box, shrink, working_scale
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos


def test_scale_rule():
    assert working_scale((640, 480), np.array([0, 0, 200, 200])) == 1.0  # small frames are never shrunk
    # 1080p, 200x200 target: search side 800 px -> 250 / 800, but never narrower than 640 px
    assert working_scale((1920, 1080), np.array([0, 0, 200, 200])) == pytest.approx(1 / 3)
    assert working_scale((1920, 1080), np.array([0, 0, 500, 500])) == pytest.approx(1 / 3)
    assert working_scale((1280, 720), np.array([0, 0, 100, 100])) == pytest.approx(0.625)  # 250 / 400
    assert working_scale((1920, 1080), np.array([0, 0, 20, 20])) == 1.0  # a small target keeps its pixels


def test_box_geometry_follows_cv2_resize():
    image = np.zeros((400, 600), np.uint8)
    box = np.array([120.0, 80.0, 60.0, 100.0])
    image[80:180, 120:180] = 255
    small = shrink(image, 0.5)
    rows, cols = np.nonzero(small > 127)
    expected = scale_box(box, 0.5)
    assert (cols.min(), rows.min(), cols.max() - cols.min() + 1, rows.max() - rows.min() + 1) == \
        pytest.approx(tuple(expected), abs=0.5)
    np.testing.assert_allclose(scale_box(scale_box(box, 0.37), 1 / 0.37), box, atol=1e-9)


@pytest.fixture(scope="module")
def rig_pair(tmp_path_factory):
    out = tmp_path_factory.mktemp("rig720")
    renderer = SceneRenderer(SceneConfig(rgb_size=(1280, 720), t_size=(640, 512), duration=1.2, rgb_fps=10,
                                         t_fps=10, seed=4, target_size=(0.12, 0.3)))
    return renderer, write_scene_videos(renderer, out, "r")


def test_thermal_is_warped_straight_into_the_working_geometry(rig_pair):
    renderer, paths = rig_pair
    inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)
    thermal = renderer.render(0.0, "t", 0).image
    direct = inputs.thermal_in_rgb(thermal, 0.5)
    two_steps = shrink(inputs.thermal_in_rgb(thermal), 0.5)
    assert direct.shape == two_steps.shape == (360, 640)
    inner = (slice(20, -20), slice(20, -20))  # away from the replicated border
    assert np.mean(np.abs(direct[inner].astype(float) - two_steps[inner])) < 4.0


def test_a_large_pair_is_tracked_at_the_working_scale_with_the_same_boxes(rig_pair, tmp_path, monkeypatch):
    from rgbt_toolkit.api.tracking import tracker_from_options
    from rgbt_toolkit.jmmac import pipeline
    from rgbt_toolkit.jmmac.run import run_tracking

    renderer, paths = rig_pair
    seen = []
    original = pipeline.JmmacTracker.track

    def spy(self, rgb, thermal, **kwargs):
        seen.append((rgb.shape[:2], thermal.shape[:2]))
        return original(self, rgb, thermal, **kwargs)

    monkeypatch.setattr(pipeline.JmmacTracker, "track", spy)
    runs = {}
    for name, full in (("work", False), ("full", True)):
        inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)
        run_tracking(inputs, tracker_from_options("+TMP"), tmp_path / name, full_resolution=full, plot=False)
        runs[name] = read_boxes(tmp_path / name / "boxes_rgb.txt")
    track = json.loads((tmp_path / "work" / "track.json").read_text())
    scale = track["working_scale"]
    assert 0.5 <= scale < 1.0
    size = (int(round(720 * scale)), int(round(1280 * scale)))
    assert seen[0] == (size, size) and seen[-1] == ((720, 1280), (720, 1280))
    truth = read_boxes(paths["rgb"].with_name("r_rgb.boxes.txt"))
    n = len(runs["work"])
    assert n == 12 and np.mean(iou_continuous(runs["work"], runs["full"])) > 0.9
    assert np.mean(iou_continuous(runs["work"], truth[:n])) > 0.8
    assert VideoReader(tmp_path / "work" / "annotated.mp4").size[1] == size[0]  # drawn on the working frame


def test_scaled_tracker_reports_full_resolution_geometry():
    class Inner:
        config = "cfg"
        box = np.array([10.0, 20.0, 30.0, 40.0])
        camera_shift = np.array([5.0, -2.0])
        camera_motion = "cme"

    scaled = ScaledTracker(Inner(), 0.5)
    np.testing.assert_allclose(scaled.box, scale_box(Inner.box, 2.0))
    np.testing.assert_allclose(scaled.camera_shift, [10.0, -4.0])
    assert scaled.config == "cfg" and scaled.camera_motion == "cme"
    assert cv2 is not None


@pytest.mark.parametrize("shape, factor", [((1080, 1920, 3), 0.3858), ((1080, 1920), 1 / 3), ((721, 1279), 0.4),
                                           ((512, 640), 0.5), ((1080, 1920, 3), 0.5257)])
def test_shrink_takes_a_block_mean_first_and_keeps_the_output_geometry(shape, factor, monkeypatch):
    from rgbt_toolkit.io import images as module  # shrink's resampling: io.images.shrink_to

    sizes, interpolations = [], []
    real_resize = module.cv2.resize

    class SpyCv2:
        INTER_AREA = cv2.INTER_AREA
        INTER_LINEAR = cv2.INTER_LINEAR

        @staticmethod
        def resize(img, size, interpolation):
            sizes.append(size)
            interpolations.append(interpolation)
            return real_resize(img, size, interpolation=interpolation)

    monkeypatch.setattr(module, "cv2", SpyCv2)
    rng = np.random.default_rng(0)
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    smooth = (128 + 100 * np.sin(xx / 23.0) * np.cos(yy / 17.0)).astype(np.uint8)
    image = smooth if len(shape) == 2 else np.stack([smooth, 255 - smooth, smooth // 2], axis=-1)
    image = np.clip(image + rng.integers(-3, 4, image.shape), 0, 255).astype(np.uint8)
    size = (int(round(shape[1] * factor)), int(round(shape[0] * factor)))
    direct = cv2.resize(image, size, interpolation=cv2.INTER_AREA)
    got = shrink(image, factor)
    k = int(1 / factor + 1e-9)
    while shape[0] % k or shape[1] % k:
        k -= 1
    assert sizes[0] == ((shape[1] // k, shape[0] // k) if k > 1 else size)  # the whole-factor block mean first
    assert got.shape == direct.shape and got.dtype == np.uint8
    # the same picture: a block mean then the rest of the way differs from one area pass only in rounding/weights
    assert np.mean(np.abs(got.astype(float) - direct)) < 1.0
    if factor in (1 / 3, 0.5):  # a whole factor is a single block mean: identical
        np.testing.assert_array_equal(got, direct)
    if k == 1 and factor >= 0.5:  # a mild reduction is one bilinear pass (OpenCV's general area path is 6x slower)
        assert interpolations == [cv2.INTER_LINEAR]


def test_the_working_scale_follows_the_trackers_sample_patch():
    """JMMAC's hc trackers sample at most 190 x 190 px, deep 250 x 250: shrinking a 1080p frame for 250 px under hc
    kept pixels ECO never used."""
    from rgbt_toolkit.api.tracking import tracker_from_options
    from rgbt_toolkit.jmmac.working_scale import sample_side

    hc, deep = tracker_from_options("default"), tracker_from_options("default", features="deep")
    assert sample_side(hc) == pytest.approx(190.0) and sample_side(deep) == pytest.approx(250.0)
    assert sample_side(object()) == 250.0  # a stand-in without ECO parts: the largest preset's
    box = np.array([900.0, 500.0, 124.0, 114.0])  # search region 4 sqrt(w h) = 476 px
    assert working_scale((1920, 1080), box, sample_side=sample_side(hc)) == pytest.approx(190 / 475.6, rel=1e-3)


def test_thermal_frames_decoded_reduced_warp_to_the_same_working_frame(tmp_path):
    """A thermal folder of 1920x1080 frames mapped into a working frame at 0.42: decoded at half size (still more
    than one thermal pixel per working pixel) and warped from there, the same picture as the whole frame warped."""
    import cv2

    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.jmmac.track_inputs import TrackInputs

    yy, xx = np.mgrid[:1080, :1920]
    thermal = (128 + 100 * np.sin(xx / 40.0) * np.cos(yy / 30.0)).astype(np.uint8)
    folder = tmp_path / "t"
    folder.mkdir()
    for k in range(3):
        cv2.imwrite(str(folder / f"{k}.jpg"), np.roll(thermal, 7 * k, axis=1), [cv2.IMWRITE_JPEG_QUALITY, 95])
    h = np.array([[1.5, -0.05, -468.0], [0.05, 1.5, -332.0], [0.0, 0.0, 1.0]])  # a similarity: RGB -> thermal px
    t_source = open_frames(folder, auto_grey=True)
    inputs = TrackInputs("x", iter(()), (1920, 1080), (1920, 1080), 30.0, 3, h, np.array([900, 500, 124, 114.0]),
                         "test", sources=(open_frames(folder), t_source))
    inputs.decode_for(0.42)
    assert t_source.target_size == (960, 540)  # 1.5 / 0.42 = 3.6 thermal px per working px: 1/2, not 1/4
    reduced = [inputs.thermal_in_rgb(frame, 0.42) for frame, _ in t_source]
    whole = [inputs.thermal_in_rgb(np.roll(thermal, 7 * k, axis=1), 0.42) for k in range(3)]
    for a, b in zip(reduced, whole):
        assert a.shape == b.shape == (454, 806)
        assert np.abs(a.astype(float) - b).mean() < 2.0
    # the affine shortcut gives warpPerspective's pixels
    straight = cv2.warpPerspective(np.roll(thermal, 7, axis=1), h @ np.array([[1 / 0.42, 0, (0.5 - 0.21) / 0.42],
                                                                               [0, 1 / 0.42, (0.5 - 0.21) / 0.42],
                                                                               [0, 0, 1.0]]),
                                   (806, 454), flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                   borderMode=cv2.BORDER_REPLICATE)
    assert np.abs(whole[1].astype(int) - straight).max() <= 1
