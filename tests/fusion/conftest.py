"""Fixtures for the fusion tests: small random heads saved to a file, generated image pairs."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from rgbt_toolkit.fusion.network import HeadConfig, MFNetHeads
from rgbt_toolkit.fusion.weights_io import save_heads


def random_heads(seed: int = 0, cfg: HeadConfig | None = None, spread: float = 0.05) -> MFNetHeads:
    """Heads whose last layers are not at their 0.5-start, so the weights vary over the image."""
    torch.manual_seed(seed)
    heads = MFNetHeads(cfg or HeadConfig())
    with torch.no_grad():
        heads.global_head.conv2.weight.normal_(0, spread)
        heads.local_head.deconv2.weight.normal_(0, spread)
    return heads.eval()


@pytest.fixture(scope="session")
def heads_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("w") / "heads.pt"
    save_heads(path, random_heads(), {"note": "test"}, half=False)
    return path


def scene(h: int, w: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A textured RGB image and a related thermal image (smooth blobs plus a hot square)."""
    rng = np.random.default_rng(seed)
    base = rng.random((h // 8 + 1, w // 8 + 1, 3))
    import cv2

    rgb = cv2.resize((base * 255).astype(np.uint8), (w, h), interpolation=cv2.INTER_CUBIC)
    t = cv2.GaussianBlur(rgb[:, :, 1], (0, 0), 3)
    t[h // 3 : h // 2, w // 3 : w // 2] = 230
    return rgb, t


@pytest.fixture(scope="session")
def make_heads():
    """The :func:`random_heads` factory, as a fixture (tests folders are not packages)."""
    return random_heads


@pytest.fixture(scope="session")
def make_scene():
    """The :func:`scene` factory, as a fixture."""
    return scene
