"""Training MFNet's heads (paper, implementation details) on cached backbone features and tracker responses.

Loss ``L = ||R_F - Y||^2`` (sum over the response map, mean over the batch) with ``R_F = W_F R_RGB + (1 - W_F) R_T``
and ``Y`` a Gaussian at the true target position. Schedule: the global head alone (``W_L = 1``), then the local head
with the global head frozen, then both jointly at a lower rate; SGD with momentum 0.9, weight decay 5e-4, batch 8.

The backbone is frozen, so its features of every search patch are computed once (``build_cache``) and the heads train
on the cache: a CPU run takes minutes. The paper's learning rates (1e-5, 1e-7 for fine-tuning) belong to its
MatConvNet loss scale; ours were chosen on this loss (see ``TrainSettings.stages``), keep the paper's order (joint
fine-tuning slower than the head stages) and are recorded in the weight file's metadata.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
import torch

from rgbt_toolkit.backbones import Backbone
from rgbt_toolkit.errors import InputError, WeightsError
from rgbt_toolkit.fusion.model import to_tensor
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads, fuse_responses
from rgbt_toolkit.fusion.responses import DcfResponseSource, ResponseSource, gaussian_label
from rgbt_toolkit.fusion.sources import (SampleSource, collect_units, count_units, make_source, split_units,
                                         unique_folders)
from rgbt_toolkit.fusion.trainset import KINDS, SampleSettings


@dataclass(frozen=True)
class Stage:
    """One phase of the schedule."""

    name: str  # "global", "local" or "joint"
    epochs: int
    lr: float


@dataclass(frozen=True)
class TrainSettings:
    """Everything that determines a training run (stored in the weight file)."""

    samples: int = 1200  # training pairs drawn (plus val_samples held out on separate images / sequences)
    val_samples: int = 240
    val_fraction: float = 0.15  # share of the source images and sequences kept for validation only
    batch: int = 8  # paper
    momentum: float = 0.9  # paper
    weight_decay: float = 5e-4  # paper
    # Rates: 1e-3 on the global head let its ReLUs die within an epoch (constant w_G); 1e-4 trains it stably.
    # The local head starts at W_L = sigmoid(local_init) = 0.95, where the sigmoid's slope is 0.045 (0.25 at 0):
    # at 5e-4 it stayed flat (W_F std 0.003 over held-out RoadScene images); 1e-2 lets it learn (held-out
    # fused-response loss 2.43 -> 2.29, peak hit 0.729 -> 0.758 on RoadScene-derived pairs, docs/fusion.md).
    stages: tuple[Stage, ...] = (Stage("global", 6, 1e-4), Stage("local", 4, 1e-2), Stage("joint", 2, 5e-5))
    local_init: float = 3.0  # initial logit of W_L (HeadConfig.local_init); 0.0 was the start before this setting
    label_sigma: float = 1.0 / 8.0  # Y: Gaussian sigma relative to sqrt(w h)
    seed: int = 0
    sample: SampleSettings = field(default_factory=SampleSettings)

    def __post_init__(self):
        for stage in self.stages:
            if not (math.isfinite(stage.lr) and stage.lr > 0):
                raise InputError(f"learning rate of the {stage.name} stage must be a finite number > 0, got {stage.lr}")
            if stage.epochs < 0:
                raise InputError(f"epochs of the {stage.name} stage must be >= 0, got {stage.epochs}")
        if not math.isfinite(self.local_init):
            raise InputError(f"local_init must be a finite logit (e.g. 3: W_L = 0.95), got {self.local_init}")
        if self.samples < 1 or self.val_samples < 1 or self.batch < 1:
            raise InputError("samples, val_samples and batch must be >= 1")
        if not 0.0 <= self.val_fraction < 1.0:
            raise InputError(f"val_fraction must be in [0, 1), got {self.val_fraction}")


@dataclass
class Cache:
    """Backbone features, responses and labels of every training pair."""

    feat_rgb: torch.Tensor  # [N, C, h, w] float16
    feat_t: torch.Tensor
    r_rgb: torch.Tensor  # [N, M, N] float32
    r_t: torch.Tensor
    label: torch.Tensor
    kinds: list[str]

    def subset(self, idx: np.ndarray) -> "Cache":
        i = torch.as_tensor(idx)
        return Cache(self.feat_rgb[i], self.feat_t[i], self.r_rgb[i], self.r_t[i], self.label[i],
                     [self.kinds[k] for k in idx])

    def __len__(self) -> int:
        return len(self.kinds)


def build_cache(
    samples: SampleSource, n: int, backbone: Backbone, layer: str, source: ResponseSource, settings: TrainSettings,
    rng: np.random.Generator, progress: Callable[[int], None] | None = None, chunk: int = 16,
) -> Cache:
    """Draw ``n`` training pairs from ``samples`` (:mod:`rgbt_toolkit.fusion.sources`) and cache features,
    responses and labels."""
    feats_rgb, feats_t, rr, rt, ys, kinds = [], [], [], [], [], []
    batch_rgb, batch_t = [], []

    def flush():
        if batch_rgb:
            f = backbone.extract(torch.cat([to_tensor(batch_rgb), to_tensor(batch_t)]), (layer,))[layer]
            feats_rgb.append(f[: len(batch_rgb)].half())
            feats_t.append(f[len(batch_rgb):].half())
            if progress is not None:
                progress(len(batch_rgb))
            batch_rgb.clear()
            batch_t.clear()

    for k in range(n):
        s = samples.draw(k, rng)
        r1, r2 = source(s)
        rr.append(r1)
        rt.append(r2)
        ys.append(gaussian_label(s.search_box, settings.sample.patch, r1.shape, settings.label_sigma))
        kinds.append(s.kind)
        batch_rgb.append(s.search_rgb)
        batch_t.append(s.search_t)
        if len(batch_rgb) == chunk:
            flush()
    flush()
    as_t = lambda a: torch.from_numpy(np.stack(a))  # noqa: E731
    return Cache(torch.cat(feats_rgb), torch.cat(feats_t), as_t(rr), as_t(rt), as_t(ys), kinds)


def fused_loss(heads: MFNetHeads, c: Cache, idx, use_global=True, use_local=True) -> torch.Tensor:
    """Paper loss on the cached items ``idx``: mean over the batch of sum((R_F - Y)^2)."""
    r_rgb, r_t, y = c.r_rgb[idx], c.r_t[idx], c.label[idx]
    _, _, w_f = heads(c.feat_rgb[idx].float(), c.feat_t[idx].float(), tuple(y.shape[1:]), use_global, use_local)
    return ((fuse_responses(w_f, r_rgb, r_t) - y) ** 2).sum(dim=(1, 2)).mean()


def train_step(heads: MFNetHeads, opt: torch.optim.Optimizer, c: Cache, idx, stage: str) -> float:
    """One SGD step of ``stage`` on items ``idx``; returns the loss before the step."""
    heads.train()
    opt.zero_grad()
    loss = fused_loss(heads, c, idx, use_global=stage != "localonly", use_local=stage != "global")
    loss.backward()
    opt.step()
    return float(loss.detach())


def _stage_params(heads: MFNetHeads, stage: str):
    trainable = {"global": [heads.global_head], "local": [heads.local_head], "joint": [heads.global_head,
                 heads.local_head]}[stage]
    for p in heads.parameters():
        p.requires_grad_(False)
    params = [p for m in trainable for p in m.parameters()]
    for p in params:
        p.requires_grad_(True)
    return params


def train_heads(
    train: Cache, settings: TrainSettings, heads: MFNetHeads | None = None, cfg: HeadConfig | None = None,
    on_epoch: Callable[[str, int, float], None] | None = None,
) -> tuple[MFNetHeads, list[dict]]:
    """Run the three-stage schedule on a cache; returns the heads and one history row per epoch."""
    torch.manual_seed(settings.seed)  # head initialisation and shuffling (the seed is part of the settings)
    heads = heads if heads is not None else MFNetHeads(
        cfg or HeadConfig(in_channels=2 * train.feat_rgb.shape[1], local_init=settings.local_init))
    gen = torch.Generator().manual_seed(settings.seed)
    history = []
    for stage in settings.stages:
        params = _stage_params(heads, stage.name)
        opt = torch.optim.SGD(params, lr=stage.lr, momentum=settings.momentum, weight_decay=settings.weight_decay)
        for epoch in range(stage.epochs):
            order = torch.randperm(len(train), generator=gen)
            losses = [train_step(heads, opt, train, order[i : i + settings.batch], stage.name)
                      for i in range(0, len(train) - settings.batch + 1, settings.batch)]
            loss = float(np.mean(losses)) if losses else float("nan")
            if losses and not math.isfinite(loss):
                raise WeightsError(f"training diverged in the {stage.name} stage, epoch {epoch + 1} (loss {loss}); "
                                   f"lower its learning rate (now {stage.lr:g}); nothing was written")
            history.append({"stage": stage.name, "epoch": epoch, "loss": loss})
            if on_epoch is not None:
                on_epoch(stage.name, epoch, loss)
    for p in heads.parameters():
        p.requires_grad_(False)
    return heads.eval(), history


def evaluate(heads: MFNetHeads, c: Cache, radius: float = 2.0) -> dict[str, dict[str, float]]:
    """Loss and peak hit rate (fused peak within ``radius`` cells of the label peak) per fusion rule and kind.

    Rules: ``rgb`` / ``t`` (one modality), ``avg`` (fixed 0.5/0.5), ``global`` (MF-G), ``local`` (MF-L), ``mfnet``.
    """
    idx = torch.arange(len(c))
    with torch.no_grad():
        out = {}
        m = c.label.shape[1:]
        w_g, w_l, w_f = heads(c.feat_rgb.float(), c.feat_t.float(), tuple(m))
        ones = torch.ones_like(w_f)
        rules = {"rgb": ones, "t": 0 * ones, "avg": 0.5 * ones, "global": w_g[:, None, None] * ones,
                 "local": w_l, "mfnet": w_f}
        peak_y = _peaks(c.label[idx])
        kinds = [k for k in KINDS if k in c.kinds] + sorted(set(c.kinds) - set(KINDS))
        for name, w in rules.items():
            r = fuse_responses(w, c.r_rgb, c.r_t)
            loss = ((r - c.label) ** 2).sum(dim=(1, 2))
            hit = (torch.linalg.norm((_peaks(r) - peak_y).float(), dim=1) <= radius).float()
            row = {"loss": float(loss.mean()), "hit": float(hit.mean())}
            for kind in kinds:
                sel = torch.tensor([k == kind for k in c.kinds])
                if sel.any():
                    row[f"hit_{kind}"] = float(hit[sel].mean())
            out[name] = row
        kinds_wg = {kind: float(w_g[torch.tensor([k == kind for k in c.kinds])].mean()) for kind in kinds}
        out["w_g_mean"] = kinds_wg
    return out


def _peaks(r: torch.Tensor) -> torch.Tensor:
    flat = r.reshape(r.shape[0], -1).argmax(dim=1)
    return torch.stack([flat // r.shape[2], flat % r.shape[2]], dim=1)


def settings_record(settings: TrainSettings) -> dict:
    """JSON-friendly copy of the settings for the weight file's metadata."""
    d = asdict(settings)
    d["stages"] = [asdict(s) for s in settings.stages]
    return d


