"""Options shared by several commands, defined once."""

from __future__ import annotations

import click

threads_option = click.option(
    "--threads",
    type=click.IntRange(min=1),
    default=None,
    help="CPU threads for torch, OpenCV and BLAS each (default: $RGBT_THREADS or 1).",
)

track_threads_option = click.option(
    "--threads",
    type=click.IntRange(min=1),
    default=None,
    help="CPU threads for the whole run (default: $RGBT_THREADS or 2). One goes to the threads that decode ahead "
         "and encode the video (unless --no-io-threads); with 2 or more left the RGB and thermal trackers run side "
         "by side and each library gets half of them, else they take turns on one.",
)

output_format_option = click.option(
    "--format",
    "output_format",
    type=click.Choice(["table", "csv", "json"]),
    default="table",
    show_default=True,
    help="Output format.",
)

output_file_option = click.option(
    "-o",
    "--output",
    type=click.Path(dir_okay=False, writable=True),
    default=None,
    help="Write the table to this file (atomically) instead of stdout.",
)

# rgbt_toolkit.eco.params.PRESETS, kept import-free for the same reason (a test keeps them equal): the ECO features
# of `rgbt track` and `rgbt track-single`
ECO_FEATURES = ("hc", "hc+cnn", "deep")

# rgbt_toolkit.metrics.conventions.CONVENTIONS, kept import-free so `rgbt --help` stays fast (a test keeps them equal)
FUSION_CONVENTIONS = ("paper", "vifb", "standard")

fusion_metric_options = [
    click.option("--convention", type=click.Choice(FUSION_CONVENTIONS), default="paper", show_default=True,
                 help="Which code family's definitions to use."),
    click.option("--metrics", default=None, help="Comma-separated metric names (default: the convention's set)."),
]


# masks of what a camera's frames show that the registration must leave out (docs/registration.md, "Overlays")
mask_options = [
    click.option("--mask-rgb", type=click.Path(exists=True, dir_okay=False), default=None,
                 help="Image (PNG, any size) non-zero where the RGB frames are to be left out of the registration "
                      "estimate: an overlay, logo or part of the rig it does not find by itself."),
    click.option("--mask-t", type=click.Path(exists=True, dir_okay=False), default=None,
                 help="The same for the thermal frames."),
]


def read_masks(mask_rgb, mask_t):
    """(RGB, thermal) mask arrays from the two options' paths (None where not given)."""
    from rgbt_toolkit.registration.overlays import read_mask

    return tuple(None if path is None else read_mask(path) for path in (mask_rgb, mask_t))


def apply_options(options):
    """Decorator applying a list of click options in order (shared option groups)."""

    def decorate(function):
        for option in reversed(options):
            function = option(function)
        return function

    return decorate
