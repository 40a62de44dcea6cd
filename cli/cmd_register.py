"""``rgbt register RGB T -o calib.json``: calibrate an RGB-thermal rig from two videos, frame folders or images."""

from __future__ import annotations

import json

import click

from rgbt_cli.options import threads_option

MODEL_CHOICES = ("homography", "affine", "similarity")  # rgbt_toolkit.registration.MODELS, kept import-free here


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
@click.option("--pairs", "max_pairs", type=click.IntRange(min=1), default=4, show_default=True,
              help="Frame pairs (spread over the recording) used for the spatial estimate.")
@click.option("--fps", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Frame rate of frame folders (videos carry their own timestamps; default 30).")
@click.option("--preview", type=click.Path(dir_okay=False), default=None,
              help="Write a check image (PNG) of the warped RGB against the thermal frame.")
@click.option("--preview-mode", type=click.Choice(["checkerboard", "overlay"]), default="checkerboard",
              show_default=True)
@click.option("--force", is_flag=True, help="Overwrite an existing output file.")
@click.option("--json", "as_json", is_flag=True, help="Print the calibration as JSON instead of a summary.")
@threads_option
def command(rgb, thermal, output, model, sync, max_offset, max_pairs, fps, preview, preview_mode, force, as_json,
            threads):
    """Estimate how RGB pixels map to THERMAL pixels (and the clock offset with --sync); save it to -o."""
    from pathlib import Path

    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.registration.calib import save_calibration
    from rgbt_toolkit.registration.pipeline import RegisterSettings, register_paths
    from rgbt_toolkit.registration.report import summary_lines, write_preview
    from rgbt_toolkit.registration.spatial import SpatialSettings
    from rgbt_toolkit.runtime import set_threads

    set_threads(threads)
    for path in (output, preview):
        if path and Path(path).exists() and not force:
            raise InputError(f"{path}: already exists; pass --force to overwrite")
    settings = RegisterSettings(spatial=SpatialSettings(model=model), sync=sync, max_offset=max_offset,
                                max_pairs=max_pairs)
    result = register_paths(rgb, thermal, settings, fps=fps)
    save_calibration(output, result.calibration)
    if preview:
        write_preview(preview, rgb, thermal, result.calibration, mode=preview_mode, fps=fps)
    if as_json:
        click.echo(json.dumps(result.calibration.to_dict(), indent=2))
    else:
        for line in summary_lines(result):
            click.echo(line)
        click.echo(f"calibration written to {output}" + (f", preview to {preview}" if preview else ""))
