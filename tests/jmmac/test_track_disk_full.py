"""`rgbt track` on a full disk (issue #42 item 4): the error names the file, and no partial record is left.

The full disk is a stand-in for ``open`` in the outputs module whose files raise ``ENOSPC`` (as the kernel does) once
one chosen file has taken a hundred characters, or when it is closed (the last buffered lines), so no root or tiny
file system is needed. The kernel's error names no file, and the run writes hidden ``.track.json.partial``-style
temporaries beside the final names: both are what these tests hold to account.
"""

from __future__ import annotations

import builtins
import errno
from pathlib import Path

import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.jmmac import outputs
from rgbt_toolkit.jmmac.inputs import resolve_inputs
from rgbt_toolkit.jmmac.run import run_tracking
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos

from .test_run_harness import _oracle

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
STREAMED = ("boxes_rgb.txt", "boxes_t.txt", "track.json")


class _FullFile:
    """A text file that runs out of space after ``room`` characters, or only when it is closed (``room`` None)."""

    def __init__(self, handle, room: int | None):
        self.handle, self.room = handle, room

    def _full(self) -> OSError:
        return OSError(errno.ENOSPC, "No space left on device")  # the kernel's error names no file

    def write(self, text: str) -> int:
        if self.room is not None:
            if len(text) > self.room:
                raise self._full()
            self.room -= len(text)
        return self.handle.write(text)

    def close(self) -> None:
        self.handle.close()
        if self.room is None:
            raise self._full()


def _fill_disk(monkeypatch, name: str, room: int | None) -> None:
    """Make the streamed file ``name`` hit a full disk (see :class:`_FullFile`)."""
    def fake_open(path, *args, **kwargs):
        handle = builtins.open(path, *args, **kwargs)
        return _FullFile(handle, room) if Path(path).name == f".{name}.partial" else handle

    monkeypatch.setattr(outputs, "open", fake_open, raising=False)


@pytest.fixture(scope="module")
def scene(tmp_path_factory):
    renderer = SceneRenderer(SceneConfig(duration=1.0, rgb_fps=10, t_fps=10, seed=2))
    return renderer, write_scene_videos(renderer, tmp_path_factory.mktemp("scene"), "s")


@pytest.mark.parametrize("room", [100, None], ids=["mid-run", "at-close"])
@pytest.mark.parametrize("name", STREAMED)
def test_a_full_disk_names_the_file_and_leaves_no_record(scene, tmp_path, monkeypatch, name, room):
    renderer, paths = scene
    inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)
    _fill_disk(monkeypatch, name, room)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space left on device") as caught:
        run_tracking(inputs, _oracle(renderer), out, plot=False)
    assert caught.value.filename == str(out / name)
    assert not out.exists(), list(out.iterdir())  # made by the run, and nothing of it left: no box file, no hidden temporary


def test_a_full_disk_keeps_an_existing_folder_and_its_files(scene, tmp_path, monkeypatch):
    renderer, paths = scene
    out = tmp_path / "out"
    out.mkdir()
    (out / "notes.txt").write_text("mine\n")
    _fill_disk(monkeypatch, "boxes_t.txt", None)
    with pytest.raises(OSError, match="No space left on device"):
        run_tracking(resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t), _oracle(renderer),
                     out, plot=False)
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt"]


def test_track_on_a_full_disk_is_one_line_naming_the_file(tmp_path, monkeypatch):
    _fill_disk(monkeypatch, "track.json", 2000)
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["track", str(SAMPLES / "demo_rgb.mp4"), str(SAMPLES / "demo_t.mp4"),
                                       "--max-frames", "8", "--no-video", "--no-plot", "-o", str(out)])
    assert result.exit_code == 1, result.output
    assert result.output.strip().splitlines()[-1] == f"Error: {out / 'track.json'}: No space left on device"
    assert not out.exists()


def test_an_atomic_write_on_a_full_disk_names_the_file(tmp_path, monkeypatch):
    from rgbt_toolkit._atomic import write_text_atomic

    def full(self, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(Path, "write_text", full)
    with pytest.raises(OSError, match="No space left on device") as caught:
        write_text_atomic(tmp_path / "summary.json", "{}")
    assert caught.value.filename == str(tmp_path / "summary.json") and list(tmp_path.iterdir()) == []


def test_a_full_disk_at_the_anti_uav_files_leaves_no_record(scene, tmp_path, monkeypatch):
    from rgbt_toolkit.io import anti_uav

    real, calls = anti_uav.write_anti_uav_result, []

    def second_one_full(path, *args, **kwargs):
        calls.append(path)
        if len(calls) == 2:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(path, *args, **kwargs)

    monkeypatch.setattr(anti_uav, "write_anti_uav_result", second_one_full)
    renderer, paths = scene
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space left on device") as caught:
        run_tracking(resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t), _oracle(renderer),
                     out, plot=False, anti_uav=True)
    assert caught.value.filename.endswith("_IR.json") and calls[0].exists() is False and not out.exists()
