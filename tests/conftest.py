"""Shared fixtures: the location of ../shared and skips when it is absent."""

from __future__ import annotations

from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared"


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    """``../shared`` beside the checkout; the test is skipped when it is absent."""
    if not (SHARED / "README.md").is_file():
        pytest.skip("../shared reference data is absent (fresh clone without it)")
    return SHARED
