"""``rgbt fuse VIS IR -o OUT``: fuse visible and infrared images with MFNet."""

from __future__ import annotations

import click

from rgbt_cli.options import threads_option


@click.command("fuse")
@click.argument("vis", type=click.Path(exists=True))
@click.argument("ir", type=click.Path(exists=True))
@click.option("-o", "--output", required=True, type=click.Path(),
              help="Output image (one pair) or folder (<stem>.png per pair).")
@click.option("--weights", "weights", type=click.Path(dir_okay=False), default=None,
              help="MFNet head weights (default: the shipped ones).")
@click.option("--backbone-weights", type=click.Path(dir_okay=False), default=None,
              help="User weights for the backbone named in the head file (needed for vggm).")
@click.option("--save-weights", is_flag=True, help="Also write the weight map W_F as <name>_weights.png (heat map).")
@click.option("--calib", type=click.Path(dir_okay=False), default=None,
              help='Calibration from `rgbt register`, or JSON {"H": 3x3} mapping infrared pixels onto the '
                   'visible image, for unregistered pairs.')
@click.option("--net-side", type=click.IntRange(min=32), default=None,
              help="Long side of the network input in pixels [192].")
@click.option("--mode", type=click.Choice(["mfnet", "global", "local"]), default="mfnet", show_default=True,
              help="Fusion weight: both heads, global only, local only (the paper's ablation).")
@click.option("--force", is_flag=True, help="Overwrite existing outputs.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON line per pair (weights, timings).")
@threads_option
def command(vis, ir, output, weights, backbone_weights, save_weights, calib, net_side, mode, force, as_json,
            threads):
    """Fuse VIS and IR (two image files, or two folders paired by file stem) into OUTPUT."""
    import dataclasses
    import json

    from tqdm import tqdm

    from rgbt_toolkit.fusion.fuse_files import fuse_files
    from rgbt_toolkit.fusion.image_fusion import FuseSettings
    from rgbt_toolkit.fusion.model import MFNet
    from rgbt_toolkit.fusion.pairs import pair_inputs, read_homography
    from rgbt_toolkit.runtime import set_threads

    set_threads(threads)
    pairs = pair_inputs(vis, ir)
    homography = read_homography(calib) if calib else None
    settings = FuseSettings(use_global=mode != "local", use_local=mode != "global")
    if net_side is not None:
        settings = dataclasses.replace(settings, net_side=net_side)
    net = MFNet.from_file(weights, backbone_weights)
    for report in tqdm(fuse_files(pairs, output, net, settings, homography, save_weights, force),
                       total=len(pairs), disable=None if not as_json else True, unit="pair"):
        if as_json:
            click.echo(json.dumps({"vis": str(report.vis), "ir": str(report.ir), "out": str(report.out),
                                   "w_g": round(report.w_g, 4), "mean_w_f": round(report.mean_w_f, 4),
                                   "ms": {k: round(v * 1000, 2) for k, v in report.timings.items()}}))
