"""The picture at the top of README.md and of the docs' home page: a frame of ``annotated.mp4`` beside ``track.png``.

Tracks the bundled sample exactly as the README's first command does (``rgbt track samples/demo_rgb.mp4
samples/demo_t.mp4``) into a temporary folder, takes one frame of the annotated video, stacks its RGB half above its
thermal half, and puts that column beside the run's picture (``track.png``), both at their own pixel size. Frame 33 is
the first that a passing van covers (frames 33 to 41, while the camera shakes: ``CM``); from the next one the motion
tracker holds the box (the orange span of ``track.png``).

    python scripts/readme_figure.py                 # writes docs/img/readme_track.png
    python scripts/readme_figure.py --frame 10 --out /tmp/figure.png
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "img" / "readme_track.png"
FRAME = 33
GAP = 12            # white pixels between the frame column and the plot


def frame_column(frame: np.ndarray) -> np.ndarray:
    """An ``annotated.mp4`` frame (RGB half | thermal half, side by side) as one column: RGB above thermal."""
    if frame.ndim != 3 or frame.shape[1] % 2:
        raise ValueError(f"expected an H x 2W x 3 frame of two camera views side by side, got {frame.shape}")
    half = frame.shape[1] // 2
    return np.concatenate([frame[:, :half], frame[:, half:]], axis=0)


def compose(frame: np.ndarray, plot: np.ndarray, gap: int = GAP) -> np.ndarray:
    """The frame's column beside the plot on a white background, both centred on the taller one's height.

    Parameters
    ----------
    frame : numpy.ndarray
        H x 2W x 3 uint8, an ``annotated.mp4`` frame (RGB view left, thermal view right).
    plot : numpy.ndarray
        h x w x 3 (or x 4, alpha dropped) uint8, ``track.png``.
    gap : int
        White columns between the two.

    Returns
    -------
    numpy.ndarray
        max(2H, h) x (W + gap + w) x 3 uint8.
    """
    column, plot = frame_column(frame), plot[..., :3]
    height = max(column.shape[0], plot.shape[0])
    canvas = np.full((height, column.shape[1] + gap + plot.shape[1], 3), 255, np.uint8)
    for image, left in ((column, 0), (plot, column.shape[1] + gap)):
        top = (height - image.shape[0]) // 2
        canvas[top:top + image.shape[0], left:left + image.shape[1]] = image
    return canvas


def run_sample(outdir: Path) -> None:
    """``rgbt track`` on the bundled sample, as README.md runs it."""
    subprocess.run([sys.executable, "-m", "rgbt_cli.main", "track", str(ROOT / "samples" / "demo_rgb.mp4"),
                    str(ROOT / "samples" / "demo_t.mp4"), "-o", str(outdir)], check=True)


def main(argv: list[str] | None = None) -> Path:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frame", type=int, default=FRAME, help=f"frame of annotated.mp4 to show (default {FRAME})")
    parser.add_argument("--out", type=Path, default=OUT, help="PNG to write (default docs/img/readme_track.png)")
    args = parser.parse_args(argv)

    import imageio.v3 as iio
    from PIL import Image

    with tempfile.TemporaryDirectory() as tmp:
        run = Path(tmp) / "demo"
        run_sample(run)
        frame = iio.imread(run / "annotated.mp4", index=args.frame, plugin="pyav")
        figure = compose(frame, iio.imread(run / "track.png"))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(figure).save(args.out, optimize=True)  # about 200 KB
    print(f"{args.out}: {figure.shape[1]}x{figure.shape[0]}, {args.out.stat().st_size // 1024} KB")
    return args.out


if __name__ == "__main__":
    main()
