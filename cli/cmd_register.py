"""``rgbt register``: calibrate an RGB-thermal rig into the calibration JSON ``track``, ``fuse`` and ``batch`` read.

From the two recordings themselves (``RGB T``), or, where they share too little to register (a drone against the
sky), from other evidence: hand-picked point pairs (``--points``), a target's boxes in both cameras
(``--from-boxes``) or a heated calibration board (``--board`` with ``RGB T``).
"""

from __future__ import annotations

import json

import click

from rgbt_cli.options import apply_options, mask_options, read_masks, threads_option
from rgbt_cli.progress import progress_bar

MODEL_CHOICES = ("homography", "affine", "similarity")  # rgbt_toolkit.registration.MODELS, kept import-free here
MAX_PAIRS = 32  # rgbt_toolkit.registration.pipeline.MAX_PAIRS, kept import-free here (a test keeps them equal)
FPS = click.FloatRange(min=0.0, min_open=True)


@click.command("register")
@click.argument("rgb", type=click.Path(exists=True), required=False)
@click.argument("thermal", type=click.Path(exists=True), required=False)
@click.option("--points", type=click.Path(exists=True, dir_okay=False), default=None,
              help="Fit to hand-picked correspondences: CSV rows x_rgb, y_rgb, x_t, y_t (>= 2 for similarity, "
                   ">= 4 for homography). RGB T, if given, set the frame sizes and the --preview frames.")
@click.option("--from-boxes", "from_boxes", nargs=2, type=click.Path(exists=True, dir_okay=False), default=None,
              metavar="RGB_BOXES T_BOXES",
              help="Fit to a target's boxes in both cameras (box files of the same frames, e.g. two "
                   "`rgbt track-single` runs); also finds a frame shift between them (see --max-offset, --fps).")
@click.option("--board", default=None, metavar="COLSxROWS",
              help="Fit to a heated calibration board seen in RGB and T (images, frame folders or videos): inner "
                   "corners of a chessboard, or dots of a circle grid (--board-pattern).")
@click.option("--board-pattern", type=click.Choice(["chessboard", "circles"]), default="chessboard",
              show_default=True, help="The --board pattern.")
@click.option("--views", type=click.IntRange(min=1, max=500), default=20, show_default=True,
              help="Frame pairs searched for the --board, spread over the recordings.")
@click.option("--rgb-size", default=None, metavar="WxH",
              help="RGB frame size for --points / --from-boxes without RGB T (the calibration records it).")
@click.option("--thermal-size", default=None, metavar="WxH",
              help="Thermal frame size for --points / --from-boxes without RGB T.")
@click.option("--threshold", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Thermal pixels within which a correspondence agrees with the fit; farther ones are named as "
                   "outliers (--points/--from-boxes: 3x the residuals' robust scale, 1-30 px, printed; --board: 2).")
@click.option("--max-residual", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Largest accepted RMS residual of the kept correspondences, thermal pixels; above it no "
                   "calibration is written (--points/--from-boxes: no fixed limit; --board: 1).")
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Calibration JSON to write (atomically).")
@click.option("--model", type=click.Choice(("auto", *MODEL_CHOICES)), default=None,
              help="Transform model from RGB to thermal pixels  [default: auto for --points/--from-boxes (a "
                   "homography only when the evidence spans half the frame each way, else a similarity; the choice "
                   "is printed), homography otherwise].")
@click.option("--sync/--no-sync", default=False, show_default=True,
              help="Estimate the clock offset between the two videos from the motion they show.")
@click.option("--max-offset", type=click.FloatRange(min=0.0, min_open=True), default=2.0, show_default=True,
              help="Largest |offset| searched by --sync (or as a frame shift by --from-boxes), seconds.")
@click.option("--offset", type=click.FloatRange(min=-3600.0, max=3600.0), default=None,
              help="Known clock offset in seconds (thermal time = RGB time + offset), instead of --sync.")
@click.option("--pairs", "max_pairs", type=click.IntRange(min=1, max=MAX_PAIRS), default=4, show_default=True,
              help="Frame pairs (spread over the recording) used for the spatial estimate.")
@click.option("--fps", type=FPS, default=None,
              help="Frame rate of frame folders, both cameras (videos carry their own timestamps), and of the "
                   "--from-boxes tracks; default 30.")
@click.option("--rgb-fps", type=FPS, default=None, help="Frame rate of an RGB frame folder (overrides --fps).")
@click.option("--thermal-fps", type=FPS, default=None, help="Frame rate of a thermal frame folder (overrides --fps).")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Write a check image (.png, .jpg, ...) of the warped RGB against the thermal frame.")
@click.option("--preview-mode", type=click.Choice(["checkerboard", "overlay"]), default=None,
              help="How --preview draws the check  [default: checkerboard].")
