"""``rgbt track`` on live sources: two named pipes fed at the camera rate, with and without ``--realtime``.

Renders an aligned synthetic scene (``rgbt_toolkit.synth``, 320x240 at 30 frames/s), re-encodes each camera as an
MPEG-TS stream (MPEG-4 Part 2, intra only, the kind of stream a camera sends), writes both streams into named pipes
from threads at 30 frames/s, and runs ``rgbt track PIPE_RGB PIPE_T --assume-aligned [--realtime]`` in a subprocess.
Prints a Markdown table: source length, run wall time, frames processed and dropped, the first-frame initialisation
time, the gap between tracked frames, how long after the source ended the run ended (start-up included), how far
behind the source the last tracked frame was, and the mean IoU of every row against the ground truth of the source frame its timestamp names.

    python benchmarks/bench_live.py --duration 30 --modes realtime plain
"""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import av
import numpy as np

from rgbt_toolkit.evaluation.metrics import iou_continuous
from rgbt_toolkit.io.boxes import read_boxes
from rgbt_toolkit.io.video import VideoReader

FPS = 30


def transport_stream(video: Path) -> tuple[bytes, int]:
    """The video re-encoded as MPEG-TS (intra-only MPEG-4 at high quality): its bytes and frame count."""
    frames, _ = VideoReader(video).read_all()
    buffer = io.BytesIO()
    with av.open(buffer, "w", format="mpegts") as out:
        stream = out.add_stream("mpeg4", rate=FPS)
        stream.width, stream.height, stream.pix_fmt = frames[0].shape[1], frames[0].shape[0], "yuv420p"
        stream.options = {"g": "1", "qscale": "1"}
        for k, frame in enumerate(frames):
            picture = av.VideoFrame.from_ndarray(frame, format="rgb24")
            picture.pts = k
            for packet in stream.encode(picture):
                out.mux(packet)
        for packet in stream.encode():
            out.mux(packet)
    return buffer.getvalue(), len(frames)


def feed(pipe: Path, data: bytes, frames: int) -> threading.Thread:
    """Write ``data`` into ``pipe`` in ``frames`` chunks at FPS (a camera sending at its own pace)."""
    def run() -> None:
        try:
            with open(pipe, "wb", buffering=0) as sink:
                step = -(-len(data) // frames)
                for start in range(0, len(data), step):
                    sink.write(data[start:start + step])
                    time.sleep(1 / FPS)
        except BrokenPipeError:
            pass

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def run(scene: Path, work: Path, mode: str, streams: dict, threads: int) -> dict:
    pipes = []
    for modality in ("rgb", "t"):
        pipe = work / f"{mode}_{modality}.pipe"
        os.mkfifo(pipe)
        pipes.append(pipe)
    count = streams["rgb"][1]
    for pipe, modality in zip(pipes, ("rgb", "t")):
        feed(pipe, streams[modality][0], count)
    out = work / f"out_{mode}"
    init = (scene / "scene_rgb.init.txt").read_text().strip().replace(" ", ",")
    command = ["rgbt", "track", *map(str, pipes), "--init", init, "--assume-aligned", "--no-plot", "--no-video",
               "-o", str(out), "--threads", str(threads)] + (["--realtime"] if mode == "realtime" else [])
    started = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    wall = time.perf_counter() - started
    if done.returncode != 0:
        raise SystemExit(f"{mode}: rgbt track failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    track = json.loads((out / "track.json").read_text())
    records, summary = track["frames"], track["summary"]
    times = np.array([r["time"] for r in records])
    source_frames = np.round(times * FPS).astype(int)
    truth = read_boxes(scene / "scene_rgb.boxes.txt")[source_frames]
    gaps = np.diff(times[1:]) if len(times) > 2 else np.array([np.nan])
    return {"mode": mode, "source s": count / FPS, "wall s": wall, "ends after source s": wall - count / FPS,
            "processed": summary["frames"],
            "dropped": summary["dropped_frames"], "init s": sum(records[0]["timing_ms"].values()) / 1000,
            "median gap s": float(np.median(gaps)), "last frame behind s": max(0.0, (count - 1) / FPS - times[-1]),
            "IoU": float(iou_continuous(read_boxes(out / "boxes_rgb.txt"), truth).mean())}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=30.0, help="scene length, seconds")
    parser.add_argument("--modes", nargs="+", default=["realtime", "plain"], choices=["realtime", "plain"])
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench_live_") as tmp:
        work = Path(tmp)
        subprocess.run(["rgbt", "synth", str(work / "scene"), "--duration", str(args.duration), "--rgb-fps", str(FPS),
                        "--t-fps", str(FPS), "--aligned", "--seed", "3"], check=True, capture_output=True)
        streams = {m: transport_stream(work / "scene" / f"scene_{m}.mp4") for m in ("rgb", "t")}
        rows = [run(work / "scene", work, mode, streams, args.threads) for mode in args.modes]
    print(f"load average {os.getloadavg()[0]:.1f}\n")
    print("| " + " | ".join(rows[0]) + " |")
    print("|" + "---|" * len(rows[0]))
    for row in rows:
        print("| " + " | ".join(f"{v:.2f}" if isinstance(v, float) else str(v) for v in row.values()) + " |")


if __name__ == "__main__":
    main()