def default_source() -> ResponseSource:
    """The DCF response source (the shipped weights use it; pass ``EcoResponseSource()`` for ECO responses)."""
    return DcfResponseSource()


def train_mfnet(
    data: Sequence[str | Path], out: str | Path, settings: TrainSettings = TrainSettings(),
    backbone: Backbone | None = None, layer: str = "deep", source: ResponseSource | None = None,
    progress: Callable[[str, int], None] | None = None, overwrite: bool = False,
    warn: Callable[[str], None] | None = None,
) -> dict:
    """The whole recipe behind ``rgbt train-mfnet``: sample, cache, train, evaluate on held-out images, save.

    The output is checked before any work (:func:`~rgbt_toolkit.fusion.weights_io.check_output`; an existing file
    needs ``overwrite``). Repeated ``data`` folders count once. ``warn(message)`` is told when nothing can be held out
    (one image pair or sequence): the validation figures are then measured on training data
    (``meta["validation_on_training_data"]``). Returns the report stored in the weight file's ``meta`` (settings,
    source, history, validation figures).
    """
    from rgbt_toolkit.backbones import load_backbone
    from rgbt_toolkit.fusion.weights_io import check_output, save_heads

    check_output(out, overwrite)
    data = unique_folders(data)
    backbone = backbone if backbone is not None else load_backbone("efficientnet-lite0")
    source = source if source is not None else default_source()
    rng = np.random.default_rng(settings.seed)
    train_units, val_units = split_units(collect_units(data), settings.val_fraction, rng)
    train_src = make_source(train_units, settings.sample)
    val_src = make_source(val_units, settings.sample) if val_units else train_src
    if not val_units and warn is not None:
        warn(f"only {len(train_units)} image pair or sequence in the training data: nothing is held out, so the "
             "validation figures are measured on training data; add more --data")
    tick = (lambda what: (lambda n: progress(what, n))) if progress else (lambda what: None)  # noqa: E731
    train = build_cache(train_src, settings.samples, backbone, layer, source, settings, rng, tick("cache"))
    val = build_cache(val_src, settings.val_samples, backbone, layer, source, settings, rng,
                      tick("cache"))
    cfg = HeadConfig(in_channels=2 * backbone.channels[layer], backbone=backbone.name, layer=layer,
                     local_init=settings.local_init)
    heads, history = train_heads(train, settings, cfg=cfg,
                                 on_epoch=(lambda st, e, l: progress("epoch", 1)) if progress else None)
    meta = {
        "settings": settings_record(settings),
        "response_source": type(source).__name__,
        "data": [str(Path(d)) for d in data],
        **{f"train_{k}": v for k, v in count_units(train_units).items()},
        **{f"val_{k}": v for k, v in count_units(val_units).items()},
        "history": history,
        "validation": evaluate(heads, val),
        "validation_on_training_data": not val_units,
    }
    save_heads(out, heads, meta)
    return meta
