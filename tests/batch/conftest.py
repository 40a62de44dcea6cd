"""A small generated dataset shared by the batch tests: four RGBT234-layout sequences and one video pair."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from rgbt_toolkit.synth import generate_scene

N_SEQUENCES = 4


@pytest.fixture(scope="session")
def generated_dataset(tmp_path_factory) -> Path:
    """Read-only template: ``data/seqs/seq0..3`` (0.5 s, 8 frames each) and ``data/seqs/vid_rgb.mp4``/``vid_t.mp4``."""
    root = tmp_path_factory.mktemp("batch_data") / "seqs"
    for i in range(N_SEQUENCES):
        generate_scene(root, (), seed=i, layout="rgbt234", name=f"seq{i}", duration=0.5)
    generate_scene(root, (), seed=9, layout="videos", name="vid", duration=0.5)
    return root


@pytest.fixture()
def dataset(generated_dataset, tmp_path) -> Path:
    """A private copy of the generated dataset (tests add corrupt sequences and count calls beside it)."""
    target = tmp_path / "data" / "seqs"
    shutil.copytree(generated_dataset, target)
    return target
