"""``rgbt fuse VIS IR -o OUT``: fuse visible and infrared images with MFNet."""

from __future__ import annotations

import click

from rgbt_cli.options import threads_option
from rgbt_cli.progress import progress_items

_SHOWN = 5  # unpaired file names listed in the warning before "and N more"


@click.command("fuse")
@click.argument("vis", type=click.Path(exists=True))
@click.argument("ir", type=click.Path(exists=True))
@click.option("-o", "--output", required=True, type=click.Path(),
              help="Two folders: OUT is a folder (created), one <stem>.png per pair. Two files: OUT is the fused "
                   "image if it ends in .png/.jpg/.jpeg/.bmp/.tif/.tiff, else a folder (existing, or a name without "
                   "a suffix) receiving <stem>.png; other suffixes are refused.")
@click.option("--weights", "weights", type=click.Path(dir_okay=False), default=None,
              help="MFNet head weights, a .pt file from `rgbt train-mfnet` (run in torch; default: the shipped "
                   "heads, run as an ONNX export without torch).")
@click.option("--backbone-weights", type=click.Path(dir_okay=False), default=None,
              help="User weights for the backbone named in the head file (needed for vggm).")
@click.option("--save-weights", is_flag=True, help="Also write the weight map W_F as <name>_weights.png (heat map).")
@click.option("--registered", is_flag=True,
              help="The pair is co-registered (same field of view) but may differ in resolution: resize the "
                   "infrared image onto the visible image's grid.")
@click.option("--calib", type=click.Path(dir_okay=False), default=None,
              help='Calibration from `rgbt register`, or JSON {"H": 3x3} mapping infrared pixels onto the '
                   'visible image, for unregistered pairs.')
@click.option("--net-side", type=click.IntRange(min=32), default=None,
              help="Long side of the network input in pixels [192].")
@click.option("--mode", type=click.Choice(["mfnet", "global", "local"]), default="mfnet", show_default=True,
              help="Fusion weight: both heads, global only, local only (the paper's ablation).")
@click.option("--force", is_flag=True, help="Overwrite existing outputs.")
@click.option("--skip-existing", is_flag=True,
              help="Skip pairs whose outputs exist (re-run after a partial failure); without it or --force, "
                   "existing outputs stop the run before anything is fused.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON line per pair (weights, timings, error).")
@threads_option
def command(vis, ir, output, weights, backbone_weights, save_weights, registered, calib, net_side, mode, force,
            skip_existing, as_json, threads):
    """Fuse VIS and IR (two image files, or two folders paired by file stem) into OUTPUT.

    A pair that cannot be fused (unreadable file, sizes that differ) is skipped; the others are fused, every
    failure is listed at the end and the exit status is 1.
    """
    import dataclasses
    import json

    from pathlib import Path

    from rgbt_toolkit._atomic import check_folder
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.fusion.fuse_files import fuse_planned, load_fusion_net, plan_outputs
    from rgbt_toolkit.fusion.image_fusion import FuseSettings
    from rgbt_toolkit.fusion.pairs import Alignment, find_pairs, read_calibration
    from rgbt_toolkit.runtime import set_threads

    if force and skip_existing:
        raise InputError("--force (overwrite existing outputs) and --skip-existing (keep them) exclude each other")
    if registered and calib:
        raise InputError("--registered and --calib exclude each other: --calib already aligns the pair")
    threads = set_threads(threads)
    check_folder(Path(output).parent, "fused image")
    found = find_pairs(vis, ir)
    for side, names in (("visible", found.only_vis), ("infrared", found.only_ir)):
        if names:
            more = f" and {len(names) - _SHOWN} more" if len(names) > _SHOWN else ""
            click.echo(f"warning: {len(names)} {side} image(s) without a partner of the same stem, not fused: "
                       f"{', '.join(names[:_SHOWN])}{more}", err=True)
    alignment = read_calibration(calib) if calib else Alignment(resize=registered)
    planned = plan_outputs(found.pairs, output, found.folders, save_weights, force, skip_existing)  # before loading
    settings = FuseSettings(use_global=mode != "local", use_local=mode != "global")
    if net_side is not None:
        settings = dataclasses.replace(settings, net_side=net_side)
    net = load_fusion_net(weights, backbone_weights, threads)
    failed, fused, skipped = [], 0, 0
    reports = fuse_planned(planned, net, settings, alignment)
    if len(found.pairs) > 1 and not as_json:  # a bar for one pair is noise
        reports = progress_items(reports, total=len(found.pairs), unit="pair")
    for report in reports:
        fused += report.ok and not report.skipped
        skipped += report.skipped
        if not report.ok:
            failed.append(report)
        if as_json:
            click.echo(json.dumps(_record(report), allow_nan=False))
    if skipped:
        click.echo(f"skipped {skipped} pair(s) whose outputs exist (--skip-existing)", err=True)
    if failed and not found.folders:  # one pair: its problem is the error line
        raise click.ClickException(failed[0].error)
    if failed:
        click.echo(f"fused {fused} of {len(found.pairs)} pair(s); {len(failed)} failed:", err=True)
        for report in failed:
            click.echo(f"  {report.error}", err=True)
        click.get_current_context().exit(1)


def _record(report) -> dict:
    """One pair as a JSON-safe record (no NaN: values of failed or skipped pairs are omitted)."""
    import math

    record = {"vis": str(report.vis), "ir": str(report.ir), "out": str(report.out)}
    if report.skipped:
        return {**record, "skipped": True}
    if not report.ok:
        return {**record, "error": report.error}

    def num(value, digits):
        return round(value, digits) if math.isfinite(value) else None

    return {**record, "w_g": num(report.w_g, 4), "mean_w_f": num(report.mean_w_f, 4),
            "ms": {k: num(v * 1000, 2) for k, v in report.timings.items()}}
