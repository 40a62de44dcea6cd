"""``rgbt track RGB [T]``: the full JMMAC tracker on a video pair, frame folders or a benchmark sequence."""

from __future__ import annotations

import math
from pathlib import Path

import click

from rgbt_cli.options import ECO_FEATURES, apply_options, mask_options, read_masks, track_threads_option
from rgbt_cli.progress import progress_bar
from rgbt_toolkit.io.encoding import CRF_RANGE, X264_PRESETS


@click.command()
@click.argument("rgb")  # a path, or a live source: rtsp:// / udp:// URL, /dev/video*, named pipe (checked when opened)
@click.argument("thermal", required=False)
@click.option("--init", "init", default=None, help="Target box x,y,w,h in the first frame (see --init-modality).")
@click.option("--init-modality", type=click.Choice(["rgb", "t"]), default="rgb", show_default=True,
              help="Which camera's pixels --init is given in.")
@click.option("--calib", type=click.Path(exists=True, dir_okay=False), default=None,
              help="RGB->T calibration JSON from `rgbt register` (default: estimated from a few frame pairs; when "
                   "that fails the run stops and says what to give).")
@click.option("--assume-aligned", is_flag=True,
              help="The two inputs are registered already (pixel to pixel up to resolution): scale between their "
                   "sizes instead of estimating a transform.")
@click.option("--offset", type=float, default=None,
              help="Thermal clock offset in seconds, as `rgbt register --sync` prints it (t_thermal = t_rgb + "
                   "offset; default: the calibration's offset, else 0).")
@apply_options(mask_options)
@click.option("--preset", "preset_name", default="default", show_default=True,
              help="default (all modules with re-acquisition after loss; box refinement only with --detector), full "
                   "(the paper's method with the first-frame box regressor), or an ablation variant: B-RGB, B-T, "
                   "average, +MF-G, +MF-L, +MF, +CME, +TMP, +RA.")
@click.option("--motion-model", type=click.Choice(["translation", "similarity", "affine", "projective"]),
              default="affine", show_default=True, help="Camera-motion transform estimated on the thermal stream.")
@click.option("--features", type=click.Choice(ECO_FEATURES), default="hc", show_default=True,
              help="ECO features: hand-crafted (the fastest), hc+cnn (hc plus EfficientNet-Lite0's stride-4 layer: "
                   "more accurate on real footage, about 1.5x the time) or deep (its stride-16 layer too: slower, "
                   "no more accurate).")
@click.option("--mfnet-weights", type=click.Path(exists=True, dir_okay=False), default=None,
              help="MFNet weights: torch heads (.pt, from `rgbt train-mfnet`) or an ONNX export of the whole network "
                   "(.onnx, `python -m rgbt_toolkit.fusion.onnx_model`); default: the shipped tracking network.")
@click.option("--detector", type=click.Path(exists=True, dir_okay=False), default=None,
              help="ONNX detector (YOLO family) for box refinement instead of the first-frame regressor.")
@click.option("--no-video", is_flag=True, help="Skip annotated.mp4 (faster).")
@click.option("--video-scale", type=click.FloatRange(0.0, 1.0, min_open=True), default=None,
              help="Draw annotated.mp4 at this fraction of the tracked frame's size (less to encode); default: the "
                   "largest, up to 1, that keeps the two views side by side at most 1280 px wide.")
@click.option("--video-preset", type=click.Choice(X264_PRESETS), default="ultrafast", show_default=True,
              help="x264 speed preset of annotated.mp4: a slower preset writes a smaller file of the same quality.")
@click.option("--video-crf", type=click.IntRange(*CRF_RANGE), default=23, show_default=True,
              help="x264 quality of annotated.mp4 (lower: better and larger; 18 looks lossless, 28 is small).")
@click.option("--no-io-threads", is_flag=True,
              help="Decode, prepare and encode on the tracking thread (default: a reader thread decodes ahead and a "
                   "writer thread encodes annotated.mp4, overlapping the tracker; the results are the same).")
@click.option("--full-resolution", is_flag=True,
              help="Track and draw frames wider than 640 px at full size (default: shrunk to a working scale that "
                   "keeps the target's search region at ECO's sample resolution; boxes are always in full-size pixels).")
