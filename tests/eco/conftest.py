"""Fixtures shared by the ECO tests."""

from __future__ import annotations

import pytest

from rgbt_toolkit.errors import WeightsError


@pytest.fixture(scope="module")
def backbone():
    """EfficientNet-Lite0 with its packaged weights (the deep presets' backbone); skips where torch or the weights
    are missing."""
    pytest.importorskip("torch")
    from rgbt_toolkit.backbones import load_backbone

    try:
        return load_backbone("efficientnet-lite0")
    except WeightsError as exc:  # pragma: no cover - packaged weights missing
        pytest.skip(str(exc))
