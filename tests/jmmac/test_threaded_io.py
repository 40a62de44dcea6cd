"""Threaded I/O of ``rgbt track`` (issue #21): a reader thread decodes and prepares frames ahead, a writer thread
encodes annotated.mp4. Same files as the single-threaded path, and a Ctrl-C, a tracker error or a writer error ends
the run with complete (or dropped) files, no temporaries and no thread left behind."""

from __future__ import annotations

import dataclasses
import errno
import hashlib
import json
import os
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io import video as video_module
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import ThreadedVideoWriter, VideoReader, VideoWriteError
from rgbt_toolkit.jmmac import preset
from rgbt_toolkit.jmmac.inputs import ReadAhead, resolve_inputs
from rgbt_toolkit.jmmac.pipeline import FrameResult
from rgbt_toolkit.jmmac.run import run_tracking
from rgbt_toolkit.runtime import BACKGROUND_NICE
from rgbt_toolkit.synth import SceneConfig, SceneRenderer, write_scene_videos

FRAMES = 12


@pytest.fixture(scope="module")
def wide_pair(tmp_path_factory):
    """800x448 RGB (wider than 640 px: tracked at a working scale) + 320x256 thermal at another rate."""
    renderer = SceneRenderer(SceneConfig(duration=FRAMES / 10, rgb_fps=10, t_fps=8, rgb_size=(800, 448),
                                         t_size=(320, 256), seed=4))
    return renderer, write_scene_videos(renderer, tmp_path_factory.mktemp("wide"), "w")


class DigestTracker:
    """A tracker stand-in whose boxes follow the pixels it is given, so equal box files mean equal frames reached it.

    It also reports a camera shift (the tail and shift drawing paths run) and can fail or be interrupted on a given
    call of ``track``."""

    def __init__(self, fail_at: int | None = None, interrupt_at: int | None = None):
        self.config = dataclasses.replace(preset("B-RGB"), camera_motion=True)
        self.camera_motion = object()  # "estimated": the harness then asks for camera_shift
        self.camera_shift = np.zeros(2)
        self.box: np.ndarray | None = None
        self.fail_at, self.interrupt_at = fail_at, interrupt_at
        self.calls = 0
        self.digests: list[str] = []

    def _result(self, index: int, rgb: np.ndarray, thermal: np.ndarray, mode: str) -> FrameResult:
        self.digests.append(hashlib.sha1(rgb.tobytes() + thermal.tobytes()).hexdigest())
        return FrameResult(index, self.box.copy(), mode, q=float(rgb.mean()), w_g=float(thermal.mean()) / 255,
                           w_f=np.full((5, 5), 0.5))

    def initialize(self, rgb, thermal, box):
        self.box = np.asarray(box, float).copy()
        return self._result(0, rgb, thermal, "init")

    def track(self, rgb, thermal):
        self.calls += 1
        if self.calls == self.fail_at:
            raise RuntimeError("tracker exploded")
        if self.calls == self.interrupt_at:
            raise KeyboardInterrupt
        step = np.array([rgb.mean() % 1.0 - 0.5, thermal.mean() % 1.0 - 0.5]) * 4  # from the pixels
        self.box[:2] += step
        self.camera_shift = self.camera_shift + step[::-1]
        return self._result(self.calls, rgb, thermal, "appearance")


def _inputs(wide_pair, *, gap_at: int | None = None):
    renderer, paths = wide_pair
    inputs = resolve_inputs(paths["rgb"], paths["t"], h_rgb_to_t=renderer.h_rgb_to_t)
    if gap_at is not None:  # an unreadable pair: the harness repeats the last box and panel
        def with_gap(pairs):
            for k, (rgb, thermal, stamp) in enumerate(pairs):
                yield (None, None, stamp) if k == gap_at else (rgb, thermal, stamp)

        inputs.pairs = with_gap(inputs.pairs)
    return inputs


