"""``rgbt fusion-metrics``: score fused visible/infrared images with the metrics of published tables."""

from __future__ import annotations

import click

from rgbt_cli.options import (
    apply_options,
    fusion_metric_options,
    output_file_option,
    output_format_option,
    threads_option,
)
from rgbt_cli.progress import progress_bar


@click.command(epilog="Conventions: paper = JMMAC/DenseFuse table code (compatibility mode; its MI is 2*EN), "
                      "vifb = VIFB benchmark, standard = textbook definitions. Metrics: EN, MI, CE, Qabf, Nabf, "
                      "FMI_w, FMI_dct, FMI_edge, FMI_pixel, SSIM, MS_SSIM, MEF_SSIM, SD, SF, AG, EI, PSNR, RMSE, CC, "
                      "SCD, VIF, Qcb, Qcv. See docs/fusion_metrics.md.")
@click.option("--vis", required=True, type=click.Path(exists=True), help="Visible image or folder.")
@click.option("--ir", required=True, type=click.Path(exists=True), help="Infrared image or folder.")
@click.option("--fused", required=True, type=click.Path(exists=True),
              help="Fused image or folder; files pair by stem as <stem>.<ext> or <stem>_<method>.<ext>.")
@apply_options(fusion_metric_options)
@output_format_option
@output_file_option
@threads_option
def command(vis, ir, fused, convention, metrics, output_format, output, threads):
    """Score fused images against their visible and infrared sources; one row per image, a mean per method."""
    from rgbt_toolkit._atomic import check_writable, write_text_atomic
    from rgbt_toolkit.metrics.report import render
    from rgbt_toolkit.metrics.scoring import pair_by_stem, score_folders
    from rgbt_toolkit.runtime import set_threads

    if output:
        check_writable(output, "table", overwrite=True)  # before scoring: a bad -o fails at once
    set_threads(threads)
    names = [m.strip() for m in metrics.split(",") if m.strip()] if metrics else None
    total = len(pair_by_stem(vis, ir, fused)[0])
    with progress_bar(total=total, unit="image", desc="scoring") as bar:
        table = score_folders(vis, ir, fused, convention=convention, metrics=names, progress=bar.update)
    text = render(table, output_format)
    if output and table.rows:
        write_text_atomic(output, text)
    elif not output:
        click.echo(text, nl=False)
    if table.errors:
        kept = ""
        if output:  # a table of headers alone would look like a result
            kept = f"; {output} holds the {len(table.rows)} scored" if table.rows else f"; {output} not written"
        click.echo(f"{len(table.errors)} image(s) could not be scored{kept}:", err=True)
        for line in table.errors:
            click.echo(f"  {line}", err=True)
        raise SystemExit(1)
