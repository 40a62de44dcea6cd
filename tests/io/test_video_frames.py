"""Video, image and frame-source readers and writers: round trips and malformed input."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.io.frames import open_frames
from rgbt_toolkit.io.images import list_images, read_image, rgb_to_grey, write_image
from rgbt_toolkit.io.video import VideoReader, VideoWriter, write_video


def _ramp_frames(n: int, size=(64, 48)) -> list[np.ndarray]:
    w, h = size
    xs = np.linspace(0, 255, w)[None, :, None]
    return [np.broadcast_to(np.clip(xs + 4 * i, 0, 255), (h, w, 3)).astype(np.uint8) for i in range(n)]


def test_video_round_trip_keeps_count_size_rate_and_content(tmp_path):
    frames = _ramp_frames(20)
    path = tmp_path / "clip.mp4"
    write_video(path, frames, fps=12.5)
    reader = VideoReader(path)
    assert reader.size == (64, 48) and reader.fps == pytest.approx(12.5) and reader.frame_count == 20
    decoded, times = reader.read_all()
    assert len(decoded) == 20
    np.testing.assert_allclose(np.diff(times), 1 / 12.5, atol=1e-3)
    assert np.abs(decoded[7].astype(int) - frames[7].astype(int)).mean() < 3  # lossy, but close


def test_grey_frames_are_the_luma_of_the_colour_ones(tmp_path):
    """Grey decoding reads the Y plane directly (no colour conversion), stretched from video range (16-235) to 0-255:
    same timing and size as the RGB frames, and the picture FFmpeg's own grey conversion gives."""
    import av

    rng = np.random.default_rng(3)
    frames = [np.kron(rng.integers(0, 256, (6, 8, 3)), np.ones((8, 8, 1))).astype(np.uint8) for _ in range(5)]
    path = tmp_path / "clip.mp4"
    write_video(path, frames, fps=10)
    colour = list(VideoReader(path).frames())
    grey = list(open_frames(path, grey=True))
    assert [t for _, t in grey] == [t for _, t in colour]
    assert grey[2][0].shape == (48, 64) and grey[2][0].dtype == np.uint8
    with av.open(str(path)) as container:
        reference = [f.to_ndarray(format="gray") for f in container.decode(video=0)]
    assert np.abs(grey[2][0].astype(int) - reference[2].astype(int)).max() <= 1


def test_grey_frames_of_other_pixel_formats_are_converted(tmp_path):
    import av

    path = tmp_path / "rgb.mkv"
    with av.open(str(path), "w") as container:  # a lossless RGB video: no luma plane to read
        stream = container.add_stream("ffv1", rate=10)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "bgr0"
        for value in (40, 200):
            frame = av.VideoFrame.from_ndarray(np.full((48, 64, 3), value, np.uint8), format="rgb24")
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    grey = [frame for frame, _ in VideoReader(path).frames(grey=True)]
    assert [g.shape for g in grey] == [(48, 64)] * 2
    assert abs(int(grey[0].mean()) - 40) <= 2 and abs(int(grey[1].mean()) - 200) <= 2


def _write_gray16_video(path, frames):
    """A lossless 16-bit grey video (FFV1 gray16le, 64 x 48, 10 fps): how radiometric thermal counts are recorded."""
    import av

    with av.open(str(path), "w") as container:
        stream = container.add_stream("ffv1", rate=10)
        stream.width, stream.height, stream.pix_fmt = 64, 48, "gray16le"
        for image in frames:
            for packet in stream.encode(av.VideoFrame.from_ndarray(image, format="gray16le")):
                container.mux(packet)
        for packet in stream.encode():
            container.mux(packet)
    return path


def test_sixteen_bit_grey_video_keeps_its_levels(tmp_path):
    """Raw thermal counts (FFV1 gray16le) use a few hundred of 65536 levels: decoded at 8 bits they collapse to one
    or two grey values (a blank frame); grey decoding keeps all 16 bits."""
    rng = np.random.default_rng(5)
    frames = [(27000 + 20 * rng.integers(0, 250, (48, 64))).astype(np.uint16) for _ in range(3)]
    path = _write_gray16_video(tmp_path / "t16.mkv", frames)
    grey = [frame for frame, _ in VideoReader(path).frames(grey=True)]
    assert grey[0].dtype == np.uint16
    np.testing.assert_array_equal(grey[1], frames[1])  # lossless: every level back


