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
    # does not depend on the residual offset error (with the generator's drastic camera shakes it does, by ~2 px)
    cfg = synth.SceneConfig(seed=5, duration=5.0, rgb_fps=20.0, t_fps=15.0, t_offset=0.15,
                            challenges=frozenset({"fast_motion"}))
    renderer = synth.SceneRenderer(cfg)
    rgb = _stream(renderer, "rgb", cfg.rgb_fps, cfg.rgb_frame_count)
    thermal = _stream(renderer, "t", cfg.t_fps, cfg.t_frame_count, cfg.t_offset)
    reg = register_streams(rgb, thermal, RegisterSettings(sync=True, max_offset=1.0, max_pairs=3))
    # the thermal file stamps each event t_offset earlier: t_thermal = t_rgb - 0.15
    assert reg.calibration.time_offset == pytest.approx(-0.15, abs=1 / 20)
    # judged where the narrower thermal camera sees (RGB corners outside its view are extrapolation)
    assert overlap_corner_error(reg.calibration.matrix, renderer.h_rgb_to_t, cfg.t_size) < 1.5
    assert reg.calibration.pairs_used == 3 and reg.rgb_frames == 100 and reg.thermal_frames == 75
    assert np.all(np.abs(reg.pairing.gap) <= reg.pairing.tolerance)


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
