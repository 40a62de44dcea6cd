"""The estimate inside `rgbt track` (issue #41): few frames read by time, JPEG decoded reduced, full read on refusal."""

import cv2
import numpy as np
import pytest

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration import RegisterSettings, corner_error, estimate_transform, overlap_corner_error
from rgbt_toolkit.registration import pipeline
from rgbt_toolkit.registration.pipeline import TRACKING, register_for_tracking, register_paths
from rgbt_toolkit.registration.sampled import SampledFolder, reduction_for
from rgbt_toolkit.registration.transforms import normalize, pixel_scaling

synth = pytest.importorskip("rgbt_toolkit.synth")


def _jpeg_folder(path, frames):
    path.mkdir()
    for index, frame in enumerate(frames):
        bgr = frame[..., ::-1] if frame.ndim == 3 else frame
        cv2.imwrite(str(path / f"{index:04d}.jpg"), bgr, [cv2.IMWRITE_JPEG_QUALITY, 92])
    return path


@pytest.fixture(scope="module")
def hd_folders(tmp_path_factory):
    """A generated 1920x1080 RGB + 640x512 thermal rig as JPEG folders (12 frames, a UAV data set's layout)."""
    cfg = synth.SceneConfig(seed=1, rgb_size=(1920, 1080), t_size=(640, 512), duration=0.8,
                            challenges=frozenset({"camera_motion"}))
    renderer = synth.SceneRenderer(cfg)
    folder = tmp_path_factory.mktemp("hd")
    times = np.arange(cfg.rgb_frame_count) / cfg.rgb_fps
    rgb = _jpeg_folder(folder / "rgb", [renderer.render(t, "rgb", k).image for k, t in enumerate(times)])
    thermal = _jpeg_folder(folder / "t", [renderer.render(t, "t", k).image for k, t in enumerate(times)])
    return rgb, thermal, renderer.h_rgb_to_t, cfg.t_size


def test_jpeg_reduction_keeps_the_analysis_size():
    assert reduction_for((1920, 1080), 640) == 2  # 960 px: the 640-px analysis copy is still a shrink
    assert reduction_for((1280, 1024), 640) == 2
    assert reduction_for((640, 512), 640) == 1
    assert reduction_for((3840, 2160), 640) == 4
    assert reduction_for((20000, 10000), 640) == 8  # OpenCV decodes at most 8x smaller