def _run(*args, **kwargs) -> dict:
    """run_tracking with a deadline (a hang fails the test instead of stalling the suite) and a check that every
    thread it started has ended when it returns or raises."""
    before = set(threading.enumerate())
    outcome: dict = {}

    def body():
        try:
            outcome["summary"] = run_tracking(*args, **kwargs)
        except BaseException as exc:  # noqa: BLE001 - handed to the test thread
            outcome["error"] = exc

    worker = threading.Thread(target=body)
    worker.start()
    worker.join(120)
    assert not worker.is_alive(), "run_tracking did not return within 120 s"
    left = [t for t in threading.enumerate() if t not in before]
    assert not left, f"threads left alive: {left}"
    if "error" in outcome:
        raise outcome["error"]
    return outcome["summary"]


def _video_frames(path: Path) -> list[np.ndarray]:
    return [frame for frame, _ in VideoReader(path)]


def _no_temporaries(folder: Path) -> None:
    assert not [p.name for p in folder.iterdir() if p.name.startswith(".")]


def test_threaded_and_single_threaded_runs_write_identical_files(wide_pair, tmp_path):
    runs = {}
    for name, threads in (("sync", False), ("threads", True)):
        tracker = DigestTracker()
        summary = _run(_inputs(wide_pair, gap_at=5), tracker, tmp_path / name, io_threads=threads, video_scale=0.5,
                       plot=False)
        assert summary["frames"] == FRAMES and summary["modes"]["skipped"] == 1 and summary["io_threads"] is threads
        runs[name] = tracker.digests
        _no_temporaries(tmp_path / name)
    assert runs["sync"] == runs["threads"] and len(runs["sync"]) == FRAMES - 1  # the same pixels reached the tracker
    for name in ("boxes_rgb.txt", "boxes_t.txt"):
        assert (tmp_path / "sync" / name).read_bytes() == (tmp_path / "threads" / name).read_bytes()
    records = {name: json.loads((tmp_path / name / "track.json").read_text()) for name in runs}
    for record in records["sync"]["frames"] + records["threads"]["frames"]:
        record.pop("timing_ms")
    assert records["sync"]["frames"] == records["threads"]["frames"]
    assert records["threads"]["summary"]["background_ms_per_frame"].keys() == {"read_prepare", "encode"}
    assert records["threads"]["video_scale"] == 0.5
    sync, threaded = _video_frames(tmp_path / "sync" / "annotated.mp4"), \
        _video_frames(tmp_path / "threads" / "annotated.mp4")
    assert len(sync) == len(threaded) == FRAMES
    assert all(np.array_equal(a, b) for a, b in zip(sync, threaded))
    scale = records["sync"]["working_scale"]
    assert 0.7 < scale < 1.0  # the working scale applies, and the video is half of it
    assert sync[0].shape[0] == pytest.approx(448 * scale * 0.5, abs=2)


def test_video_scale_shrinks_the_annotated_video_and_bad_scales_are_refused(wide_pair, tmp_path):
    _run(_inputs(wide_pair), DigestTracker(), tmp_path / "full", plot=False, max_frames=3)
    _run(_inputs(wide_pair), DigestTracker(), tmp_path / "small", plot=False, max_frames=3, video_scale=0.25)
    full, small = VideoReader(tmp_path / "full" / "annotated.mp4"), VideoReader(tmp_path / "small" / "annotated.mp4")
    assert small.size[1] == pytest.approx(full.size[1] / 4, abs=2) and small.frame_count == 3
    # the encoder's preset and quality are the caller's: a high crf writes a smaller file of the same frames
    _run(_inputs(wide_pair), DigestTracker(), tmp_path / "coarse", plot=False, max_frames=3, video_preset="medium",
         video_crf=40)
    coarse = tmp_path / "coarse" / "annotated.mp4"
    assert VideoReader(coarse).frame_count == 3
    assert coarse.stat().st_size < (tmp_path / "full" / "annotated.mp4").stat().st_size
    for bad in (0.0, 1.5, float("nan")):
        with pytest.raises(InputError, match="video scale must be in"):
            run_tracking(_inputs(wide_pair), DigestTracker(), tmp_path / "bad", video_scale=bad)


