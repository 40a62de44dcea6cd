"""The challenges real footage has and the plain generator lacked: gimbal jumps, leaving the view, long occlusion,
real sensor artefacts and small far targets. Each test checks the rendered pixels against the truth."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.synth import SceneConfig, SceneRenderer
from rgbt_toolkit.synth.render import clip_box

SMALL = dict(duration=4.0, rgb_size=(160, 120), t_size=(128, 96))


def _scene(*challenges: str, seed: int = 3, **fields) -> SceneRenderer:
    return SceneRenderer(SceneConfig(challenges=frozenset(challenges), seed=seed, **{**SMALL, **fields}))


def _frames(renderer: SceneRenderer, modality: str, step: int = 1) -> list:
    fps = renderer.config.rgb_fps
    return [renderer.render(i / fps, modality, i) for i in range(0, renderer.config.rgb_frame_count, step)]


def _red(image: np.ndarray) -> np.ndarray:
    """The red jacket (TARGET_TOP is 0.85, 0.15, 0.10): no background patch is this red."""
    image = image.astype(int)
    return (image[:, :, 0] > 150) & (image[:, :, 1] < 90) & (image[:, :, 2] < 90)


def _hot(image: np.ndarray) -> np.ndarray:
    return image > 165  # the target renders at >= ~178 grey, the background and vehicles below ~150


def _centres(frames: list) -> np.ndarray:
    return np.array([f.box[:2] + f.box[2:] / 2 for f in frames])


# ----- gimbal_jump ------------------------------------------------------------------------------------------------
def test_gimbal_jump_moves_the_target_across_the_image_in_one_frame_in_both_cameras():
    renderer = _scene("gimbal_jump")
    width = renderer.config.rgb_size[0]
    rgb, thermal = _frames(renderer, "rgb"), _frames(renderer, "t")
    rgb_steps = np.linalg.norm(np.diff(_centres(rgb), axis=0), axis=1)
    t_steps = np.linalg.norm(np.diff(_centres(thermal), axis=0), axis=1)
    jumps = np.nonzero(rgb_steps > 0.2 * width)[0]
    assert 1 <= len(jumps) <= 3
    np.testing.assert_array_equal(np.nonzero(t_steps > 0.15 * width)[0], jumps)  # one gimbal: both jump together
    world = renderer.timeline.target_xy
    assert np.abs(np.diff(world, axis=0)).max() < 1.0  # the target itself walks smoothly
    assert sum(rgb[j + 1].flags["gimbal_jump"] for j in jumps) == len(jumps)
    for j in jumps:  # the truth follows the jump: the jacket is where the box says after it
        ys, xs = np.nonzero(_red(rgb[j + 1].image))
        x, y, w, h = rgb[j + 1].box
        assert abs(xs.min() - x) < 2.0 and abs(ys.min() - y) < 2.0 and abs(xs.max() + 1 - (x + w)) < 2.0


# ----- leave_view -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("modality, target_pixels", [("rgb", _red), ("t", _hot)])
def test_leave_view_truth_is_zero_exactly_while_no_target_pixel_is_in_the_image(modality, target_pixels):
    frames = _frames(_scene("leave_view"), modality)
    outside = [f for f in frames if f.flags["out_of_view"]]
    inside = [f for f in frames if not f.absent]
    assert 5 <= len(outside) <= len(frames) // 2
    for frame in outside:
        assert frame.absent and np.all(frame.box == 0)
        assert target_pixels(frame.image).sum() == 0
    for frame in inside:
        x, y, w, h = frame.box
        assert w > 0 and h > 0 and x >= 0 and y >= 0
        assert x + w <= frame.image.shape[1] + 1e-9 and y + h <= frame.image.shape[0] + 1e-9  # clipped to the image
        assert target_pixels(frame.image)[int(y): int(np.ceil(y + h)), int(x): int(np.ceil(x + w))].sum() > 0


def test_leave_view_comes_back():
    frames = _frames(_scene("leave_view"), "rgb")
    absent = np.array([f.absent for f in frames])
    first, last = np.nonzero(absent)[0][[0, -1]]
    assert np.all(absent[first: last + 1]) and not absent[:first].any() and not absent[last + 1:].any()
    assert last < len(frames) - 5  # back in view for the end of the sequence


def test_clip_box_keeps_the_inside_part_and_zeroes_a_box_wholly_outside():
    np.testing.assert_allclose(clip_box(np.array([-5.0, 10, 20, 10]), (100, 50))[0], [0, 10, 15, 10])
    np.testing.assert_allclose(clip_box(np.array([95.0, 45, 20, 10]), (100, 50))[0], [95, 45, 5, 5])
    box, outside = clip_box(np.array([100.0, 10, 20, 10]), (100, 50))
    assert outside and np.all(box == 0)


# ----- long_occlusion ---------------------------------------------------------------------------------------------
def test_long_occlusion_hides_the_target_in_both_cameras_for_one_to_two_seconds():
    renderer = _scene("long_occlusion")
    fps = renderer.config.rgb_fps
    rgb, thermal = _frames(renderer, "rgb"), _frames(renderer, "t")
    hidden = np.array([f.flags["long_occlusion"] for f in rgb])
    assert 1.0 <= hidden.sum() / fps <= 2.0 + 1 / fps
    unseen_unflagged = 0
    for frame_rgb, frame_t in zip(rgb, thermal):
        assert frame_rgb.absent == frame_t.absent == frame_rgb.flags["long_occlusion"]
        assert frame_rgb.box[2] > 0 and frame_t.box[2] > 0  # the box files keep where the hidden target is
        seen = _red(frame_rgb.image).sum() > 0 or _hot(frame_t.image).sum() > 0
        if frame_rgb.absent:
            assert _red(frame_rgb.image).sum() == 0 and _hot(frame_t.image).sum() == 0
        unseen_unflagged += not seen and not frame_rgb.absent
    assert unseen_unflagged <= 4  # only a sliver may show in the frames just before and after the flagged stretch


def test_long_occlusion_lasts_longer_than_the_crossing_occlusion():
    long_hidden = sum(f.absent for f in _frames(_scene("long_occlusion"), "t"))
    short = _scene("occlusion")
    crossing = sum(short.occlusion_fraction(i / 15) > 0.99 for i in range(short.config.rgb_frame_count))
    assert long_hidden > 2 * crossing


# ----- real_sensor ------------------------------------------------------------------------------------------------
def _stuck(frames: list) -> int:
    """Pixels at 0 or 255 in every frame (below the overlay, whose fixed characters stay too): dead or hot."""
    stack = np.stack([f.image if f.image.ndim == 2 else f.image[:, :, 1] for f in frames])
    stack = stack[:, stack.shape[1] // 6:]
    return int((np.all(stack == 0, axis=0) | np.all(stack == 255, axis=0)).sum())


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_real_sensor_has_dead_and_hot_pixels_that_stay_fixed(modality):
    assert _stuck(_frames(_scene("real_sensor"), modality, step=7)) >= 3
    assert _stuck(_frames(_scene(), modality, step=7)) == 0


@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_real_sensor_burns_a_changing_timestamp_into_the_top_left_corner(modality):
    real, plain = _scene("real_sensor"), _scene()
    a, b = real.render(0.0, modality, 0).image, real.render(1.0, modality, 15).image

    def text(image):
        grey = image if image.ndim == 2 else image.min(axis=2)
        h, w = grey.shape
        return grey[: h // 8, : 3 * w // 4] > 180  # white strokes, softened by the codec

    assert text(a).sum() > 20 and text(b).sum() > 20
    assert (text(a) != text(b)).sum() > 5  # the digits change
    assert text(plain.render(0.0, modality, 0).image).sum() < text(a).sum() / 4


def test_real_sensor_adds_column_stripes_to_thermal_and_keeps_the_truth():
    real, plain = _scene("real_sensor"), _scene()
    a, b = real.render(1.0, "t", 15), plain.render(1.0, "t", 15)
    np.testing.assert_array_equal(a.box, b.box)
    rows = slice(a.image.shape[0] // 6, None)  # below the overlay
    columns = (a.image[rows].astype(float) - b.image[rows]).mean(axis=0)
    stripes = columns - np.convolve(columns, np.ones(9) / 9, mode="same")
    assert stripes[8:-8].std() > 2.0


# ----- far_target -------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("modality", ["rgb", "t"])
def test_far_target_is_8_to_20_pixels_and_visible(modality):
    renderer = _scene("far_target")
    for frame in _frames(renderer, modality, step=6):
        x, y, w, h = frame.box
        assert 8 <= w <= 20 and 8 <= h <= 20, frame.box
        grey = frame.image.astype(float) if frame.image.ndim == 2 else frame.image.mean(axis=2)
        core = grey[int(y + h / 2) - 1: int(y + h / 2) + 2, int(x + w / 2) - 1: int(x + w / 2) + 2].mean()
        around = np.median(grey[max(int(y) - 15, 0): int(y + h) + 15, max(int(x) - 15, 0): int(x + w) + 15])
        assert (core > around + 60) if modality == "t" else (core < around - 60)  # warm in thermal, dark in RGB


def test_far_target_sky_has_little_texture():
    def texture(renderer):
        grey = renderer.render(0.0, "rgb", 0).image.mean(axis=2)
        return np.abs(np.diff(grey, axis=1)).mean()

    assert texture(_scene("far_target")) < 0.5 * texture(_scene())


# ----- the default scene and the CLI ------------------------------------------------------------------------------
def test_new_challenges_leave_the_other_time_functions_alone():
    plain, jumping = _scene("occlusion"), _scene("occlusion", "gimbal_jump", "real_sensor")
    np.testing.assert_array_equal(plain.timeline.target_xy, jumping.timeline.target_xy)
    np.testing.assert_array_equal(plain.timeline.occluder_x, jumping.timeline.occluder_x)
    assert plain.timeline.jump_times is None and plain.timeline.long_occluder_xy is None
    frame = plain.render(1.0, "rgb", 15)
    assert not frame.absent and "out_of_view" not in frame.flags and "gimbal_jump" not in frame.flags


def test_cli_renders_every_new_challenge_with_absent_frames_written(tmp_path):
    names = "gimbal_jump,leave_view,long_occlusion,real_sensor,far_target"
    result = CliRunner().invoke(main, ["synth", str(tmp_path), "--challenges", names, "--layout", "rgbt234",
                                       "--duration", "2", "--rgb-size", "96x72", "--t-size", "80x64"])
    assert result.exit_code == 0, result.output
    seq = tmp_path / "scene"
    truth = json.loads((seq / "scene.json").read_text())
    assert truth["config"]["challenges"] == sorted(names.split(","))
    for camera, boxes_file in (("rgb", "visible.txt"), ("t", "infrared.txt")):
        rows = np.loadtxt(seq / boxes_file, delimiter=",")
        frames = truth[camera]["frames"]
        assert len(rows) == len(frames) == len(list((seq / ("visible" if camera == "rgb" else "infrared")).iterdir()))
        outside = np.array(["out_of_view" in f["flags"] for f in frames])
        assert outside.any() and all(f["absent"] for f, out in zip(frames, outside) if out)
        np.testing.assert_array_equal(np.all(rows == 0, axis=1), outside)


# ----- appearance_change ------------------------------------------------------------------------------------------
def test_appearance_change_turns_the_visible_target_only():
    """The target's visible look drifts from the first frame's (colours swap, stripes turn) while its box and its
    thermal signature stay as without the challenge."""
    plain, turning = _scene(), _scene("appearance_change")
    duration = plain.config.duration

    def patch(renderer, t, modality):
        frame = renderer.render(t, modality)
        x, y, w, h = np.round(frame.box).astype(int)
        return frame.image[y:y + h, x:x + w].astype(float), frame.box

    start, start_box = patch(turning, 0.0, "rgb")
    np.testing.assert_array_equal(start, patch(plain, 0.0, "rgb")[0])  # the same first frame
    end, end_box = patch(turning, duration, "rgb")
    plain_end, plain_box = patch(plain, duration, "rgb")
    np.testing.assert_allclose(end_box, plain_box)
    assert np.abs(end - plain_end).mean() > 10  # another side shows by the end
    np.testing.assert_allclose(patch(turning, duration, "t")[0], patch(plain, duration, "t")[0], atol=1e-6)
