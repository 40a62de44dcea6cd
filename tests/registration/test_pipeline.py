"""End to end on the project's synthetic RGB-T scenes, whose renderer records the true RGB->T homography."""

import numpy as np
import pytest

from rgbt_toolkit.errors import RegistrationError
from rgbt_toolkit.registration import (
    RegisterSettings, corner_error, estimate_transform, overlap_corner_error, register_streams,
)

synth = pytest.importorskip("rgbt_toolkit.synth")


def test_generated_pairs_median_corner_error_below_one_pixel():
    errors = []
    for seed in range(3):
        renderer = synth.SceneRenderer(synth.SceneConfig(seed=seed))
        rgb = renderer.render(1.0, "rgb").image
        thermal = renderer.render(1.0, "t").image
        result = estimate_transform([rgb], [thermal])
        errors.append(corner_error(result.matrix, renderer.h_rgb_to_t, renderer.config.rgb_size))
    assert np.median(errors) < 1.0, errors


def _stream(renderer, modality, fps, count, offset=0.0):
    """Frames as write_scene_videos makes them: frame j stamped j / fps shows scene time j / fps + offset."""
    frames = [renderer.render(j / fps + offset, modality, j).image for j in range(count)]
    return lambda: iter([(frame, j / fps) for j, frame in enumerate(frames)])


def test_streams_with_different_rates_and_clock_offset():
    # fast target motion gives both cameras clear motion events; the background stays put, so the spatial estimate
    # does not depend on the residual offset error (with the generator's drastic camera shakes it does, by ~2 px).
    # Seeds 0-5 whose clips hold a clear motion peak (--sync refuses 1 and 3). Corner errors 0.49 / 0.75 / 0.80 /
    # 1.80 px (a sparser last refinement level: 0.56 / 0.89 / 1.14 / 1.28, median 1.01)
    errors = []
    for seed in (0, 2, 4, 5):
        cfg = synth.SceneConfig(seed=seed, duration=5.0, rgb_fps=20.0, t_fps=15.0, t_offset=0.15,
                                challenges=frozenset({"fast_motion"}))
        renderer = synth.SceneRenderer(cfg)
        rgb = _stream(renderer, "rgb", cfg.rgb_fps, cfg.rgb_frame_count)
        thermal = _stream(renderer, "t", cfg.t_fps, cfg.t_frame_count, cfg.t_offset)
        reg = register_streams(rgb, thermal, RegisterSettings(sync=True, max_offset=1.0, max_pairs=3))
        # the thermal file stamps each event t_offset earlier: t_thermal = t_rgb - 0.15
        assert reg.calibration.time_offset == pytest.approx(-0.15, abs=1 / 20)
        # judged where the narrower thermal camera sees (RGB corners outside its view are extrapolation)
        errors.append(overlap_corner_error(reg.calibration.matrix, renderer.h_rgb_to_t, cfg.t_size))
        assert reg.calibration.pairs_used == 3 and reg.rgb_frames == 100 and reg.thermal_frames == 75
        assert np.all(np.abs(reg.pairing.gap) <= reg.pairing.tolerance)
    assert np.median(errors) < 1.0 and max(errors) < 2.0, np.round(errors, 2)


def test_single_frames_register_but_cannot_sync(make_pair):
    visible, thermal, truth = make_pair(3)
    one_rgb, one_t = (lambda: iter([(visible, 0.0)])), (lambda: iter([(thermal, 5.0)]))
    reg = register_streams(one_rgb, one_t)  # two stills pair whatever their nominal times
    assert corner_error(reg.calibration.matrix, truth, (visible.shape[1], visible.shape[0])) < 1.5
    with pytest.raises(RegistrationError, match="single frame carries no motion"):
        register_streams(one_rgb, one_t, RegisterSettings(sync=True))


def test_register_paths_decodes_grey_frames(monkeypatch, tmp_path):
    """Registration needs grey only; asking for it halves the decoding time (docs/benchmarks_registration.md)."""
    import rgbt_toolkit.io.frames as frames_module
    from rgbt_toolkit.registration import register_paths

    asked = []

    def spy(path, *, fps=None, grey=False):
        asked.append(grey)
        raise RuntimeError("stop here")

    monkeypatch.setattr(frames_module, "open_frames", spy)
    with pytest.raises(RuntimeError, match="stop here"):
        register_paths(tmp_path / "a.mp4", tmp_path / "b.mp4")
    assert asked == [True]


def _folder(path, frames):
    from rgbt_toolkit.io.images import write_image

    path.mkdir()
    for i, frame in enumerate(frames):
        write_image(path / f"{i:03d}.png", frame)
    return path