def test_a_wide_pair_is_drawn_at_most_1280_px_wide_unless_told_otherwise(tmp_path):
    """By default a panel wider than PANEL_MAX_WIDTH (a 1920x1080 RGB camera's working frame beside its thermal
    view) is drawn at the scale that makes it that wide, and track.json records that scale; ``video_scale=1`` draws
    the working frame's full size."""
    from rgbt_toolkit.jmmac.annotate import PANEL_MAX_WIDTH, panel_width
    from rgbt_toolkit.jmmac.working_scale import working_size

    renderer = SceneRenderer(SceneConfig(duration=0.4, rgb_fps=10, t_fps=10, rgb_size=(1920, 1080),
                                         t_size=(1280, 720), seed=4))
    pair = renderer, write_scene_videos(renderer, tmp_path / "in", "w")
    _run(_inputs(pair), DigestTracker(), tmp_path / "auto", plot=False, max_frames=3)
    _run(_inputs(pair), DigestTracker(), tmp_path / "full", plot=False, max_frames=3, video_scale=1.0)
    meta = {name: json.loads((tmp_path / name / "track.json").read_text()) for name in ("auto", "full")}
    working = working_size((1920, 1080), meta["full"]["working_scale"])
    wide = panel_width(working, (1280, 720))
    assert wide > PANEL_MAX_WIDTH and meta["full"]["video_scale"] == 1.0
    full, auto = (VideoReader(tmp_path / name / "annotated.mp4") for name in ("full", "auto"))
    assert full.size[0] in (wide, wide + 1)  # yuv420p pads an odd width by a pixel
    assert PANEL_MAX_WIDTH - 4 <= auto.size[0] <= PANEL_MAX_WIDTH and auto.frame_count == 3
    assert meta["auto"]["video_scale"] == pytest.approx(PANEL_MAX_WIDTH / wide, abs=1e-6)


def test_the_thermal_box_is_drawn_where_it_is_when_the_thermal_folder_is_decoded_smaller(tmp_path):
    """1920x1080 JPEG folders of both cameras tracked at a 640x360 working frame: the thermal frames are decoded at
    half size, while the thermal box is in the camera's pixels. The panel draws it at the camera's scale (it was
    drawn twice as far from the corner, off the view for a target at the centre)."""
    import cv2

    from rgbt_toolkit.io.boxes import read_boxes as read_box_file

    rng = np.random.default_rng(3)
    for name in ("rgb", "t"):
        (tmp_path / name).mkdir()
        for k in range(4):
            frame = rng.integers(60, 140, (1080, 1920), dtype=np.uint8)
            cv2.imwrite(str(tmp_path / name / f"{k:03d}.jpg"), frame if name == "t" else np.dstack([frame] * 3))
    inputs = resolve_inputs(tmp_path / "rgb", tmp_path / "t", init=np.array([860.0, 440, 200, 200]),
                            h_rgb_to_t=np.eye(3))
    _run(inputs, DigestTracker(), tmp_path / "out", plot=False)
    meta = json.loads((tmp_path / "out" / "track.json").read_text())
    assert meta["working_scale"] == pytest.approx(1 / 3) and meta["video_scale"] == 1.0
    assert inputs.sources[1].target_size == (960, 540)  # the thermal folder was read at half size
    boxes_t = read_box_file(tmp_path / "out" / "boxes_t.txt")
    for k, (panel, _) in enumerate(VideoReader(tmp_path / "out" / "annotated.mp4").frames()):
        if k == 0:  # the first frame's box is drawn white (mode "init")
            continue
        view = panel[:, 640:1280].astype(int)
        green = (view[:, :, 1] > 150) & (view[:, :, 0] < 120) & (view[:, :, 2] < 120)
        rows, cols = np.nonzero(green)
        x, y, w, h = boxes_t[k] / 3  # camera pixels -> the 640x360 thermal view
        assert abs(cols.min() - x) <= 2 and abs(cols.max() - (x + w)) <= 3
        assert abs(rows.min() - y) <= 2 and abs(rows.max() - (y + h)) <= 3


