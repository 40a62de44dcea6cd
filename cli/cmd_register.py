"""``rgbt register RGB T -o calib.json``: calibrate an RGB-thermal rig from two videos, frame folders or images."""

from __future__ import annotations

import json

import click

from rgbt_cli.options import threads_option

MODEL_CHOICES = ("homography", "affine", "similarity")  # rgbt_toolkit.registration.MODELS, kept import-free here
MAX_PAIRS = 32  # rgbt_toolkit.registration.pipeline.MAX_PAIRS, kept import-free here (a test keeps them equal)
FPS = click.FloatRange(min=0.0, min_open=True)


@click.command("register")
@click.argument("rgb", type=click.Path(exists=True))
@click.argument("thermal", type=click.Path(exists=True))
@click.option("-o", "--output", type=click.Path(dir_okay=False), required=True,
              help="Calibration JSON to write (atomically).")
@click.option("--model", type=click.Choice(MODEL_CHOICES), default="homography", show_default=True,
              help="Transform model from RGB to thermal pixels.")
@click.option("--sync/--no-sync", default=False, show_default=True,
              help="Estimate the clock offset between the two videos from the motion they show.")
@click.option("--max-offset", type=click.FloatRange(min=0.0, min_open=True), default=2.0, show_default=True,
              help="Largest |offset| searched by --sync, seconds.")
@click.option("--offset", type=click.FloatRange(min=-3600.0, max=3600.0), default=None,
              help="Known clock offset in seconds (thermal time = RGB time + offset), instead of --sync.")
@click.option("--pairs", "max_pairs", type=click.IntRange(min=1, max=MAX_PAIRS), default=4, show_default=True,
              help="Frame pairs (spread over the recording) used for the spatial estimate.")
@click.option("--fps", type=FPS, default=None,
              help="Frame rate of frame folders, both cameras (videos carry their own timestamps; default 30).")
@click.option("--rgb-fps", type=FPS, default=None, help="Frame rate of an RGB frame folder (overrides --fps).")
@click.option("--thermal-fps", type=FPS, default=None, help="Frame rate of a thermal frame folder (overrides --fps).")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Write a check image (.png, .jpg, ...) of the warped RGB against the thermal frame.")
@click.option("--preview-mode", type=click.Choice(["checkerboard", "overlay"]), default=None,
              help="How --preview draws the check  [default: checkerboard].")
@click.option("--force", is_flag=True, help="Overwrite existing output files.")
@click.option("--json", "as_json", is_flag=True, help="Print the calibration as JSON instead of a summary.")
@threads_option
def command(rgb, thermal, output, model, sync, max_offset, offset, max_pairs, fps, rgb_fps, thermal_fps, preview,
            preview_mode, force, as_json, threads):
    """Estimate how RGB pixels map to THERMAL pixels (and the clock offset with --sync); save it to -o."""
    from tqdm import tqdm

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
    check_outputs(output, preview, (rgb, thermal), force=force)
    settings = RegisterSettings(spatial=SpatialSettings(model=model), sync=sync, max_offset=max_offset,
                                max_pairs=max_pairs, offset=offset or 0.0)
    with tqdm(desc="reading frames", unit="frame", disable=None, leave=False) as bar:
        result = register_paths(rgb, thermal, settings, fps=fps, rgb_fps=rgb_fps, thermal_fps=thermal_fps,
                                on_frame=bar.update)
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