@click.option("--force", is_flag=True, help="Overwrite existing output files.")
@click.option("--json", "as_json", is_flag=True, help="Print the calibration as JSON instead of a summary.")
@apply_options(mask_options)
@threads_option
def command(rgb, thermal, points, from_boxes, board, board_pattern, views, rgb_size, thermal_size, threshold,
            max_residual, output, model, sync, max_offset, offset, max_pairs, fps, rgb_fps, thermal_fps, preview,
            preview_mode, force, as_json, mask_rgb, mask_t, threads):
    """Estimate how RGB pixels map to THERMAL pixels (and the clock offset with --sync); save it to -o.

    \b
    rgbt register RGB T -o calib.json                   the recordings themselves
    rgbt register --points pts.csv --rgb-size 1920x1080 --thermal-size 640x512 -o calib.json
    rgbt register --from-boxes rgb.txt t.txt --rgb-size 1920x1080 --thermal-size 640x512 -o calib.json
    rgbt register --board 9x6 board_rgb.mp4 board_t.mp4 -o calib.json
    """
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.registration.calib import save_calibration
    from rgbt_toolkit.registration.pipeline import RegisterSettings, register_paths
    from rgbt_toolkit.registration.report import check_outputs, summary_lines, write_preview
    from rgbt_toolkit.registration.spatial import SpatialSettings
    from rgbt_toolkit.runtime import set_threads

    set_threads(threads)
    if sync and offset is not None:
        raise InputError("give either --sync (estimate the offset) or --offset (a known one), not both")
    if preview_mode is not None and not preview:
        raise InputError("--preview-mode needs --preview PATH (the check image it draws)")
    evidence = [name for name, given in (("--points", points), ("--from-boxes", from_boxes), ("--board", board))
                if given]
    if len(evidence) > 1:
        raise InputError(f"give one source of evidence, not {' and '.join(evidence)}")
    if (rgb is None) != (thermal is None):
        raise InputError("give both recordings, RGB and THERMAL (or neither, with --points or --from-boxes)")
    if model == "auto" and evidence[:1] not in (["--points"], ["--from-boxes"]):
        raise InputError("--model auto weighs the spread of --points or --from-boxes evidence; give homography, "
                         "affine or similarity")
    if (mask_rgb or mask_t) and evidence:
        raise InputError(f"--mask-rgb / --mask-t leave pixels out of the estimate from the recordings themselves; "
                         f"they do not go with {evidence[0]}")
    if evidence and evidence[0] != "--board":
        if sync:
            raise InputError(f"--sync estimates the offset from the recordings; it does not go with {evidence[0]}")
        _register_fitted(rgb, thermal, points, from_boxes, rgb_size, thermal_size, threshold, max_residual, output,
                         model or "auto", max_offset, offset, fps, rgb_fps, thermal_fps, preview, preview_mode, force,
                         as_json)
        return
    if rgb is None:
        raise InputError("nothing to calibrate from: give the RGB and THERMAL recordings, or --points FILE, or "
                         "--from-boxes RGB_BOXES T_BOXES (see rgbt register --help)")
    if rgb_size or thermal_size:
        raise InputError("--rgb-size and --thermal-size are for --points / --from-boxes; the recordings carry "
                         "their own sizes")
    if board:
        if sync or offset is not None:
            raise InputError("--board pairs board frames by time; --sync and --offset do not apply")
        _register_board(rgb, thermal, board, board_pattern, views, threshold, max_residual, output,
                        model or "homography", fps, preview, preview_mode, force, as_json)
        return
    if threshold is not None or max_residual is not None:
        raise InputError("--threshold and --max-residual apply to --points, --from-boxes and --board")
    masks = read_masks(mask_rgb, mask_t)
    check_outputs(output, preview, (rgb, thermal), force=force)
    settings = RegisterSettings(spatial=SpatialSettings(model=model or "homography"), sync=sync,
                                max_offset=max_offset, max_pairs=max_pairs, offset=offset or 0.0)
    with progress_bar(desc="reading frames", unit="frame", leave=False) as bar:
        result = register_paths(rgb, thermal, settings, fps=fps, rgb_fps=rgb_fps, thermal_fps=thermal_fps,
                                on_frame=bar.update, masks=masks)
    if preview:  # first: a preview that cannot be drawn leaves no calibration behind
        write_preview(preview, rgb, thermal, result.calibration, times=result.preview_times,
                      mode=preview_mode or "checkerboard", fps=fps, rgb_fps=rgb_fps, thermal_fps=thermal_fps)
    save_calibration(output, result.calibration)
    if as_json:
        click.echo(json.dumps(result.calibration.to_dict(), indent=2))
    else:
        for line in summary_lines(result):
            click.echo(line)
        click.echo(f"calibration written to {output}" + (f", preview to {preview}" if preview else ""))


