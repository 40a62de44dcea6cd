"""``rgbt track-single FRAMES_OR_VIDEO --init x,y,w,h``: the ECO tracker on one modality."""

from __future__ import annotations

from contextlib import contextmanager

import click

from rgbt_cli.options import ECO_FEATURES, threads_option
from rgbt_cli.progress import progress_bar


@click.command()
@click.argument("source", type=click.Path(exists=True))
@click.option("--init", "init", required=True, help="Target box x,y,w,h in the first frame (pixels).")
@click.option("--features", type=click.Choice(ECO_FEATURES), default="hc+cnn", show_default=True,
              help="ECO preset: hc+cnn (fHOG + colour names / intensity plus EfficientNet-Lite0's stride-4 layer: "
                   "the most accurate on real clips, about 2x hc's CPU per frame), hc (hand-crafted only, the "
                   "fastest) or deep (EfficientNet-Lite0's deep layer too; about 2x hc+cnn's CPU).")
@click.option("--colour-table", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Colour-name table in the original CNnorm.mat format, instead of the project's own.")
@click.option("--max-frames", type=click.IntRange(min=1), default=None, help="Stop after this many frames.")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Boxes file to write (x,y,w,h per frame, comma-separated).")
@click.option("--force", is_flag=True, help="Overwrite an existing boxes file.")
@click.option("--no-reacquire", is_flag=True,
              help="Do not search the whole frame for a lost target (ECO alone; see docs/eco.md, re-acquisition).")
@click.option("--absent", type=click.Choice(["hold", "zeros"]), default="hold", show_default=True,
              help="Rows of frames where the target counts as lost: the last reliable box (benchmark convention) or "
                   "0,0,0,0.")
@click.option("--anti-uav", "anti_uav", type=click.Path(dir_okay=False), default=None,
              help="Also write the Anti-UAV result format here ({\"res\": [...]}, [] on frames judged absent).")
@click.option("--plot", "plot", type=click.Path(dir_okay=False), default=None,
              help="Also draw the run as a PNG here: centre path, peak score and PSR per frame, frames judged "
                   "absent shaded.")
@click.option("--video", "video", type=click.Path(dir_okay=False), default=None,
              help="Also write an annotated MP4 here: the box (green while tracked, orange while the target counts "
                   "as lost), the last second's centre path and the frame number.")
@threads_option
def command(source, init, features, colour_table, max_frames, output, force, no_reacquire, absent, anti_uav,
            threads, plot, video):
    """Track one target through a video, a folder of frames, or a benchmark sequence folder (with img/)."""
    from pathlib import Path

    from rgbt_toolkit._atomic import check_writable
    from rgbt_toolkit.eco.params import preset
    from rgbt_toolkit.eco.reacquire import ReacquireParams
    from rgbt_toolkit.io.anti_uav import write_anti_uav_result
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.eco.run import track_frames
    from rgbt_toolkit.io.boxes import parse_box, write_boxes
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.io.images import list_images
    from rgbt_toolkit.io.sequences import LAYOUTS
    from rgbt_toolkit.runtime import set_threads

    set_threads(threads)
    box = parse_box(init)
    path = Path(source)
    if path.is_dir() and not list_images(path) and (path / "img").is_dir():
        path = path / "img"  # OTB-style sequence folder
    elif path.is_dir() and not list_images(path):
        folders = dict.fromkeys(d for layout in LAYOUTS for d in (layout.rgb_dir, layout.t_dir))
        modalities = [name for name in folders if (path / name).is_dir()]
        if modalities:
            raise InputError(f"{path}: a paired RGB-T sequence; pass one modality's folder, e.g. "
                             f"{path / modalities[0]} (or track both with `rgbt track {path}`)")
    # the boxes file and each extra output: new names, none of them an input recording
    outputs = [(output, None, "boxes file"), (anti_uav, "--anti-uav", "Anti-UAV result file"), (plot, "--plot", "plot"),
               (video, "--video", "annotated video")]
    outputs = [(target, option, what) for target, option, what in outputs if target]
    taken: set = set()
    for target, option, what in outputs:
        where = Path(target).resolve()
        if where in taken:
            itself = " - it names the boxes file itself" if where == Path(output).resolve() else ""
            raise InputError(f"{target}: {option} names another output file{itself}; choose another name")
        taken.add(where)
        check_writable(target, what, overwrite=force)
    # an unreadable frame keeps its row (the previous box again); a frame of another size is an error
    frames = open_frames(path, keep_gaps=True, fixed_size=True)
    for target, _, what in outputs:
        if frames.holds(target):
            raise InputError(f"{target}: the {what} would overwrite an input recording; choose another name")
    params = preset(features)
    if colour_table:
        params = params.with_(colour_table=colour_table)
    total = min(len(frames), max_frames) if max_frames else len(frames)
    with progress_bar(total=total or None, unit="frame", desc=path.name) as bar, \
            _annotated_video(video, frames.fps) as draw:
        first: list = []  # the first frame: the faint background of --plot
        run = track_frames(_keep_first((f for f, _ in frames), first), box, params, max_frames=max_frames,
                           progress=bar.update, reacquire=None if no_reacquire else ReacquireParams(),
                           on_frame=draw)
    rows = run.boxes.copy()
    if absent == "zeros":
        rows[~run.present] = 0.0
    write_boxes(output, rows, precision=2)
    if anti_uav:
        write_anti_uav_result(anti_uav, run.boxes, run.present)
    if plot and run.frames:
        from rgbt_toolkit.run_plots import plot_single_run

        plot_single_run(run.boxes, run.peaks, run.psrs, run.present, plot, background=first[0] if first else None,
                        title=path.name)
    if run.interrupted:  # Ctrl-C: the rows so far are written, as `rgbt track` keeps what it tracked
        click.echo(f"interrupted after {run.frames} frame{'s' if run.frames != 1 else ''} -> {output}")
        raise SystemExit(130)
    s = run.seconds
    tracked = run.frames - 1 - run.skipped
    skipped = f" ({run.skipped} unreadable: the previous box repeated)" if run.skipped else ""
    if tracked < 1:  # only the initial frame: no rate to report
        click.echo(f"tracked {run.frames} frame{'s' if run.frames != 1 else ''}{skipped} -> {output}")
        return
    per = {k: 1000 * v / tracked for k, v in s.items() if k != "initialize"}
    lost = int((~run.present).sum())
    lost_note = f", target judged absent on {lost}" if lost else ""
    click.echo(f"tracked {run.frames} frames{skipped}{lost_note} at {run.fps:.1f} frames/s with ECO {features} "
               f"-> {output}")
    click.echo("ms/frame: " + ", ".join(f"{k} {v:.1f}" for k, v in per.items()))


@contextmanager
def _annotated_video(path, fps: float):
    """A per-frame drawer writing ``path`` (None: no video, and no drawing). The video appears under its name only
    when the run ends, with the frames tracked so far after a Ctrl-C (as ``rgbt track`` keeps its video)."""
    if not path:
        yield None
        return
    from rgbt_toolkit.io.video import ThreadedVideoWriter
    from rgbt_toolkit.jmmac.annotate import SingleAnnotator, tail_length

    annotator = SingleAnnotator(tail=tail_length(fps))
    # drawn and encoded on the writer thread, in frame order, off the tracking loop (as `rgbt track` does)
    with ThreadedVideoWriter(path, fps, keep_partial=True, threads=1) as writer:
        yield lambda frame, box, present: writer.write(lambda: annotator.draw(frame, box.copy(), present))


def _keep_first(stream, first: list):
    """Pass ``stream`` through, appending its first readable frame to ``first``."""
    for frame in stream:
        if not first and frame is not None:
            first.append(frame)
        yield frame