@pytest.mark.parametrize("io_threads", [True, False])
def test_ctrl_c_in_the_tracker_closes_every_file_complete(wide_pair, tmp_path, io_threads):
    out = tmp_path / "out"
    summary = _run(_inputs(wide_pair), DigestTracker(interrupt_at=6), out, io_threads=io_threads, plot=False)
    assert summary["interrupted"] and summary["frames"] == 6 and summary["error"] is None
    assert read_boxes(out / "boxes_rgb.txt").shape == (6, 4) and read_boxes(out / "boxes_t.txt").shape == (6, 4)
    track = json.loads((out / "track.json").read_text())
    assert track["summary"]["interrupted"] is True and len(track["frames"]) == 6
    assert VideoReader(out / "annotated.mp4").frame_count == 6  # the queued frames were encoded before closing
    _no_temporaries(out)


def test_ctrl_c_in_the_reader_thread_reaches_the_loop(wide_pair, tmp_path, interrupt_after):
    inputs = _inputs(wide_pair)

    inputs.pairs = interrupt_after(inputs.pairs, 4)
    summary = _run(inputs, DigestTracker(), tmp_path / "out", plot=False)
    assert summary["interrupted"] and summary["frames"] == 4
    assert VideoReader(tmp_path / "out" / "annotated.mp4").frame_count == 4
    _no_temporaries(tmp_path / "out")


@pytest.mark.parametrize("io_threads", [True, False])
def test_tracker_error_closes_the_files_and_is_raised(wide_pair, tmp_path, io_threads):
    out = tmp_path / "out"
    with pytest.raises(RuntimeError, match="tracker exploded"):
        _run(_inputs(wide_pair), DigestTracker(fail_at=4), out, io_threads=io_threads)
    track = json.loads((out / "track.json").read_text())
    assert track["summary"]["error"] == "tracker exploded" and len(track["frames"]) == 4
    assert read_boxes(out / "boxes_rgb.txt").shape == (4, 4)
    assert VideoReader(out / "annotated.mp4").frame_count == 4
    _no_temporaries(out)


def _full_disk_after(monkeypatch, frames: int) -> None:
    """The encoder fails with ENOSPC on frame ``frames`` (0-based), whichever thread it runs on."""
    original = video_module.VideoWriter.write

    def write(self, frame):
        if self.frames_written == frames:
            raise OSError(errno.ENOSPC, "No space left on device")
        original(self, frame)

    monkeypatch.setattr(video_module.VideoWriter, "write", write)


@pytest.mark.parametrize("io_threads", [True, False])
def test_writer_error_stops_the_run_drops_the_video_and_keeps_the_rest(wide_pair, tmp_path, monkeypatch, io_threads):
    _full_disk_after(monkeypatch, 3)
    out = tmp_path / "out"
    with pytest.raises(VideoWriteError, match=r"annotated\.mp4: cannot write the video \(No space left on device\)"):
        _run(_inputs(wide_pair), DigestTracker(), out, io_threads=io_threads)
    assert not (out / "annotated.mp4").exists() and not (out / "track.png").exists()
    track = json.loads((out / "track.json").read_text())
    assert "No space left on device" in track["summary"]["error"]
    rows = len(track["frames"])
    assert 3 <= rows < FRAMES  # stopped soon after the failure (the writer thread reports it at the next hand-over)
    assert read_boxes(out / "boxes_rgb.txt").shape == (rows, 4) and read_boxes(out / "boxes_t.txt").shape == (rows, 4)
    _no_temporaries(out)