def test_frame_folders_at_their_own_rates(tmp_path, make_pair):
    from rgbt_toolkit.registration import register_paths

    visible, thermal, truth = make_pair(7)
    rgb = _folder(tmp_path / "rgb", [visible] * 6)
    t = _folder(tmp_path / "t", [thermal] * 5)
    reg = register_paths(rgb, t, RegisterSettings(max_pairs=2), rgb_fps=30.0, thermal_fps=25.0)
    np.testing.assert_allclose(np.diff(reg.rgb_times), 1 / 30)
    np.testing.assert_allclose(np.diff(reg.thermal_times), 1 / 25)
    assert len(reg.pairing) == 5  # each thermal frame (the slower camera) gets its nearest RGB frame
    assert corner_error(reg.calibration.matrix, truth, (visible.shape[1], visible.shape[0])) < 2.0
    rgb_t, thermal_t = reg.preview_times  # the preview shows a pair the estimate used, matched in time
    assert abs(rgb_t - thermal_t) <= reg.pairing.tolerance


def test_undecodable_frames_are_not_counted(tmp_path, make_pair):
    from rgbt_toolkit.io.video import CorruptFrameWarning
    from rgbt_toolkit.registration import register_paths

    visible, thermal, _ = make_pair(7)
    rgb = _folder(tmp_path / "rgb", [visible] * 5)
    t = _folder(tmp_path / "t", [thermal] * 4)
    (t / "004.png").write_bytes(b"not a png")
    with pytest.warns(CorruptFrameWarning):
        reg = register_paths(rgb, t, RegisterSettings(max_pairs=2))
    assert reg.thermal_frames == 4 and len(reg.pairing) == 4


def test_mixed_sizes_and_blank_frames_name_the_recording(tmp_path, make_pair):
    import cv2

    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.registration import register_paths

    visible, thermal, _ = make_pair(7)
    rgb = _folder(tmp_path / "rgb", [visible] * 4)
    small = cv2.resize(thermal, (thermal.shape[1] // 2, thermal.shape[0] // 2))
    mixed = _folder(tmp_path / "mixed", [thermal, small, thermal, small])
    with pytest.raises(InputError, match=rf"^{mixed}: frames differ in size \(\d+x\d+, \d+x\d+\)"):
        register_paths(rgb, mixed, RegisterSettings(max_pairs=4))
    blank = _folder(tmp_path / "blank", [np.zeros_like(thermal)] * 4)
    with pytest.raises(RegistrationError, match=rf"^{blank}: the 2 thermal frame\(s\) paired .* are blank"):
        register_paths(rgb, blank, RegisterSettings(max_pairs=2))


def test_pairs_are_limited():
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.registration.pipeline import MAX_PAIRS

    frames = lambda: iter([(np.zeros((32, 32), np.uint8), 0.0)])  # noqa: E731
    with pytest.raises(InputError, match=f"between 1 and {MAX_PAIRS}"):
        register_streams(frames, frames, RegisterSettings(max_pairs=MAX_PAIRS + 1))


def test_thermal_warm_up_frames_are_left_out_of_sync_and_pairs(monkeypatch):
    """A thermal camera blank for its first 2 s: the switch to the picture is no motion event, and the pairs come
    from the part that shows the scene."""
    cfg = synth.SceneConfig(seed=9, duration=6.0, rgb_fps=30.0, t_fps=25.0, t_offset=0.45,
                            challenges=frozenset({"camera_motion"}))
    renderer = synth.SceneRenderer(cfg)
    rgb = _stream(renderer, "rgb", cfg.rgb_fps, cfg.rgb_frame_count)
    live = _stream(renderer, "t", cfg.t_fps, cfg.t_frame_count, cfg.t_offset)
    thermal = lambda: ((np.full_like(f, 60) if t < 2.0 else f, t) for f, t in live())  # noqa: E731
    import rgbt_toolkit.registration.pipeline as pipeline

    given = []

    def spy(rgb_frames, thermal_frames, settings):
        given.extend(thermal_frames)
        return estimate_transform(rgb_frames, thermal_frames, settings)

    monkeypatch.setattr(pipeline, "estimate_transform", spy)
    reg = register_streams(rgb, thermal, RegisterSettings(sync=True, max_pairs=4))
    assert reg.calibration.time_offset == pytest.approx(-0.45, abs=1 / 25)
    assert len(given) == 4 and all(frame.std() > 5 for frame in given)  # no warm-up frame among the pairs
    assert reg.preview_times[1] >= 2.0
