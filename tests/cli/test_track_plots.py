"""The pictures the tracking commands leave: ``rgbt track``'s track.png and ``rgbt track-single --plot``."""

from __future__ import annotations

import numpy as np
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.video import write_video

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _videos(tmp_path, n=12):
    rng = np.random.default_rng(0)
    base = (rng.integers(0, 255, (60, 80)) // 4 * 4).astype(np.uint8)
    frames = [np.roll(np.stack([base] * 3, axis=2), k, axis=1) for k in range(n)]
    write_video(tmp_path / "a_rgb.mp4", frames, fps=10)
    write_video(tmp_path / "a_t.mp4", frames, fps=10)
    return [str(tmp_path / "a_rgb.mp4"), str(tmp_path / "a_t.mp4"), "--init", "30,20,12,12", "--preset", "B-T",
            "--no-video", "--assume-aligned"]  # the same frames in both: registered by construction


def test_track_writes_track_png_unless_told_not_to(tmp_path):
    args = _videos(tmp_path)
    result = CliRunner().invoke(main, ["track", *args, "-o", str(tmp_path / "out")])
    assert result.exit_code == 0, result.output
    png = tmp_path / "out" / "track.png"
    assert png.read_bytes()[:8] == PNG_SIGNATURE and png.stat().st_size > 20_000
    assert f"plot: {png}" in result.output
    result = CliRunner().invoke(main, ["track", *args, "-o", str(tmp_path / "out")])
    assert result.exit_code == 1 and "track.png" in result.output  # an earlier run's picture is not overwritten
    result = CliRunner().invoke(main, ["track", *args, "-o", str(tmp_path / "out"), "--force", "--no-plot"])
    assert result.exit_code == 0, result.output
    assert not png.exists()  # forced without a picture: the earlier run's one does not stay beside the new boxes


def _frames(tmp_path, n=6):
    """The track-single tests' moving-patch frame folder (one definition, in tests/eco)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "eco"))
    from test_cli_track_single import _folder

    return _folder(tmp_path, n)


def test_track_single_draws_the_run_with_plot(tmp_path):
    folder = _frames(tmp_path)
    out, png = tmp_path / "boxes.txt", tmp_path / "run.png"
    args = ["track-single", str(folder), "--init", "40,30,16,20", "-o", str(out)]
    result = CliRunner().invoke(main, [*args, "--plot", str(png)])
    assert result.exit_code == 0, result.output
    assert png.read_bytes()[:8] == PNG_SIGNATURE and png.stat().st_size > 20_000
    assert len(out.read_text().splitlines()) == 6
    result = CliRunner().invoke(main, [*args, "--force", "--plot", str(out)])
    assert result.exit_code == 1 and "--plot names another output file" in result.output
    png.write_bytes(b"keep")  # an existing picture is not overwritten without --force, and checked before tracking
    result = CliRunner().invoke(main, ["track-single", str(folder), "--init", "40,30,16,20", "-o",
                                       str(tmp_path / "other.txt"), "--plot", str(png)])
    assert result.exit_code == 1 and f"{png}: already exists" in result.output and png.read_bytes() == b"keep"
    assert not (tmp_path / "other.txt").exists()