def _size(text: str | None, option: str) -> tuple[int, int] | None:
    if text is None:
        return None
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise click.BadParameter(f"'{text}' is not WIDTHxHEIGHT", param_hint=option) from None
    if w < 1 or h < 1:
        raise click.BadParameter(f"'{text}': width and height must be positive", param_hint=option)
    return w, h


def _report(result, output, preview, preview_mode, rgb, thermal, fps, rgb_fps, thermal_fps, as_json) -> None:
    """Preview (first: one that cannot be drawn leaves no calibration), the calibration file, then the summary."""
    from rgbt_toolkit.registration.calib import save_calibration
    from rgbt_toolkit.registration.fit import fit_summary_lines
    from rgbt_toolkit.registration.report import write_preview

    if preview:
        write_preview(preview, rgb, thermal, result.calibration, mode=preview_mode or "checkerboard", fps=fps,
                      rgb_fps=rgb_fps, thermal_fps=thermal_fps)
    save_calibration(output, result.calibration)
    if as_json:
        click.echo(json.dumps(result.calibration.to_dict(), indent=2))
        return
    for line in fit_summary_lines(result):
        click.echo(line)
    click.echo(f"calibration written to {output}" + (f", preview to {preview}" if preview else ""))


def _register_fitted(rgb, thermal, points, from_boxes, rgb_size, thermal_size, threshold, max_residual, output, model,
                     max_offset, offset, fps, rgb_fps, thermal_fps, preview, preview_mode, force, as_json) -> None:
    """--points / --from-boxes: frame sizes from RGB T or the size options, then the fit."""
    from dataclasses import replace

    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.io.frames import open_frames
    from rgbt_toolkit.registration.report import check_outputs

    sizes = _size(rgb_size, "--rgb-size"), _size(thermal_size, "--thermal-size")
    if rgb is not None:
        if any(sizes):
            raise InputError("give either RGB T (their frames set the sizes) or --rgb-size/--thermal-size, not both")
        sizes = open_frames(rgb, fps=rgb_fps or fps).size, open_frames(thermal, fps=thermal_fps or fps).size
    elif not all(sizes):
        raise InputError("the calibration records both frame sizes: give --rgb-size WxH and --thermal-size WxH, or "
                         "the RGB and THERMAL recordings")
    if preview and rgb is None:
        raise InputError("--preview draws the warped RGB frame on the thermal one: give the RGB and THERMAL "
                         "recordings too")
    if preview_mode is not None and not preview:
        raise InputError("--preview-mode needs --preview PATH (the check image it draws)")
    inputs = tuple(p for p in (rgb, thermal, points, *(from_boxes or ())) if p is not None)
    check_outputs(output, preview, inputs, force=force)
    limits = {k: v for k, v in (("threshold", threshold), ("max_rms", max_residual)) if v is not None}
    if points:
        from rgbt_toolkit.registration.from_points import calibrate_from_points

        result = calibrate_from_points(points, sizes[0], sizes[1], model=model, **limits)
    else:
        from rgbt_toolkit.registration.from_boxes import calibrate_from_boxes

        result = calibrate_from_boxes(from_boxes[0], from_boxes[1], sizes[0], sizes[1], model=model,
                                      fps=fps or 30.0, max_offset=0.0 if offset is not None else max_offset,
                                      **limits)
    if offset is not None:  # a known clock offset given with the evidence is recorded as given
        result = replace(result, calibration=replace(result.calibration, time_offset=float(offset)))
    _report(result, output, preview, preview_mode, rgb, thermal, fps, rgb_fps, thermal_fps, as_json)


def _register_board(rgb, thermal, board, pattern, views, threshold, max_residual, output, model, fps, preview,
                    preview_mode, force, as_json) -> None:
    from rgbt_toolkit.registration.board import BoardSpec, calibrate_from_board
    from rgbt_toolkit.registration.report import check_outputs

    spec = BoardSpec.parse(board, pattern)
    check_outputs(output, preview, (rgb, thermal), force=force)
    limits = {k: v for k, v in (("threshold", threshold), ("max_rms", max_residual)) if v is not None}
    result = calibrate_from_board(rgb, thermal, spec, model=model, views=views, fps=fps, **limits)
    _report(result, output, preview, preview_mode, rgb, thermal, fps, None, None, as_json)