def test_writer_error_when_closing_the_video_is_raised_after_the_other_files(wide_pair, tmp_path, monkeypatch):
    def close(self):
        raise OSError(errno.EIO, "Input/output error")

    monkeypatch.setattr(video_module.VideoWriter, "close", close)
    out = tmp_path / "out"
    with pytest.raises(VideoWriteError, match=r"annotated\.mp4: cannot write the video \(Input/output error\)"):
        _run(_inputs(wide_pair), DigestTracker(), out, plot=False)
    track = json.loads((out / "track.json").read_text())
    assert len(track["frames"]) == FRAMES and "Input/output error" in track["summary"]["error"]
    assert not (out / "annotated.mp4").exists()
    _no_temporaries(out)


def test_threaded_writer_hands_a_failure_to_the_caller_without_hanging(tmp_path, monkeypatch):
    _full_disk_after(monkeypatch, 0)
    writer = ThreadedVideoWriter(tmp_path / "v.mp4", 10, queue_size=1)
    frame = np.zeros((32, 32, 3), np.uint8)
    with pytest.raises(VideoWriteError, match="No space left"):
        for _ in range(50):  # the queue fills while nobody encodes: write must notice the dead writer
            writer.write(frame)
    writer.abort()
    assert not writer._thread.is_alive() and list(tmp_path.iterdir()) == []


def test_read_ahead_keeps_order_honours_the_limit_and_stops_its_source():
    closed = []

    def source():
        try:
            yield from range(100)
        finally:
            closed.append(True)

    with ReadAhead(source(), lambda k: k * 2, depth=2, limit=10) as reader:
        assert list(reader) == [2 * k for k in range(10)]
    assert closed == [True] and not reader._thread.is_alive()
    reader = ReadAhead(source(), depth=2)
    assert next(reader) == 0
    reader.close()  # stopped while the thread waits on a full queue
    assert closed == [True, True] and not reader._thread.is_alive()
    with pytest.raises(InputError, match="bad frame"):
        list(ReadAhead(_failing(), depth=3))


def _failing():
    yield 1
    raise InputError("bad frame")


def test_the_writer_thread_draws_each_panel_once_and_repeats_it_for_a_skipped_frame(tmp_path):
    """run_tracking hands the video a LazyPanel: drawn on the writer thread, in frame order, once."""
    from rgbt_toolkit.jmmac.frame_steps import LazyPanel

    drawn = []

    def draw(index):
        drawn.append((index, threading.current_thread().name))
        return np.full((16, 16, 3), 40 * index, np.uint8)

    panels = [LazyPanel(draw, k) for k in range(3)]
    writer = ThreadedVideoWriter(tmp_path / "v.mp4", 10)
    for panel in panels + [panels[-1]]:  # an unreadable frame repeats the last panel
        writer.write(panel)
    assert all(name != threading.current_thread().name for _, name in drawn)  # nothing drawn by the caller
    writer.close()
    assert [index for index, _ in drawn] == [0, 1, 2]  # in order, the repeated panel not drawn again
    assert all(name.startswith("rgbt-video-writer") for _, name in drawn)
    assert panels[-1]() is panels[-1]()
    frames = _video_frames(tmp_path / "v.mp4")
    assert len(frames) == 4 and np.array_equal(frames[2], frames[3])


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="per-thread nice values are Linux's")
def test_reader_and_writer_threads_run_nicer_than_the_tracking_thread(tmp_path):
    """The tracker gets the cores first; the caller's own priority is left as it was."""
    own = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    seen = []

    def nice_of_this_thread(item):
        seen.append(os.getpriority(os.PRIO_PROCESS, threading.get_native_id()))
        return item

    assert list(ReadAhead(range(3), nice_of_this_thread, depth=2)) == [0, 1, 2]
    assert seen and all(n == min(19, own + BACKGROUND_NICE) for n in seen)
    seen.clear()
    writer = ThreadedVideoWriter(tmp_path / "v.mp4", 10)
    writer.write(lambda: nice_of_this_thread(np.zeros((16, 16, 3), np.uint8)))  # drawn on the writer thread
    writer.close()
    assert seen == [min(19, own + BACKGROUND_NICE)]
    assert list(ReadAhead(range(2), nice_of_this_thread, nice=0)) == [0, 1] and seen[-1] == own
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == own