def test_trackers_get_sixteen_bit_video_as_eight_bits_with_one_range(tmp_path):
    """Colour mode (the trackers' frames) maps raw counts with the first frame's range for the whole video: before,
    a gray16le video came out of the RGB conversion as a flat grey (counts / 257 = 105-125 for 27000-32000)."""
    from rgbt_toolkit.io.frames import open_frames

    ramp = np.tile(np.linspace(27000, 32000, 64), (48, 1))
    frames = [ramp.astype(np.uint16), (ramp + 500).astype(np.uint16)]  # the scene warms by 500 counts
    path = _write_gray16_video(tmp_path / "t16.mkv", frames)
    out = [frame for frame, _ in open_frames(path)]
    assert out[0].dtype == np.uint8 and out[0].shape == (48, 64)
    assert int(out[0].max()) - int(out[0].min()) > 180  # the used range spread over the 8 bits
    assert np.corrcoef(out[0].ravel(), frames[0].ravel())[0, 1] > 0.999
    shift = out[1].astype(int) - out[0].astype(int)  # one range: warmer is brighter, not re-stretched
    assert 15 <= np.median(shift) <= 25


def test_odd_sized_frames_are_padded_not_refused(tmp_path):
    path = tmp_path / "odd.mp4"
    write_video(path, [np.zeros((31, 45, 3), np.uint8)] * 3, fps=10)
    assert VideoReader(path).size == (46, 32)


def test_writer_leaves_no_file_when_the_run_fails(tmp_path):
    path = tmp_path / "broken.mp4"
    with pytest.raises(ValueError, match="differs"):
        with VideoWriter(path, 10) as writer:
            writer.write(np.zeros((32, 32, 3), np.uint8))
            writer.write(np.zeros((16, 16, 3), np.uint8))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("keep_partial, kept", [(True, True), (False, False)])
def test_ctrl_c_keeps_the_partial_video_only_when_asked(tmp_path, keep_partial, kept):
    """`rgbt track` keeps what it tracked; `rgbt synth` must not leave a video that its ground truth does not match."""
    path = tmp_path / "v.mp4"
    with pytest.raises(KeyboardInterrupt):
        with VideoWriter(path, 10, keep_partial=keep_partial) as writer:
            writer.write(np.zeros((32, 32, 3), np.uint8))
            raise KeyboardInterrupt
    assert [p.name for p in tmp_path.iterdir()] == (["v.mp4"] if kept else [])
    if kept:
        assert VideoReader(path).read_all()[1].shape == (1,)


@pytest.mark.parametrize("content, message", [(b"", "empty"), (b"not a video at all" * 10, "cannot open")])
def test_bad_video_files_are_clear_errors(tmp_path, content, message):
    path = tmp_path / "bad.mp4"
    path.write_bytes(content)
    with pytest.raises(FileFormatError, match=message):
        VideoReader(path)


def test_missing_video_names_the_file(tmp_path):
    with pytest.raises(MissingFileError, match="nothere.mp4"):
        VideoReader(tmp_path / "nothere.mp4")


def test_image_round_trip_and_natural_order(tmp_path):
    image = np.random.default_rng(0).integers(0, 255, (20, 30, 3), dtype=np.uint8)
    for name in ("10.png", "2.png", "1.png"):
        write_image(tmp_path / name, image)
    assert [p.name for p in list_images(tmp_path)] == ["1.png", "2.png", "10.png"]
    np.testing.assert_array_equal(read_image(tmp_path / "2.png"), image)
    assert read_image(tmp_path / "2.png", grey=True).shape == (20, 30)


def test_grey_conversion_uses_matlab_weights():
    pixel = np.array([[[200, 100, 50]]], np.uint8)
    assert rgb_to_grey(pixel)[0, 0] == round(0.298936021293775 * 200 + 0.587043074451121 * 100
                                              + 0.114020904255103 * 50)


def test_corrupt_image_is_a_clear_error(tmp_path):
    path = tmp_path / "x.jpg"
    path.write_bytes(b"\xff\xd8garbage")
    with pytest.raises(FileFormatError, match="x.jpg: cannot decode"):
        read_image(path)