def test_sizes_map_reduced_frames_to_full_pixels(make_pair):
    """Frames decoded at half size, with their full sizes given, give the full-size matrix."""
    visible, thermal, truth = make_pair(3)
    half = [cv2.resize(f, (f.shape[1] // 2, f.shape[0] // 2), interpolation=cv2.INTER_AREA) for f in (visible, thermal)]
    sizes = ((visible.shape[1], visible.shape[0]), (thermal.shape[1], thermal.shape[0]))
    result = estimate_transform([half[0]], [half[1]], sizes=sizes)
    assert result.rgb_size == sizes[0] and result.thermal_size == sizes[1]
    unsized = estimate_transform([half[0]], [half[1]])  # in the half-size frames' own pixels
    assert corner_error(unsized.matrix, truth, sizes[0]) > 10
    to_half_a, to_half_t = (pixel_scaling(small.shape[1] / w, small.shape[0] / h)
                            for small, (w, h) in zip(half, sizes))
    expected = normalize(np.linalg.inv(to_half_t) @ unsized.matrix @ to_half_a)
    np.testing.assert_allclose(result.matrix, expected, rtol=1e-9, atol=1e-9)
    assert corner_error(result.matrix, truth, sizes[0]) < 4.0  # 160x120 frames: 2 px at half size


def test_generated_1080p_pair_same_answer_as_the_full_read(hd_folders):
    rgb, thermal, truth, t_size = hd_folders
    full = register_paths(rgb, thermal).calibration
    quick = register_paths(rgb, thermal, TRACKING).calibration  # accepted on its own, without the full read
    assert quick.rgb_size == full.rgb_size == (1920, 1080) and quick.thermal_size == full.thermal_size == t_size
    # RGB px at 1080p, i.e. 1 px per 640 px of width (measured: 2.60 and 2.62 px, 0.04 px apart)
    assert overlap_corner_error(full.matrix, truth, t_size) < 3.0
    assert overlap_corner_error(quick.matrix, truth, t_size) < 3.0
    assert overlap_corner_error(quick.matrix, full.matrix, t_size) < 0.5


def test_tracking_estimate_decodes_a_few_jpegs_reduced(hd_folders, monkeypatch):
    """Only the paired files are decoded, each at half size as grey; the full read decodes every file."""
    import rgbt_toolkit.io.frames as frames_module

    rgb, thermal, _, _ = hd_folders
    decoded, given = [], {}
    imread = cv2.imread

    def spy_imread(path, flags=cv2.IMREAD_COLOR):
        decoded.append((path, flags))
        return imread(path, flags)

    def no_full_decode(*args, **kwargs):
        raise AssertionError("a frame was decoded at full size")

    def spy_estimate(rgb_frames, thermal_frames, settings, sizes=None):
        given.update(rgb=[f.shape for f in rgb_frames], sizes=sizes)
        return estimate_transform(rgb_frames, thermal_frames, settings, sizes=sizes)

    monkeypatch.setattr(cv2, "imread", spy_imread)
    monkeypatch.setattr(frames_module, "read_image", no_full_decode)
    monkeypatch.setattr(pipeline, "estimate_transform", spy_estimate)
    reg = register_for_tracking(rgb, thermal)
    assert reg.rgb_frames == len(list(rgb.iterdir())) == 12
    assert len(decoded) <= 2 * TRACKING.max_pairs
    rgb_flags = {flags for path, flags in decoded if "/rgb/" in path}
    assert rgb_flags == {cv2.IMREAD_REDUCED_GRAYSCALE_2 | cv2.IMREAD_IGNORE_ORIENTATION}
    assert set(given["rgb"]) == {(540, 960)} and given["sizes"] == ((1920, 1080), (640, 512))


def _long_gop_video(path, frames, gop: int) -> None:
    """H.264 with a keyframe every ``gop`` frames and no scene-cut keyframes (x264's own default GOP is 250)."""
    import av

    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=15)
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        stream.codec_context.gop_size = gop
        stream.options = {"crf": "18", "preset": "veryfast", "x264-params": "scenecut=0"}
        for frame in frames:
            rgb = np.repeat(frame[..., None], 3, axis=2) if frame.ndim == 2 else frame
            container.mux(stream.encode(av.VideoFrame.from_ndarray(np.ascontiguousarray(rgb), format="rgb24")))
        container.mux(stream.encode())


@pytest.fixture(scope="module")
def long_gop_videos(tmp_path_factory, make_pair):
    """64 frames of a 320x240 RGB and a thermal video, keyframes at frames 0 and 32 only."""
    folder = tmp_path_factory.mktemp("long_gop")
    visible, thermal, truth = make_pair(5)
    crop = lambda image: image[: image.shape[0] // 2 * 2, : image.shape[1] // 2 * 2]  # noqa: E731
    rng = np.random.default_rng(0)
    noisy = lambda image: np.clip(crop(image) + rng.normal(0, 2, crop(image).shape), 0, 255).astype(np.uint8)  # noqa
    _long_gop_video(folder / "rgb.mp4", [noisy(visible) for _ in range(64)], 32)
    _long_gop_video(folder / "t.mp4", [noisy(thermal) for _ in range(64)], 32)
    return folder, truth


def test_decode_cost_counts_from_the_keyframe_before(long_gop_videos):
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.registration.pipeline import SeekableVideo

    folder, _ = long_gop_videos
    source = open_frames(folder / "rgb.mp4", grey=True)
    video = SeekableVideo(source.path, source.__iter__)
    np.testing.assert_array_equal(video.decode_cost(video.times[[0, 5, 31, 32, 40, 63]]), [1, 6, 32, 1, 9, 32])
    np.testing.assert_array_equal(video.decode_cost(video.times[[5]] + 0.01), [6])  # nearest frame's cost


def test_video_pairs_within_the_decode_budget(long_gop_videos):
    """Four chunks of 16 frames: the pairs at the two keyframes cost 2 frames, the others 34; only the cheap ones
    are decoded, and they give the answer of the full read."""
    folder, truth = long_gop_videos
    counts = {}
    results = {}
    for name, settings in (("all", RegisterSettings()), ("budget", TRACKING)):
        decoded = []
        results[name] = register_paths(folder / "rgb.mp4", folder / "t.mp4", settings,
                                       on_frame=lambda: decoded.append(1))
        counts[name] = len(decoded)
    budget = results["budget"]
    assert budget.spatial.pairs_used == 2 and results["all"].spatial.pairs_used == 4
    assert round(budget.preview_times[0] * 15) in (0, 32)  # the pairs used are the keyframes'
    assert counts["budget"] <= 8 < counts["all"], counts
    assert corner_error(budget.calibration.matrix, truth, (320, 240)) < 1.5
    assert corner_error(budget.calibration.matrix, results["all"].calibration.matrix, (320, 240)) < 0.5


def test_refused_shortcut_defers_to_the_full_read(monkeypatch):
    """A refusal on the few frames decides nothing: the full read's answer (or refusal) stands."""
    calls = []

    def fake(rgb, thermal, settings=RegisterSettings(), *, fps=None, masks=(None, None)):
        calls.append(settings)
        if settings is TRACKING:
            raise RegistrationError("registration failed: no reliable match (few frames)")
        return "full read's answer"

    monkeypatch.setattr(pipeline, "register_paths", fake)
    assert register_for_tracking("rgb", "t") == "full read's answer"
    assert calls == [TRACKING, RegisterSettings()]


def test_mismatched_folders_refused_as_by_the_full_read(tmp_path, make_pair):
    visible, _, _ = make_pair(2)
    _, other_thermal, _ = make_pair(11)
    rgb = _jpeg_folder(tmp_path / "rgb", [visible] * 6)
    thermal = _jpeg_folder(tmp_path / "t", [other_thermal] * 6)
    with pytest.raises(RegistrationError) as full:
        register_paths(rgb, thermal)
    with pytest.raises(RegistrationError) as quick:
        register_for_tracking(rgb, thermal)
    assert str(quick.value) == str(full.value)


def test_sampled_folder_skips_unreadable_files_and_names_odd_sizes(tmp_path, make_pair):
    from rgbt_toolkit.io.video import CorruptFrameWarning

    visible, _, _ = make_pair(2)
    folder = _jpeg_folder(tmp_path / "rgb", [visible] * 4)
    (folder / "0002.jpg").write_bytes(b"not a jpeg")
    frames = SampledFolder(folder, 10.0, 640)
    with pytest.warns(CorruptFrameWarning, match="0002.jpg"):
        fetched = frames.frames_at(frames.times[[1, 2]])
    assert list(fetched) == [pytest.approx(0.1)] and fetched[0.1].shape == visible.shape[:2]
    cv2.imwrite(str(folder / "0003.jpg"), cv2.resize(visible, (100, 80)))
    with pytest.raises(InputError, match=r"0003\.jpg: 100x80, the other frames are"):
        frames.frames_at(frames.times[[3]])
