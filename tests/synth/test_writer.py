"""Writing a scene to disk: all files appear together or not at all, existing outputs are refused, bad options are
one line (``rgbt synth`` through click's runner, and the library writers)."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.errors import InputError
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_sequence, write_scene_videos

SMALL = ["--duration", "0.4", "--rgb-size", "64x48", "--t-size", "48x40"]


def _synth(*args):
    return CliRunner().invoke(main, ["synth", *map(str, args)])


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _interrupt_after(monkeypatch, calls: int, stop) -> None:
    """Make the renderer call ``stop()`` on its ``calls``-th frame, as Ctrl-C or a SIGTERM would arrive mid-run."""
    render, count = SceneRenderer.render, [0]

    def render_then_stop(self, *args, **kwargs):
        count[0] += 1
        if count[0] == calls:
            stop()
        return render(self, *args, **kwargs)

    monkeypatch.setattr(SceneRenderer, "render", render_then_stop)


def _ctrl_c():
    raise KeyboardInterrupt


@pytest.mark.parametrize("layout", ["videos", "rgbt234"])
def test_interrupted_run_leaves_the_earlier_scene_as_it_was(tmp_path, monkeypatch, layout):
    """Ctrl-C once left a truncated scene_rgb.mp4 beside the earlier scene's thermal video and ground truth."""
    assert _synth(tmp_path, "--layout", layout, *SMALL).exit_code == 0
    before = _snapshot(tmp_path)
    _interrupt_after(monkeypatch, 4, _ctrl_c)
    cfg = SceneConfig(seed=5, duration=1.0, rgb_size=(64, 48), t_size=(48, 40))
    with pytest.raises(KeyboardInterrupt):
        if layout == "videos":
            write_scene_videos(SceneRenderer(cfg), tmp_path, force=True)
        else:
            write_scene_sequence(SceneRenderer(cfg), tmp_path / "scene", force=True)
    assert _snapshot(tmp_path) == before  # no hidden staging folder either


def test_interrupted_run_in_a_new_folder_leaves_nothing(tmp_path, monkeypatch):
    _interrupt_after(monkeypatch, 7, _ctrl_c)
    result = _synth(tmp_path / "new" / "out", *SMALL)
    assert result.exit_code != 0 and list(tmp_path.iterdir()) == []


def test_sigterm_removes_the_partial_files(tmp_path, monkeypatch):
    _interrupt_after(monkeypatch, 3, lambda: os.kill(os.getpid(), signal.SIGTERM))
    result = _synth(tmp_path / "out", *SMALL)
    assert result.exit_code == 128 + signal.SIGTERM and list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # the handler does not outlive the command


@pytest.mark.parametrize("layout, existing", [("videos", "scene_rgb.mp4"), ("rgbt234", "scene/visible")])
def test_existing_scene_is_refused_without_force(tmp_path, layout, existing):
    assert _synth(tmp_path, "--layout", layout, *SMALL).exit_code == 0
    before = _snapshot(tmp_path)
    result = _synth(tmp_path, "--layout", layout, *SMALL, "--seed", "3")
    assert result.exit_code == 1 and result.output.strip() == f"Error: {tmp_path / existing}: already exists; " \
                                                              "pass --force to overwrite"
    assert _snapshot(tmp_path) == before


def test_forced_sequence_drops_the_earlier_frames(tmp_path):
    """A 1-s sequence written over a 2-s one once kept 30 images in visible/ beside a 15-row visible.txt."""
    assert _synth(tmp_path, "--layout", "rgbt234", *SMALL[2:], "--duration", "0.8").exit_code == 0
    (tmp_path / "scene" / "notes.md").write_text("mine")  # not ours: stays
    result = _synth(tmp_path, "--layout", "rgbt234", *SMALL[2:], "--duration", "0.4", "--force")
    assert result.exit_code == 0, result.output
    seq = tmp_path / "scene"
    assert len(list((seq / "visible").iterdir())) == len(list((seq / "infrared").iterdir())) == 6
    assert len((seq / "visible.txt").read_text().splitlines()) == 6
    assert sorted(p.name for p in seq.iterdir()) == ["infrared", "infrared.txt", "init.txt", "notes.md",
                                                    "scene.json", "visible", "visible.txt"]


@pytest.mark.parametrize("args, says", [
    (["--duration", "0.1", "--rgb-fps", "1"], "duration 0.1 s at 1 fps gives no RGB frame"),
    (["--duration", "0.1", "--rgb-fps", "1", "--layout", "rgbt234"], "duration 0.1 s at 1 fps gives no RGB frame"),
    (["--duration", "0.1", "--t-fps", "1"], "duration 0.1 s at 1 fps gives no thermal frame"),
    (["--rgb-size", "321x241"], "RGB size 321x241: MP4 video needs an even width and height; choose e.g. 320x240"),
    (["--t-size", "255x192"], "thermal size 255x192: MP4 video needs an even width and height"),
    (["--aligned", "--t-size", "100x80"], "--aligned sets the thermal size to the RGB size"),
    (["--layout", "rgbt234", "--t-offset", "1"], "--t-offset and --t-fps apply to the videos layout only"),
    (["--layout", "rgbt234", "--t-fps", "10"], "--t-offset and --t-fps apply to the videos layout only"),
    *[(["--name", name, "--layout", layout], f"name '{name}' is not a plain file name")
      for name in ("../escaped", "a/b", "", ".", "..") for layout in ("videos", "rgbt234")],
])
def test_bad_options_are_one_line_and_write_nothing(tmp_path, args, says):
    result = _synth(tmp_path / "out", *args)
    assert result.exit_code == 1 and says in result.output and len(result.output.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_odd_sizes_are_fine_as_jpeg_frames(tmp_path):
    result = _synth(tmp_path, "--layout", "rgbt234", "--rgb-size", "65x49", "--t-size", "49x41", "--duration", "0.2")
    assert result.exit_code == 0, result.output
    from rgbt_toolkit.io.images import read_image

    assert read_image(tmp_path / "scene" / "visible" / "00001v.jpg").shape[:2] == (49, 65)


def test_library_refuses_a_name_that_is_a_path(tmp_path):
    with pytest.raises(InputError, match="not a plain file name"):
        write_scene_videos(SceneRenderer(SceneConfig(duration=0.2)), tmp_path, "../up")


def test_help_explains_rates_and_the_offset_sign():
    text = " ".join(CliRunner().invoke(main, ["synth", "--help"]).output.split())
    assert "RGB camera frame rate" in text and "Thermal camera frame rate" in text
    assert "`register --sync` reports about -T_OFFSET" in text and "--force" in text


def test_guide_lists_every_challenge_and_option():
    from rgbt_toolkit.synth import CHALLENGES

    guide = (Path(__file__).parents[2] / "docs" / "guide.md").read_text()
    section = guide.split("## `rgbt synth`")[1].split("\n## ")[0]
    assert [n for n in (*CHALLENGES, "--aligned", "--force", "--name") if n not in section] == []
