"""Live sources: frames that arrive at their own pace through named pipes and growing files (``rgbt track``
with pipes, ``--realtime``), streams cut inside a frame, and the reader's hand-over between threads."""

from __future__ import annotations

import io
import json
import os
import threading
import time
from pathlib import Path

import av
import numpy as np
import pytest
from click.testing import CliRunner

from rgbt_cli.main import main
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.live import Mailbox, is_live
from rgbt_toolkit.jmmac.pipeline import FrameResult

pytestmark = pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="named pipes need a POSIX system")

W, H, FPS, N = 160, 128, 30, 45
SIDE = 16


def square_x(k: int) -> int:
    """Where the bright square is in frame ``k``: its position says which frame a box came from."""
    return 8 + 3 * k


def scene(k: int) -> np.ndarray:
    frame = np.full((H, W, 3), 40, np.uint8)
    frame[56:56 + SIDE, square_x(k):square_x(k) + SIDE] = 220
    return frame


def encode(fmt: str, codec: str, count: int = N, scale: int = 1) -> tuple[bytes, list[int]]:
    """``count`` frames at FPS in a streaming container (``scale``: 1/scale of the size, a smaller thermal camera);
    the bytes and the offset where each frame's packet ends."""
    buffer = io.BytesIO()
    with av.open(buffer, "w", format=fmt) as out:
        stream = out.add_stream(codec, rate=FPS)
        stream.width, stream.height, stream.pix_fmt = W // scale, H // scale, "yuv420p"
        if codec == "mpeg4":
            stream.options = {"g": "1", "qscale": "2"}  # intra only: a frame decodes on arrival
        ends = []
        for k in range(count):
            frame = av.VideoFrame.from_ndarray(np.ascontiguousarray(scene(k)[::scale, ::scale]), format="rgb24")
            frame.pts = k
            for packet in stream.encode(frame):
                out.mux(packet)
            ends.append(buffer.tell())
        for packet in stream.encode():
            out.mux(packet)
    return buffer.getvalue(), ends