def test_open_frames_accepts_video_folder_and_image(tmp_path):
    frames = _ramp_frames(5)
    write_video(tmp_path / "v.mp4", frames, fps=10)
    folder = tmp_path / "frames"
    for i, frame in enumerate(frames):
        write_image(folder / f"{i}.png", frame)
    video = open_frames(tmp_path / "v.mp4")
    images = open_frames(folder, fps=10)
    single = open_frames(folder / "3.png")
    assert (video.kind, images.kind, single.kind) == ("video", "folder", "image")
    assert len(list(video)) == len(list(images)) == 5 and len(list(single)) == 1
    assert [t for _, t in images] == pytest.approx([0, 0.1, 0.2, 0.3, 0.4])


def test_open_frames_errors(tmp_path):
    with pytest.raises(MissingFileError):
        open_frames(tmp_path / "none")
    (tmp_path / "empty").mkdir()
    with pytest.raises(InputError, match="holds no images"):
        open_frames(tmp_path / "empty")
    (tmp_path / "notes.xyz").write_text("hi")
    with pytest.raises(FileFormatError, match="unknown file type"):
        open_frames(tmp_path / "notes.xyz")


def test_colours_survive_the_round_trip(tmp_path):
    """The writer converts RGB to the encoder's YUV planes itself: a swapped channel or range would show here."""
    colours = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 200, 40], [30, 90, 200], [128, 128, 128]])
    frame = np.repeat(colours.astype(np.uint8)[None, :, None, :], 32, axis=0).repeat(32, axis=2).reshape(32, 192, 3)
    path = tmp_path / "colours.mp4"
    write_video(path, [frame] * 3, fps=10)
    decoded, _ = VideoReader(path).read_all()
    for k, colour in enumerate(colours):  # the middle of each 32x32 patch, away from chroma bleeding at its edges
        mean = decoded[1][8:24, 32 * k + 8:32 * k + 24].reshape(-1, 3).mean(axis=0)
        np.testing.assert_allclose(mean, colour, atol=6)


def test_a_frame_can_be_handed_over_as_the_function_that_draws_it(tmp_path):
    frames = _ramp_frames(4)
    path = tmp_path / "drawn.mp4"
    with VideoWriter(path, fps=10) as writer:
        for frame in frames:
            writer.write(lambda frame=frame: frame)
    assert writer.frames_written == 4
    decoded, _ = VideoReader(path).read_all()
    assert len(decoded) == 4 and np.abs(decoded[2].astype(int) - frames[2].astype(int)).mean() < 3


def test_grey_conversion_is_the_float64_weighted_sum_to_the_bit():
    """rgb_to_grey runs through OpenCV; it must round exactly as the plain float64 sum does (MATLAB's rgb2gray)."""
    rng = np.random.default_rng(3)
    weights = np.array([0.298936021293775, 0.587043074451121, 0.114020904255103])
    for image in (rng.integers(0, 256, (97, 131, 3), dtype=np.uint8), rng.integers(0, 256, (40, 50, 4), np.uint8),
                  rng.integers(0, 65536, (33, 21, 3), dtype=np.uint16)):
        expected = np.clip(np.round(image[..., :3].astype(np.float64) @ weights), 0, np.iinfo(image.dtype).max)
        assert np.array_equal(rgb_to_grey(image), expected.astype(image.dtype))
    levels = np.repeat(np.arange(256, dtype=np.uint8)[None, :, None], 3, axis=2)  # grey stays grey
    assert np.array_equal(rgb_to_grey(levels)[0], np.arange(256))
    floats = rng.random((5, 6, 3)).astype(np.float32)
    np.testing.assert_allclose(rgb_to_grey(floats), floats @ weights.astype(np.float32), rtol=1e-6)
    pixels = rng.integers(0, 256, (10, 3), dtype=np.uint8)  # not an image: a list of pixels
    assert np.array_equal(rgb_to_grey(pixels), np.round(pixels.astype(np.float64) @ weights).astype(np.uint8))


