"""Frame sources keep the place of an unreadable frame when asked, and refuse a stream whose frame size changes."""

from __future__ import annotations

import av
import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.io.frames import open_frames
from rgbt_toolkit.io.images import write_image
from rgbt_toolkit.io.video import CorruptFrameWarning, write_video


def _frames(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(0)
    return [(rng.random((48, 64, 3)) * 255).astype(np.uint8) for _ in range(n)]


def _folder(tmp_path, n=6):
    folder = tmp_path / "f"
    folder.mkdir()
    for k, frame in enumerate(_frames(n)):
        write_image(folder / f"{k}.png", frame)
    return folder


def test_unreadable_folder_frame_keeps_its_place_only_when_asked(tmp_path):
    folder = _folder(tmp_path)
    (folder / "3.png").write_text("not a picture")
    with pytest.warns(CorruptFrameWarning, match="3.png"):
        dropped = [t for _, t in open_frames(folder)]
    assert len(dropped) == 5 and 3 / 30 not in dropped
    with pytest.warns(CorruptFrameWarning, match="3.png"):
        kept = list(open_frames(folder, keep_gaps=True))
    assert len(kept) == 6 and kept[3][0] is None and kept[3][1] == pytest.approx(3 / 30)
    assert all(frame is not None for k, (frame, _) in enumerate(kept) if k != 3)


def test_frames_lost_to_a_corrupt_video_packet_keep_their_place(tmp_path):
    path = tmp_path / "v.mp4"
    write_video(path, _frames(12), fps=10)
    with av.open(str(path)) as container:
        packets = [(p.pos, p.size) for p in container.demux(container.streams.video[0]) if p.size]
    data = bytearray(path.read_bytes())
    pos, size = packets[6]
    data[pos:pos + size] = np.random.default_rng(1).integers(0, 256, size, dtype=np.uint8).tobytes()
    path.write_bytes(bytes(data))
    with pytest.warns(CorruptFrameWarning, match="undecodable packet"):
        plain = list(open_frames(path))
    with pytest.warns(CorruptFrameWarning, match="undecodable packet"):
        kept = list(open_frames(path, keep_gaps=True))
    lost = 12 - len(plain)
    assert lost >= 1 and len(kept) == 12  # every nominal frame has an entry again
    assert sum(frame is None for frame, _ in kept) == lost
    np.testing.assert_allclose([t for _, t in kept], np.arange(12) / 10, atol=1e-6)


def test_a_long_interval_of_a_variable_rate_video_is_not_a_lost_frame(tmp_path):
    """Only undecodable packets open a gap: a 100-ms interval among 33-ms ones, all frames intact, adds no row."""
    from fractions import Fraction

    path = tmp_path / "vfr.mp4"
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=30)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "yuv420p"
        stream.time_base = Fraction(1, 1000)
        for pts, image in zip([0, 33, 67, 100, 200, 233, 267, 300, 333, 367], _frames(10)):
            frame = av.VideoFrame.from_ndarray(image, format="rgb24")
            frame.pts, frame.time_base = pts, Fraction(1, 1000)
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    got = [frame for frame, _ in open_frames(path, keep_gaps=True)]
    assert len(got) == 10 and all(frame is not None for frame in got)


def test_frame_of_another_size_in_a_folder_is_named_in_width_x_height(tmp_path):
    folder = _folder(tmp_path)
    write_image(folder / "4.png", np.zeros((40, 50, 3), np.uint8))
    with pytest.raises(InputError, match=r"4.png: 50x40, the other frames are 64x48$"):
        list(open_frames(folder, fixed_size=True))
    assert len(list(open_frames(folder))) == 6  # registration checks sizes itself, naming the recording
