"""Save and load MFNet head weights, with the head configuration stored beside the tensors.

File format (a ``torch.save`` dict): ``{"format": "rgbt-mfnet-heads", "version": 1, "config": HeadConfig fields,
"state": state dict (float16 to keep the shipped file small), "meta": free-form training record}``.
"""

from __future__ import annotations

from pathlib import Path

import torch

from rgbt_toolkit._atomic import atomic_path, check_writable
from rgbt_toolkit.errors import MissingFileError, WeightsError
from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads

FORMAT = "rgbt-mfnet-heads"
VERSION = 1
DEFAULT_WEIGHTS = Path(__file__).resolve().parent / "weights" / "mfnet_heads.pt"


def save_heads(path: str | Path, heads: MFNetHeads, meta: dict | None = None, half: bool = True) -> None:
    """Write ``heads`` to ``path`` atomically (float16 tensors unless ``half=False``)."""
    bad = _non_finite(heads.state_dict())
    if bad:
        raise WeightsError(f"{path}: not written, tensor {bad!r} holds NaN or infinite values (training diverged; "
                           "lower the learning rates)")
    state = {k: (v.detach().half() if half and v.is_floating_point() else v.detach()).cpu().clone()
             for k, v in heads.state_dict().items()}
    bad = _non_finite(state)
    if bad:
        raise WeightsError(f"{path}: not written, tensor {bad!r} overflows float16; save with half=False")
    blob = {"format": FORMAT, "version": VERSION, "config": heads.cfg.to_dict(), "state": state, "meta": meta or {}}
    with atomic_path(path) as tmp:
        torch.save(blob, tmp)


def read_meta(path: str | Path | None = None) -> dict:
    """The training record stored with a weight file."""
    return dict(_read_blob(Path(path) if path is not None else DEFAULT_WEIGHTS)["meta"])


def load_heads(path: str | Path | None = None, expect: HeadConfig | None = None) -> MFNetHeads:
    """Load heads from ``path`` (``None``: the shipped weights); float32, eval mode.

    Parameters
    ----------
    path : str or Path, optional
        A file written by :func:`save_heads` (``rgbt train-mfnet``).
    expect : HeadConfig, optional
        Raise :class:`WeightsError` if the file's backbone/layer/channels differ (e.g. heads trained on VGG-M
        features used with EfficientNet-Lite0).
    """
    path = Path(path) if path is not None else DEFAULT_WEIGHTS
    blob = _read_blob(path)
    try:
        cfg = HeadConfig(**blob["config"])
    except TypeError as exc:
        raise WeightsError(f"{path}: head configuration not understood ({exc}); re-train with this version") from None
    if expect is not None:
        for field in ("backbone", "layer", "in_channels"):
            if getattr(cfg, field) != getattr(expect, field):
                raise WeightsError(
                    f"{path}: heads were trained for {field}={getattr(cfg, field)!r}, this model uses "
                    f"{getattr(expect, field)!r}; use weights trained for the same backbone (rgbt train-mfnet)"
                )
    heads = MFNetHeads(cfg)
    own = heads.state_dict()
    state = blob["state"]
    missing = [k for k in own if k not in state]
    extra = [k for k in state if k not in own]
    if missing or extra:
        first = missing[0] if missing else extra[0]
        raise WeightsError(f"{path}: {len(missing)} missing and {len(extra)} unexpected tensors (first {first!r})")
    for k, v in own.items():
        if tuple(state[k].shape) != tuple(v.shape):
            raise WeightsError(f"{path}: tensor {k!r} has shape {tuple(state[k].shape)}, expected {tuple(v.shape)}")
    bad = _non_finite(state)
    if bad:
        raise WeightsError(f"{path}: tensor {bad!r} holds NaN or infinite values; the file is unusable, re-train it "
                           "(rgbt train-mfnet)")
    heads.load_state_dict({k: v.float() for k, v in state.items()}, strict=True)
    return heads.eval()


def check_output(path: str | Path, overwrite: bool = False) -> Path:
    """Check, before any training, that a weight file can be written at ``path`` (see :func:`check_writable`)."""
    return check_writable(path, "weight file", overwrite=overwrite)


def _non_finite(state: dict) -> str | None:
    """Name of the first floating-point tensor with a NaN or infinite value, or None."""
    for k, v in state.items():
        if torch.is_tensor(v) and v.is_floating_point() and not torch.isfinite(v).all():
            return k
    return None


def _read_blob(path: Path) -> dict:
    if not path.is_file():
        raise MissingFileError(f"{path}: MFNet weight file not found; train one with `rgbt train-mfnet`")
    try:
        blob = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # torch raises pickle/zip/runtime errors for a corrupt file
        raise WeightsError(f"{path}: not a readable torch file ({type(exc).__name__})") from None
    if not isinstance(blob, dict) or blob.get("format") != FORMAT:
        raise WeightsError(f"{path}: not an MFNet head file (no format={FORMAT!r}); was it written by train-mfnet?")
    if blob.get("version") != VERSION:
        raise WeightsError(f"{path}: MFNet head file version {blob.get('version')}, this toolkit reads {VERSION}")
    return blob
