"""``rgbt train-mfnet``: train MFNet's fusion heads on aligned RGB-T pairs or sequences (see docs/fusion.md)."""

from __future__ import annotations

import click

from rgbt_cli.options import threads_option
from rgbt_cli.progress import progress_bar


@click.command("train-mfnet")
@click.option("--data", "data", required=True, multiple=True, type=click.Path(exists=True, file_okay=False),
              help="Aligned pairs (DIR/vi + DIR/ir, paired by stem), an RGB-T sequence folder or a dataset folder of "
                   "sequences (GTOT, RGBT234, LasHeR, ...); repeat for several folders (repeats count once).")
@click.option("-o", "--output", required=True, type=click.Path(dir_okay=False),
              help="Weight file to write (.pt); checked before training (not a folder, not existing without --force).")
@click.option("--samples", type=click.IntRange(min=8), default=None, help="Training pairs to draw [1200].")
@click.option("--val-samples", type=click.IntRange(min=8), default=None, help="Held-out pairs to draw [240].")
@click.option("--epochs", default=None, metavar="G,L,J", help="Epochs of the global, local, joint stages [6,4,2].")
@click.option("--lr", default=None, metavar="G,L,J",
              help="Learning rates of the global, local, joint stages [1e-4,1e-2,5e-5].")
@click.option("--local-init", type=float, default=None,
              help="Starting logit of the local weight W_L (3: W_L = 0.95, as in both shipped files; 0: 0.5) [3].")
@click.option("--kinds", default=None, metavar="K1,K2,...",
              help="Sample conditions of image-pair training samples, drawn in equal shares [all six: clean, rgb_dark, "
                   "rgb_glare, t_crossover, rgb_distractor, t_distractor].")
@click.option("--seed", type=int, default=0, show_default=True, help="Seed of sampling, initialisation, shuffling.")
@click.option("--source", type=click.Choice(["dcf", "eco"]), default="dcf", show_default=True,
              help="Tracker responses to fuse during training (eco needs rgbt_toolkit.eco).")
@click.option("--force", is_flag=True, help="Overwrite an existing output file.")
@threads_option
def command(data, output, samples, val_samples, epochs, lr, local_init, kinds, seed, source, force, threads):
    """Train MFNet heads (global, then local, then joint) with the paper's loss and write them to OUTPUT."""
    import dataclasses
    import json
    import math

    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.fusion.responses import DcfResponseSource, EcoResponseSource
    from rgbt_toolkit.fusion.train import Stage, TrainSettings, train_mfnet
    from rgbt_toolkit.fusion.weights_io import check_output
    from rgbt_toolkit.runtime import set_threads

    set_threads(threads)
    check_output(output, force)
    if local_init is not None and not math.isfinite(local_init):
        raise InputError(f"--local-init {local_init}: expected a finite number (3: W_L = 0.95, 0: 0.5)")
    settings = TrainSettings(seed=seed)
    if samples is not None:
        settings = dataclasses.replace(settings, samples=samples)
    if val_samples is not None:
        settings = dataclasses.replace(settings, val_samples=val_samples)
    if local_init is not None:
        settings = dataclasses.replace(settings, local_init=local_init)
    if kinds is not None:
        from rgbt_toolkit.fusion.trainset import check_kinds

        chosen = tuple(k.strip() for k in kinds.split(",") if k.strip())
        check_kinds(chosen)
        settings = dataclasses.replace(settings, sample=dataclasses.replace(settings.sample, kinds=chosen))
    counts = _triple("--epochs", epochs, int, "three non-negative integers G,L,J, e.g. 6,4,2")
    rates = _triple("--lr", lr, float, "three positive learning rates G,L,J, e.g. 1e-4,1e-2,5e-5")
    if counts and min(counts) < 0:
        raise InputError(f"--epochs {epochs!r}: epochs must be >= 0")
    if counts and sum(counts) == 0:
        raise InputError(f"--epochs {epochs!r}: no stage would train; give at least one stage an epoch, e.g. 6,4,2")
    if rates and not all(math.isfinite(r) and r > 0 for r in rates):
        raise InputError(f"--lr {lr!r}: learning rates must be finite numbers > 0")
    settings = dataclasses.replace(settings, stages=tuple(
        Stage(s.name, counts[k] if counts else s.epochs, rates[k] if rates else s.lr)
        for k, s in enumerate(settings.stages)))
    if source == "eco":
        try:
            resp = EcoResponseSource()
        except ImportError:
            raise InputError("--source eco: rgbt_toolkit.eco is not available in this installation; use dcf") from None
    else:
        resp = DcfResponseSource()
    total = settings.samples + settings.val_samples + sum(s.epochs for s in settings.stages)
    with progress_bar(total=total, unit="step") as bar:
        meta = train_mfnet(list(data), output, settings, source=resp, progress=lambda what, n: bar.update(n),
                           overwrite=force, warn=lambda text: click.echo(f"warning: {text}", err=True))
    val = meta["validation"]
    click.echo(json.dumps(_finite({"output": str(output), "validation": val,
                                   "validation_on_training_data": meta["validation_on_training_data"]}),
                          indent=1, allow_nan=False))
    where = "training" if meta["validation_on_training_data"] else "held-out"
    click.echo(f"wrote {output}: {where} peak hit mfnet {val['mfnet']['hit']:.3f} (avg {val['avg']['hit']:.3f}, "
               f"rgb {val['rgb']['hit']:.3f}, t {val['t']['hit']:.3f}), fused-response loss "
               f"{val['mfnet']['loss']:.3f} (avg {val['avg']['loss']:.3f})", err=True)


def _finite(value):
    """``value`` with every non-finite float replaced by None, so the JSON never holds NaN or Infinity."""
    import math

    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _triple(option: str, text: str | None, kind, expected: str) -> list | None:
    """Parse ``G,L,J`` into three values of ``kind`` (None when the option was not given)."""
    from rgbt_toolkit.errors import InputError

    if text is None:
        return None
    try:
        values = [kind(x) for x in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3:
        raise InputError(f"{option} {text!r}: expected {expected}")
    return values
