"""A real-content RGB-T pair for speed figures, derived from a shared full-HD clip as ``../shared/data/video/README.md``
describes: the clip itself is the visible stream, and a 640x512 "thermal" stream is derived from it (grey, contrast
remapped, a narrower field of view through a known homography, smoothed as a microbolometer's optics do, sensor noise),
both encoded as H.264 at a real bit rate. The registration is known, the target (the car ahead) is in both streams,
and every frame carries real texture and real camera motion, which generated scenes do not.

    python benchmarks/real_pair.py OUTDIR [--frames 300]

writes ``rgb.mp4`` (1920x1080), ``t.mp4`` (640x512), ``calib.json`` (the true RGB -> T homography), ``rgb.init.txt``
(the car's box on the first frame), and with ``--jpeg`` the folders ``rgb_jpg/`` and ``t_jpg/`` (both cameras as
1920x1080 JPEG frames, the layout of a UAV RGB-T data set), with ``rgb_jpg.init.txt``.

The source clip has 180 frames; longer streams play it forward, then backward, and so on (the frames stay real; the
motion reverses at each end).
"""

from __future__ import annotations

import argparse
import json
from fractions import Fraction
from pathlib import Path

import numpy as np

SOURCE = Path(__file__).resolve().parents[2] / "shared" / "data" / "video" / "test_realtime_vod.mp4"
RGB_SIZE, T_SIZE = (1920, 1080), (640, 512)
ROW_OFFSET = 60  # the 1920x1200 clip cropped to its middle 1080 rows
INIT_BOX = (940.0, 530.0, 124.0, 114.0)  # the dark car ahead on the first frame, x, y, w, h in the cropped frame
# The thermal camera's view: a 1280x1024 part of the visible frame around (960, 540), rolled 2 degrees, at half scale.
T_CENTRE, T_SCALE, T_ROLL_DEG = (972.0, 548.0), 0.5, 2.0


def rgb_to_t_homography(t_size: tuple[int, int] = T_SIZE, scale: float = T_SCALE) -> np.ndarray:
    """The true RGB -> thermal mapping: a similarity about ``T_CENTRE`` (a narrower, slightly rolled view)."""
    a = np.deg2rad(T_ROLL_DEG)
    rot = scale * np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    centre_t = np.array([t_size[0] / 2, t_size[1] / 2])
    h = np.eye(3)
    h[:2, :2] = rot
    h[:2, 2] = centre_t - rot @ np.array(T_CENTRE)
    return h


def source_frames(frames: int) -> list[np.ndarray]:
    """``frames`` BGR frames of the cropped clip, played forward and backward."""
    import av

    with av.open(str(SOURCE)) as container:
        clip = [f.to_ndarray(format="bgr24")[ROW_OFFSET:ROW_OFFSET + RGB_SIZE[1]] for f in container.decode(video=0)]
    order: list[int] = []
    forward = True
    while len(order) < frames:
        span = range(len(clip)) if forward else range(len(clip) - 1, -1, -1)
        order.extend(i for i in span if not order or i != order[-1])
        forward = not forward
    return [clip[i] for i in order[:frames]]


def thermal_view(bgr: np.ndarray, h: np.ndarray, size: tuple[int, int], rng: np.random.Generator) -> np.ndarray:
    """The derived thermal frame: luminance remapped (dark asphalt and cars warm, sky cold), warped into the thermal
    camera's view, smoothed, with fixed-pattern and temporal noise."""
    import cv2

    grey = cv2.cvtColor(bgr, cv2.COLOR_BGR2GRAY).astype(np.float32)
    warm = 255.0 - 0.8 * grey  # contrast inverted and compressed
    view = cv2.warpPerspective(warm, h, size, flags=cv2.INTER_AREA if h[0, 0] < 1 else cv2.INTER_LINEAR)
    view = cv2.GaussianBlur(view, (0, 0), 1.2)
    view += rng.normal(0.0, 2.5, view.shape).astype(np.float32)
    return np.clip(view, 0, 255).astype(np.uint8)


def encode(path: Path, images: list[np.ndarray], fps: int = 30, crf: int = 20) -> None:
    """H.264 (yuv420p) at a real camera's quality."""
    import av

    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=Fraction(fps, 1))
        stream.width, stream.height = images[0].shape[1], images[0].shape[0]
        stream.pix_fmt = "yuv420p"
        stream.options = {"crf": str(crf), "preset": "medium"}
        colour = images[0].ndim == 3
        for image in images:
            frame = av.VideoFrame.from_ndarray(image, format="bgr24" if colour else "gray")
            container.mux(stream.encode(frame))
        container.mux(stream.encode(None))


def write_pair(outdir: Path, frames: int = 300, jpeg: bool = False) -> dict[str, Path]:
    """Write the pair (cached: existing files of the same frame count are kept) and return its paths."""
    import cv2

    from rgbt_toolkit.registration.calib import Calibration, save_calibration

    outdir.mkdir(parents=True, exist_ok=True)
    paths = {"rgb": outdir / "rgb.mp4", "t": outdir / "t.mp4", "calib": outdir / "calib.json",
             "rgb_jpg": outdir / "rgb_jpg", "t_jpg": outdir / "t_jpg"}
    stamp = outdir / "pair.json"
    wanted = {"frames": frames, "jpeg": jpeg, "source": SOURCE.name}
    if stamp.is_file() and json.loads(stamp.read_text()) == wanted:
        return paths
    rgb = source_frames(frames)
    rng = np.random.default_rng(0)
    h = rgb_to_t_homography()
    encode(paths["rgb"], rgb)
    encode(paths["t"], [thermal_view(f, h, T_SIZE, rng) for f in rgb])
    save_calibration(paths["calib"], Calibration(matrix=h, model="similarity", rgb_size=RGB_SIZE,
                                                 thermal_size=T_SIZE))
    init = ",".join(f"{v:g}" for v in INIT_BOX)
    (outdir / "rgb.init.txt").write_text(init + "\n")
    if jpeg:
        # both cameras as 1920x1080 JPEG folders: the thermal view rendered at the visible frame's size
        h_full = rgb_to_t_homography(RGB_SIZE, T_SCALE * RGB_SIZE[0] / T_SIZE[0])
        for key in ("rgb_jpg", "t_jpg"):
            paths[key].mkdir(exist_ok=True)
        for k, image in enumerate(rgb):
            cv2.imwrite(str(paths["rgb_jpg"] / f"{k:06d}.jpg"), image, [cv2.IMWRITE_JPEG_QUALITY, 92])
            cv2.imwrite(str(paths["t_jpg"] / f"{k:06d}.jpg"), thermal_view(image, h_full, RGB_SIZE, rng),
                        [cv2.IMWRITE_JPEG_QUALITY, 92])
        save_calibration(outdir / "calib_jpg.json", Calibration(matrix=h_full, model="similarity",
                                                                rgb_size=RGB_SIZE, thermal_size=RGB_SIZE))
        (outdir / "rgb_jpg.init.txt").write_text(init + "\n")
    stamp.write_text(json.dumps(wanted))
    return paths


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("outdir", type=Path)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--jpeg", action="store_true", help="also write 1920x1080 JPEG folders of both cameras")
    args = parser.parse_args()
    for name, path in write_pair(args.outdir, args.frames, args.jpeg).items():
        print(f"{name}: {path}")


if __name__ == "__main__":
    main()