def feed(path: Path, data: bytes, pieces: int = N, fps: float = FPS, mode: str = "wb") -> threading.Thread:
    """Write ``data`` to ``path`` in ``pieces`` chunks at ``fps``, from a thread (a camera at its own pace)."""
    def run() -> None:
        try:
            with open(path, mode, buffering=0) as sink:
                step = -(-len(data) // pieces)
                for start in range(0, len(data), step):
                    sink.write(data[start:start + step])
                    sink.flush()
                    time.sleep(1 / fps)
        except BrokenPipeError:  # the reader stopped early: the test says whether that was right
            pass

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def pipes(tmp_path: Path, data: bytes, cut: int | None = None, thermal: bytes | None = None):
    """Two named pipes fed with the same stream, or ``thermal`` for the second (cameras started together)."""
    paths = []
    for name in ("cam_rgb.ts", "cam_t.ts"):
        os.mkfifo(tmp_path / name)
        paths.append(tmp_path / name)
    payloads = [data if cut is None else data[:cut], thermal if thermal is not None else data]
    payloads[1] = payloads[1] if cut is None else payloads[1][:cut]
    writers = [feed(p, payload) for p, payload in zip(paths, payloads)]
    return paths, writers


class CentroidTracker:
    """Finds the bright square (its centroid) in the RGB frame, after ``delay`` seconds of "work"."""

    def __init__(self, delay: float = 0.0):
        from rgbt_toolkit.jmmac import preset

        self.config = preset("B-T")
        self.camera_motion = None
        self.delay = delay
        self.box = np.zeros(4)

    def initialize(self, rgb, thermal, box):
        self.box = np.asarray(box, float)
        return FrameResult(0, self.box.copy(), "init")

    def track(self, rgb, thermal):
        time.sleep(self.delay)
        rows, cols = np.nonzero(rgb[..., 0] > 130)
        self.box = np.array([cols.mean() - (SIDE - 1) / 2, rows.mean() - (SIDE - 1) / 2, SIDE, SIDE])
        return FrameResult(0, self.box.copy(), "appearance")


@pytest.fixture
def tracker(monkeypatch):
    import rgbt_toolkit.jmmac.api as api

    made = CentroidTracker()
    monkeypatch.setattr(api, "build_tracker", lambda config, **options: made)
    return made


def track_args(paths, out, *extra):
    return ["track", str(paths[0]), str(paths[1]), "--init", f"{square_x(0)},56,{SIDE},{SIDE}", "--assume-aligned",
            "--no-video", "--no-plot", "-o", str(out), *extra]


def check_rows_match_timestamps(out: Path) -> list[dict]:
    """Every record's box is the square of the frame its timestamp names, and box files have one row per record."""
    track = json.loads((out / "track.json").read_text())
    frames = track["frames"]
    boxes = read_boxes(out / "boxes_rgb.txt")
    assert len(boxes) == len(frames) == track["summary"]["frames"]
    source_frames = np.array([round(r["time"] * FPS) for r in frames])
    np.testing.assert_allclose([r["time"] for r in frames], source_frames / FPS, atol=1e-3)
    np.testing.assert_allclose(boxes[:, 0], [square_x(k) for k in source_frames], atol=1.0)
    assert np.all(np.diff(source_frames) > 0)
    return frames


def test_pipes_at_their_own_pace_track_every_frame(tmp_path, tracker):
    data, _ = encode("mpegts", "mpeg4")
    paths, writers = pipes(tmp_path, data)
    started = time.monotonic()
    result = CliRunner().invoke(main, track_args(paths, tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert time.monotonic() - started > (N - 5) / FPS  # it waited for the frames as they came
    frames = check_rows_match_timestamps(tmp_path / "out")
    assert len(frames) == N and [round(r["time"] * FPS) for r in frames] == list(range(N))
    summary = json.loads((tmp_path / "out" / "track.json").read_text())["summary"]
    assert summary["dropped_frames"] == 0 and "dropped" not in result.output
    assert "live sources: read once" in result.output
    for writer in writers:
        writer.join(5)


def test_realtime_drops_frames_a_slow_tracker_cannot_keep_up_with(tmp_path, tracker):
    tracker.delay = 0.1  # 10 frames/s against a 30 frames/s source
    data, _ = encode("mpegts", "mpeg4")
    paths, _ = pipes(tmp_path, data)
    result = CliRunner().invoke(main, track_args(paths, tmp_path / "out", "--realtime"))
    assert result.exit_code == 0, result.output
    frames = check_rows_match_timestamps(tmp_path / "out")
    summary = json.loads((tmp_path / "out" / "track.json").read_text())["summary"]
    dropped = summary["dropped_frames"]
    assert dropped >= N // 2 and len(frames) + dropped == N  # each pair either tracked or counted as dropped
    assert f"{dropped} dropped to keep up (--realtime)" in result.output
    # latency stays bounded: the newest pair is tracked, so the last record is one of the last frames sent
    assert round(frames[-1]["time"] * FPS) >= N - 4


def test_without_realtime_a_slow_tracker_drops_nothing(tmp_path, tracker):
    tracker.delay = 0.05
    data, _ = encode("mpegts", "mpeg4", count=20)
    paths, _ = pipes(tmp_path, data)
    result = CliRunner().invoke(main, track_args(paths, tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert len(check_rows_match_timestamps(tmp_path / "out")) == 20


def test_a_stream_cut_inside_a_frame_ends_the_run_cleanly(tmp_path, tracker):
    data, ends = encode("nut", "rawvideo", count=20)
    cut = ends[16] + (ends[17] - ends[16]) // 2  # half of frame 17's packet
    paths, _ = pipes(tmp_path, data, cut=cut)
    result = CliRunner().invoke(main, track_args(paths, tmp_path / "out"))
    assert result.exit_code == 0, result.output
    assert "the stream ended inside a frame; that incomplete frame was dropped" in result.output
    frames = check_rows_match_timestamps(tmp_path / "out")
    assert len(frames) == 17  # frames 0-16: complete outputs up to the last whole frame
    track = json.loads((tmp_path / "out" / "track.json").read_text())
    assert any("inside a frame" in note for note in track["summary"]["source_notes"])
    assert not list((tmp_path / "out").glob(".*partial*"))


def test_a_growing_file_is_followed_until_it_stops_growing(tmp_path, monkeypatch):
    import rgbt_toolkit
    import rgbt_toolkit.io.live as live
    import rgbt_toolkit.jmmac.api as api

    monkeypatch.setattr(live, "STALL_SECONDS", 1.0)
    monkeypatch.setattr(api, "build_tracker", lambda config, **options: CentroidTracker())
    data, _ = encode("mpegts", "mpeg4")
    paths = [tmp_path / "rec_rgb.ts", tmp_path / "rec_t.ts"]
    head = len(data) // 4  # the recorder has written a quarter when tracking starts
    for path in paths:
        path.write_bytes(data[:head])
    for path in paths:
        feed(path, data[head:], pieces=3 * N // 4, mode="ab")
    result = rgbt_toolkit.track(str(paths[0]), str(paths[1]), init=(square_x(0), 56, SIDE, SIDE),
                                assume_aligned=True, realtime=True)
    assert len(result.frames) + result.summary["dropped_frames"] == N  # to the end of the file, not its first quarter
    times = np.array([r.time for r in result.frames])
    # the first box is the given one, on whichever pair was newest when tracking started (on a busy machine the
    # live reader may already have dropped frame 0); every later box follows the target at its frame's time
    np.testing.assert_allclose(result.boxes_rgb[1:, 0], [square_x(k) for k in np.round(times[1:] * FPS)], atol=1.0)


def test_live_sources_need_the_geometry_up_front(tmp_path, tracker):
    data, _ = encode("mpegts", "mpeg4", count=3)
    paths, writers = pipes(tmp_path, data)
    args = track_args(paths, tmp_path / "out")
    args.remove("--assume-aligned")
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 1 and "Traceback" not in result.output
    assert "its registration cannot be estimated" in result.output and "--assume-aligned" in result.output
    for path in paths:  # let the writers finish: nobody opened the pipes
        with open(path, "rb") as drain:
            drain.read()
    for writer in writers:
        writer.join(5)
    assert not (tmp_path / "out").exists()


def test_a_missing_source_is_named(tmp_path):
    result = CliRunner().invoke(main, ["track", str(tmp_path / "nope_rgb.ts"), str(tmp_path / "nope_t.ts"),
                                       "--assume-aligned"])
    assert result.exit_code == 1 and "nope_rgb.ts: no such file or folder" in result.output


def test_what_counts_as_live(tmp_path):
    os.mkfifo(tmp_path / "pipe")
    (tmp_path / "file.mp4").write_bytes(b"x")
    assert is_live("rtsp://camera.local:554/stream1") and is_live("udp://@:1234") and is_live("/dev/video0")
    assert is_live(tmp_path / "pipe")
    assert not is_live(tmp_path / "file.mp4") and not is_live(tmp_path) and not is_live(tmp_path / "missing.ts")


def test_mailbox_keeps_the_newest_and_counts_the_rest():
    stop = threading.Event()
    latest = Mailbox(2, keep_latest=True)
    for k in range(5):
        assert latest.put(k, stop)
    latest.close()
    assert latest.get() == 4 and latest.dropped == 4 and latest.get() is not None

    bounded = Mailbox(2)
    assert bounded.put(0, stop) and bounded.put(1, stop)
    waiting = threading.Thread(target=bounded.put, args=(2, stop))
    waiting.start()
    waiting.join(0.2)
    assert waiting.is_alive()  # full: the producer waits (back-pressure) ...
    assert bounded.get() == 0
    waiting.join(1)
    assert not waiting.is_alive() and bounded.get() == 1 and bounded.get() == 2 and bounded.dropped == 0


def test_live_pairs_feed_the_streaming_tracker(tmp_path, tracker):
    """The loop docs/api.md shows: frames from two pipes, paired by time, into ``Tracker``."""
    import rgbt_toolkit
    from rgbt_toolkit.io.live import LivePairs, open_live

    data, _ = encode("mpegts", "mpeg4", count=20)
    paths, _ = pipes(tmp_path, data)
    streaming = rgbt_toolkit.Tracker(preset="B-T", assume_aligned=True)
    times, xs = [], []
    with LivePairs(open_live(paths[0]), open_live(paths[1])) as frames:
        for k, (rgb_frame, thermal_frame, time_s) in enumerate(frames):
            assert rgb_frame.shape == (H, W, 3) and thermal_frame.shape == (H, W, 3)
            step = (streaming.initialize(rgb_frame, thermal_frame, (square_x(0), 56, SIDE, SIDE)) if k == 0
                    else streaming.track(rgb_frame, thermal_frame))
            times.append(time_s)
            xs.append(step.box_rgb[0])
    assert frames.dropped == 0
    np.testing.assert_allclose(times, np.arange(20) / FPS, atol=1e-3)
    np.testing.assert_allclose(xs, [square_x(k) for k in range(20)], atol=1.0)


def test_stopping_early_releases_the_sources(tmp_path, tracker):
    """--max-frames ends the run; the readers stop and close the pipes, so the cameras' writers are not left hanging."""
    data, _ = encode("mpegts", "mpeg4")
    paths, writers = pipes(tmp_path, data)
    result = CliRunner().invoke(main, track_args(paths, tmp_path / "out", "--max-frames", "5"))
    assert result.exit_code == 0, result.output
    assert len(read_boxes(tmp_path / "out" / "boxes_rgb.txt")) == 5
    for writer in writers:
        writer.join(3)  # a writer whose reader went away gets a broken pipe and ends
        assert not writer.is_alive()


def test_a_calibrated_rig_with_a_smaller_thermal_camera(tmp_path, tracker):
    """--calib with --realtime: the thermal stream is half the size; boxes_t is the RGB box through the calibration."""
    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    calib = tmp_path / "rig.json"
    save_calibration(calib, Calibration(np.diag([0.5, 0.5, 1.0]), "affine", (W, H), (W // 2, H // 2)))
    data, _ = encode("mpegts", "mpeg4", count=20)
    thermal, _ = encode("mpegts", "mpeg4", count=20, scale=2)
    paths, _ = pipes(tmp_path, data, thermal=thermal)
    args = track_args(paths, tmp_path / "out", "--realtime", "--calib", str(calib))
    args.remove("--assume-aligned")
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    frames = check_rows_match_timestamps(tmp_path / "out")
    assert len(frames) + json.loads((tmp_path / "out" / "track.json").read_text())["summary"]["dropped_frames"] == 20
    np.testing.assert_allclose(read_boxes(tmp_path / "out" / "boxes_t.txt"),
                               read_boxes(tmp_path / "out" / "boxes_rgb.txt") * 0.5, atol=0.02)