@pytest.mark.parametrize("kind", ["video", "folder"])
def test_auto_grey_keeps_one_channel_of_a_grey_picture_and_three_of_a_colour_one(tmp_path, kind):
    """``auto_grey`` (what `rgbt track` opens the thermal stream with): a grey picture stored as colour travels as
    H x W frames, the same picture; a colour stream stays colour. The first frame decides for the whole stream."""
    grey_frames = [np.repeat(f[:, :, :1], 3, axis=2) for f in _ramp_frames(4)]
    colour_frames = [f.copy() for f in _ramp_frames(4)]
    colour_frames[0][10:14, 10:14] = (255, 0, 0)  # one coloured detail (a palette, an overlay) keeps colour
    for name, frames, grey in (("grey", grey_frames, True), ("colour", colour_frames, False)):
        if kind == "video":
            source = tmp_path / f"{name}.mp4"
            write_video(source, frames, fps=10)
        else:
            source = tmp_path / name
            source.mkdir()
            for k, frame in enumerate(frames):
                write_image(source / f"{k:03d}.png", frame)
        auto = [f for f, _ in open_frames(source, auto_grey=True)]
        plain = [f for f, _ in open_frames(source)]
        assert len(auto) == len(plain) == 4
        assert all(f.ndim == (2 if grey else 3) for f in auto), name
        for a, p in zip(auto, plain):
            np.testing.assert_allclose(a.astype(int), (p[..., 0] if grey else p).astype(int), atol=1)


def test_writer_refuses_an_unknown_preset_or_quality(tmp_path):
    with pytest.raises(ValueError, match="unknown x264 preset 'quick'"):
        VideoWriter(tmp_path / "a.mp4", 10, preset="quick")
    with pytest.raises(ValueError, match="crf"):
        VideoWriter(tmp_path / "b.mp4", 10, crf=60)
    assert not list(tmp_path.iterdir())  # nothing opened, nothing left


def test_a_slower_preset_writes_a_smaller_file_of_the_same_picture(tmp_path):
    rng = np.random.default_rng(5)
    base = cv2_blur(rng.integers(0, 256, (96, 128, 3)).astype(np.uint8))
    frames = [np.roll(base, 2 * k, axis=1) for k in range(12)]
    sizes = {}
    for preset in ("ultrafast", "medium"):
        path = tmp_path / f"{preset}.mp4"
        with VideoWriter(path, 10, preset=preset, crf=23) as writer:
            for frame in frames:
                writer.write(frame)
        sizes[preset] = path.stat().st_size
        decoded, _ = VideoReader(path).read_all()
        assert np.abs(decoded[6].astype(int) - frames[6].astype(int)).mean() < 6
    assert sizes["medium"] < sizes["ultrafast"]


def cv2_blur(image: np.ndarray) -> np.ndarray:
    import cv2

    return cv2.GaussianBlur(image, (0, 0), 2)


def test_frame_folders_decode_jpeg_fast_with_the_same_pixels(tmp_path):
    """``read_frame`` (frame folders) decodes JPEG with OpenCV: the pixels ``read_image`` (imageio/Pillow) gives, for
    colour, grey and grey-as-colour files; a truncated JPEG is still a clear error naming the file."""
    from rgbt_toolkit.io.images import read_frame

    rng = np.random.default_rng(9)
    colour = cv2_blur(rng.integers(0, 256, (60, 80, 3)).astype(np.uint8))
    grey = colour[..., 1].copy()
    files = {"colour.jpg": colour, "grey.jpg": grey, "grey_as_colour.jpg": np.repeat(grey[..., None], 3, axis=2)}
    for name, image in files.items():
        write_image(tmp_path / name, image)
        expected = read_image(tmp_path / name)
        np.testing.assert_array_equal(read_frame(tmp_path / name), expected)
        np.testing.assert_array_equal(read_frame(tmp_path / name, grey=True), read_image(tmp_path / name, grey=True))
    np.testing.assert_array_equal(read_frame(tmp_path / "grey_as_colour.jpg", luma=True),
                                  read_image(tmp_path / "grey_as_colour.jpg")[..., 0])
    data = (tmp_path / "colour.jpg").read_bytes()
    (tmp_path / "cut.jpg").write_bytes(data[: len(data) // 2])
    with pytest.raises(FileFormatError, match="cut.jpg"):
        read_frame(tmp_path / "cut.jpg")
