"""skip_blocks: the low-bit-rate stream of the real Halmstad clips, where most 16x16 blocks repeat the last frame bit
for bit and the picture is refreshed whole every 128 frames. The stream model on scripted frames, the renderer's use
of it, and the property measured on a real clip beside the generated one."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.synth import SceneConfig, SceneRenderer
from rgbt_toolkit.synth.stream import SkipBlockStream
from tests.real_clips import real_clip

SMALL = dict(duration=4.0, rgb_size=(160, 128), t_size=(128, 96))


def _noisy(base: np.ndarray, rng: np.random.Generator, sigma: float = 3.0) -> np.ndarray:
    return np.clip(base + rng.normal(0, sigma, base.shape), 0, 255).astype(np.uint8)


def _repeated_blocks(a: np.ndarray, b: np.ndarray, block: int = 16) -> float:
    """Share of whole ``block`` x ``block`` blocks of two frames that are bit-identical."""
    if a.ndim == 3:
        a, b = a[..., 0], b[..., 0]
    h, w = a.shape[0] // block * block, a.shape[1] // block * block
    same = (a[:h, :w] == b[:h, :w]).reshape(h // block, block, w // block, block).all(axis=(1, 3))
    return float(same.mean())


def test_sensor_noise_alone_sends_no_block_between_refreshes():
    rng = np.random.default_rng(0)
    base = np.full((64, 96), 120.0)
    stream = SkipBlockStream(gop=8)
    first = stream.frame(_noisy(base, rng), 0)
    for index in range(1, 8):
        np.testing.assert_array_equal(stream.frame(_noisy(base, rng), index), first)
    refreshed = _noisy(base, rng)
    np.testing.assert_array_equal(stream.frame(refreshed, 8), refreshed)  # the next refresh shows the frame whole


def test_a_block_that_changes_is_sent_and_the_others_repeat():
    rng = np.random.default_rng(1)
    base = np.full((64, 96), 60.0)
    stream = SkipBlockStream()
    first = stream.frame(_noisy(base, rng), 0)
    moved = base.copy()
    moved[20:28, 36:44] = 220  # a hot 8x8 target inside block row 1, column 2
    image = _noisy(moved, rng)
    shown = stream.frame(image, 1)
    np.testing.assert_array_equal(shown[16:32, 32:48], image[16:32, 32:48])
    outside = np.ones(shown.shape, bool)
    outside[16:32, 32:48] = False
    np.testing.assert_array_equal(shown[outside], first[outside])
    # the target leaves: its block is sent again; a faint change stays stale
    back = base.copy()
    back[0:16, 0:16] += 5  # 5 grey levels: under the 8-level threshold
    image = _noisy(back, rng)
    shown = stream.frame(image, 2)
    np.testing.assert_array_equal(shown[16:32, 32:48], image[16:32, 32:48])
    np.testing.assert_array_equal(shown[0:16, 0:16], first[0:16, 0:16])


def test_partial_edge_blocks_and_colour_frames():
    rng = np.random.default_rng(2)
    base = np.full((40, 50, 3), 100.0)
    stream = SkipBlockStream()
    first = stream.frame(_noisy(base, rng), 0)
    changed = base.copy()
    changed[34:40, 45:50] = 250  # the bottom-right edge block is 8x2 px; the change fills most of it
    image = _noisy(changed, rng)
    shown = stream.frame(image, 1)
    np.testing.assert_array_equal(shown[32:, 48:], image[32:, 48:])
    np.testing.assert_array_equal(shown[:32], first[:32])


def test_frames_out_of_order_are_refused():
    stream = SkipBlockStream(gop=4)
    image = np.zeros((16, 16), np.uint8)
    stream.frame(image, 0)
    with pytest.raises(ValueError, match="replay from frame 0"):
        stream.frame(image, 2)
    stream.frame(image, 4)  # a refresh needs no past
    with pytest.raises(ValueError):
        SkipBlockStream(block=0)


def test_renderer_repeats_most_blocks_where_per_frame_noise_repeats_few():
    config = SceneConfig(challenges=frozenset({"real_sensor", "skip_blocks"}), seed=3, **SMALL)
    plain = SceneRenderer(SceneConfig(challenges=frozenset({"real_sensor"}), seed=3, **SMALL))
    streamed = SceneRenderer(config)
    fps = config.rgb_fps
    frames = [streamed.render(i / fps, "t", i).image for i in range(30)]
    truth = [plain.render(i / fps, "t", i).image for i in range(30)]
    np.testing.assert_array_equal(frames[0], truth[0])  # a refresh is the camera's own picture
    repeated = [_repeated_blocks(frames[i], frames[i - 1]) for i in range(1, 30)]
    assert np.median(repeated) > 0.8
    assert max(_repeated_blocks(truth[i], truth[i - 1]) for i in range(1, 30)) < 0.1  # per-frame noise: few


def test_a_slow_target_stands_still_on_some_frames_and_stays_within_a_block_of_the_truth():
    config = SceneConfig(challenges=frozenset({"skip_blocks"}), seed=5, **SMALL)
    renderer = SceneRenderer(config)
    frames = [renderer.render(i / config.t_fps, "t", i) for i in range(30)]
    hot = [f.image > 165 for f in frames]  # the target renders at >= ~178 grey, the background below ~150
    boxes = np.array([f.box for f in frames])
    assert np.all(np.abs(np.diff(boxes[:, :2], axis=0)).max(axis=1) > 0.05)  # the truth moves on every frame
    assert sum(np.array_equal(hot[i], hot[i - 1]) for i in range(1, 30)) >= 3  # what is shown does not
    for mask, box in zip(hot, boxes):
        ys, xs = np.nonzero(mask)
        assert abs(xs.min() - box[0]) < 16 and abs(xs.max() + 1 - box[0] - box[2]) < 16


def test_renderer_gives_the_same_frame_in_any_order():
    config = SceneConfig(challenges=frozenset({"skip_blocks"}), seed=4, **SMALL)
    fps = config.rgb_fps
    in_order = SceneRenderer(config)
    sequential = [in_order.render(i / fps, "rgb", i).image for i in range(12)]
    jumping = SceneRenderer(config)
    for i in (11, 5, 6, 0, 11):
        np.testing.assert_array_equal(jumping.render(i / fps, "rgb", i).image, sequential[i])


def test_generated_stream_repeats_blocks_as_the_real_clips_do(shared_dir):
    """A real thermal drone clip repeats most blocks from frame to frame; per-frame noise and JPEG blocking
    (real_sensor) repeat none; real_sensor with skip_blocks lands on the real side."""
    images, _ = real_clip(shared_dir, "svan_ir_drone_003", frames=40)
    real = np.median([_repeated_blocks(images[i], images[i - 1]) for i in range(1, 40)])
    assert real > 0.9
    for challenges, low, high in (({"real_sensor"}, 0.0, 0.05), ({"real_sensor", "skip_blocks"}, 0.8, 1.0)):
        config = SceneConfig(challenges=frozenset(challenges), seed=1, duration=3.0)
        renderer = SceneRenderer(config)
        frames = [renderer.render(i / config.t_fps, "t", i).image for i in range(40)]
        generated = np.median([_repeated_blocks(frames[i], frames[i - 1]) for i in range(1, 40)])
        assert low <= generated <= high, (challenges, generated)
