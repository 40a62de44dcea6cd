"""Issue #20: a night-sky pair, where nothing is seen by both cameras, stops `rgbt track` before tracking.

The thermal camera sees a warm drone against a cold, low-texture sky (the generator's ``far_target`` scene); the RGB
camera, at night, sees only sensor noise and a few stars that are cold in thermal. The RGB frames are not blank, so
this is the evidence check refusing (``no reliable match``), not the blank-frame check that
``tests/cli/test_track_calibration_sources.py`` covers with a black RGB video.
"""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main

TRACK = ["--preset", "B-T", "--no-video", "--no-plot", "--max-frames", "3"]


@pytest.fixture(scope="module")
def night_sky(tmp_path_factory):
    """``scene_t.mp4`` (a far drone against a cold sky) and ``night_rgb.mp4`` (noise and stars), 1 s at 15 fps."""
    import cv2

    from rgbt_toolkit.io.video import write_video
    from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos

    folder = tmp_path_factory.mktemp("night_sky")
    renderer = SceneRenderer(SceneConfig(seed=3, duration=1.0, challenges=frozenset({"far_target"})))
    paths = write_scene_videos(renderer, folder)
    w, h = renderer.config.rgb_size
    rng = np.random.default_rng(0)
    stars = rng.integers(0, [w, h], (12, 2))
    frames = []
    for _ in range(15):
        sky = rng.normal(8.0, 2.0, (h, w))
        for x, y in stars:
            cv2.circle(sky, (int(x), int(y)), 1, 120, -1)
        frames.append(np.repeat(sky.clip(0, 255).astype(np.uint8)[:, :, None], 3, axis=2))
    write_video(folder / "night_rgb.mp4", frames, fps=15)
    return folder, paths["t"]


def test_night_rgb_is_not_blank(night_sky):
    """The refusal below must come from the evidence, not from the blank-frame check."""
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.registration.features import BLANK_GRADIENT_RMS, gradient_rms, to_grey

    folder, _ = night_sky
    frame, _ = next(iter(open_frames(folder / "night_rgb.mp4", grey=True)))
    assert gradient_rms(to_grey(frame)) > 2 * BLANK_GRADIENT_RMS


def test_night_sky_stops_track_before_tracking(night_sky):
    folder, thermal = night_sky
    out = folder / "out"
    result = CliRunner().invoke(main, ["track", str(folder / "night_rgb.mp4"), str(thermal), *TRACK, "-o", str(out)])
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1, result.output
    assert "no RGB->T transform (registration failed:" in lines[0]
    assert lines[0].count("registration failed") == 1, lines[0]
    assert "no reliable match between the RGB and thermal views" in lines[0], lines[0]
    assert "blank" not in lines[0]
    for remedy in ("--calib FILE", "--assume-aligned", "--points FILE", "--from-boxes", "--board COLSxROWS"):
        assert remedy in lines[0]
    assert "Traceback" not in result.output
    assert not out.exists()  # stopped before tracking: no folder, no boxes, no track.json