@click.option("--no-plot", is_flag=True, help="Skip track.png (centre path, q, mode, w_G, camera motion per frame).")
@click.option("--show-weights", is_flag=True, help="Overlay the fusion weight map W_F in annotated.mp4.")
@click.option("--absent", type=click.Choice(["hold", "zeros"]), default="hold", show_default=True,
              help="Box-file rows of frames where the target counts as lost (track.json present: false): the "
                   "tracker's box (benchmark convention) or 0,0,0,0.")
@click.option("--anti-uav", "anti_uav", is_flag=True,
              help="Also write NAME_RGB.json and NAME_IR.json in the Anti-UAV result format ([] where absent).")
@click.option("--max-frames", type=click.IntRange(min=1), default=None, help="Stop after this many frames.")
@click.option("--realtime", is_flag=True,
              help="Read the inputs once as live feeds (files followed while they grow) and keep latency bounded: "
                   "when tracking falls behind, track the newest frame pair and drop the older ones (counted in "
                   "track.json). Live sources need --calib or --assume-aligned.")
@click.option("-o", "--outdir", type=click.Path(file_okay=False), default=None,
              help="Output folder (default: track_<name>).")
@click.option("--force", is_flag=True, help="Replace the results of an earlier run in OUTDIR.")
@track_threads_option
def command(rgb, thermal, init, init_modality, calib, assume_aligned, offset, preset_name, motion_model, features,
            mfnet_weights, detector,
            no_video, no_plot, show_weights, absent, anti_uav, max_frames, outdir, force, threads, realtime=False,
            full_resolution=False, video_scale=None, video_preset="ultrafast", video_crf=23, no_io_threads=False,
            mask_rgb=None, mask_t=None):
    """Track one target through paired RGB and thermal videos (or frame folders, or one benchmark sequence).

    Writes boxes_rgb.txt and boxes_t.txt (x,y,w,h per frame, each camera's pixels), track.json (per-frame mode,
    MAX-PSR q, template scores, camera-motion flag, fusion weight, timings), annotated.mp4 and track.png (those
    records drawn: the centre path and, per frame, q, mode, w_G and the camera-motion flag).
    """
    from click.core import ParameterSource

    from rgbt_cli.signals import sigterm_raises
    from rgbt_toolkit.api.tracking import open_inputs, tracker_from_options
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.io.boxes import parse_box
    from rgbt_toolkit.jmmac.config import preset
    from rgbt_toolkit.jmmac.run import run_tracking
    from rgbt_toolkit.registration.calib import load_calibration
    from rgbt_toolkit.runtime import set_threads, split_tracker_threads

    library_threads, parallel_trackers = split_tracker_threads(threads, io_threads=not no_io_threads)
    set_threads(library_threads)
    from rgbt_toolkit.errors import MissingFileError
    from rgbt_toolkit.io.live import is_live

    for source in (rgb, thermal):  # a URL, device or pipe is checked when it is opened
        if source is not None and not is_live(source) and not Path(source).exists():
            raise MissingFileError(f"{source}: no such file or folder")
    given = click.get_current_context().get_parameter_source("init_modality") is ParameterSource.COMMANDLINE
    if given and init is None:
        raise InputError("--init-modality says which camera's pixels --init is in; give --init too")
    if show_weights and no_video:
        raise InputError("--show-weights draws on annotated.mp4; it cannot go with --no-video")
    for name in ("video_scale", "video_preset", "video_crf"):
        given_here = click.get_current_context().get_parameter_source(name) is ParameterSource.COMMANDLINE
        if given_here and no_video:
            flag = "--" + name.replace("_", "-")
            raise InputError(f"{flag} sets how annotated.mp4 is written; it cannot go with --no-video")
    if offset is not None and not math.isfinite(offset):
        raise click.BadParameter(f"must be a finite number of seconds, got {offset}", param_hint="'--offset'")
    preset(preset_name)  # an unknown name fails before the (long) registration estimate
    if assume_aligned and calib:
        raise InputError("give either --calib (the rig's transform) or --assume-aligned (registered footage), not both")
    if (mask_rgb or mask_t) and (calib or assume_aligned):
        raise InputError("--mask-rgb / --mask-t leave pixels out of the registration estimate; with --calib or "
                         "--assume-aligned there is none")
    calibration = load_calibration(calib) if calib else None
    masks = read_masks(mask_rgb, mask_t)
    if outdir:  # before the (long) registration estimate; a derived name is checked once the inputs are known
        _check_outdir(outdir, force)
    live = realtime or any(source is not None and is_live(source) for source in (rgb, thermal))
    # the models load before the inputs open when a live source would play on meanwhile, or when the user names
    # model files: a file that does not load then stops the run before the registration estimate, not after it
    early = live or mfnet_weights is not None or detector is not None
    tracker = tracker_from_options(preset_name, features=features, motion_model=motion_model,
                                   mfnet_weights=mfnet_weights, detector=detector,
                                   parallel_trackers=parallel_trackers) if early else None
    inputs = open_inputs(rgb, thermal, init=parse_box(init) if init else None, init_modality=init_modality,
                         calib=calibration, calib_name=calib, offset=offset, assume_aligned=assume_aligned,
                         realtime=realtime, masks=masks)
    for note in inputs.notes:
        click.echo(f"note: {note}", err=True)
    if inputs.init_source.startswith("automatic"):
        x, y, w, h_ = inputs.init_box
        click.echo(f"target chosen automatically: --init {x:.0f},{y:.0f},{w:.0f},{h_:.0f} (RGB pixels)", err=True)
    outdir = outdir or f"track_{inputs.name}"
    _check_outdir(outdir, force)
    for skipped_file, name in ((no_video, "annotated.mp4"), (no_plot, "track.png")):
        if skipped_file and (Path(outdir) / name).exists():  # forced: do not leave the earlier run's video/picture
            (Path(outdir) / name).unlink()
    if tracker is None:
        tracker = tracker_from_options(preset_name, features=features, motion_model=motion_model,
                                       mfnet_weights=mfnet_weights, detector=detector,
                                       parallel_trackers=parallel_trackers)
    total = min(inputs.frame_count, max_frames) if max_frames and inputs.frame_count else inputs.frame_count
    terminated = []  # SIGTERM stops the run like Ctrl-C: every output closed as a complete file up to that frame

    def on_sigterm(signum: int) -> BaseException:
        terminated.append(signum)
        return KeyboardInterrupt()

    with sigterm_raises(on_sigterm), progress_bar(total=total or None, unit="frame", desc=inputs.name) as bar:
        summary = run_tracking(inputs, tracker, outdir, video=not no_video, show_weights=show_weights,
                               progress=bar.update, max_frames=max_frames, plot=not no_plot, absent_rows=absent,
                               anti_uav=anti_uav, full_resolution=full_resolution,
                               io_threads=not no_io_threads, video_scale=video_scale,
                               video_preset=video_preset, video_crf=video_crf)
    state = "interrupted after" if summary["interrupted"] else "tracked"
    skipped = summary["modes"].get("skipped", 0)
    skipped = f" ({skipped} unreadable: the previous box repeated)" if skipped else ""
    lost = summary.get("absent_frames", 0)
    lost = f", target judged absent on {lost}" if lost else ""
    for note in summary.get("source_notes", []):
        click.echo(f"note: {note}", err=True)
    dropped = summary.get("dropped_frames", 0)
    dropped = f", {dropped} dropped to keep up (--realtime)" if dropped else ""
    click.echo(f"{state} {summary['frames']} frames{skipped}{lost}{dropped} at {summary['fps']} frames/s -> {outdir}")
    for name, path in summary["outputs"].items():
        click.echo(f"  {name}: {path}")
    if summary["interrupted"]:
        raise SystemExit(128 + terminated[0] if terminated else 130)


def _check_outdir(outdir: str, force: bool) -> None:
    """Refuse an output folder that cannot be made, or that holds an earlier run's results (unless ``force``)."""
    from pathlib import Path

    from rgbt_toolkit._atomic import check_folder

    check_folder(outdir, "results")
    earlier = [name for name in ("boxes_rgb.txt", "boxes_t.txt", "track.json", "annotated.mp4", "track.png")
               if (Path(outdir) / name).exists()]
    if earlier and not force:
        raise click.ClickException(f"{outdir}: holds results of an earlier run ({', '.join(earlier)}); "
                                   "choose another -o or pass --force")
