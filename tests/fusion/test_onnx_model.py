"""MFNet through ONNX Runtime (``fusion.onnx_model``): the shipped export gives the torch heads' weights, bad files
get one-line errors, and building the default tracker imports neither torch nor scipy.stats."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from rgbt_toolkit.errors import MissingFileError, WeightsError
from rgbt_toolkit.fusion.onnx_model import TRACKING_ONNX, OnnxMfnet, export_onnx
from rgbt_toolkit.jmmac.fusion_part import MfnetWeighting

pytest.importorskip("onnxruntime")


@pytest.fixture(scope="module")
def torch_mfnet():
    from rgbt_toolkit.fusion.model import MFNet
    from rgbt_toolkit.jmmac.api import TRACKING_HEADS

    return MFNet.from_file(TRACKING_HEADS)


def _frames(seed: int):
    rng = np.random.default_rng(seed)
    rgb = rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)
    thermal = cv2_blur(rng.integers(0, 255, (120, 160), dtype=np.uint8))
    return rgb, thermal


def cv2_blur(image):
    import cv2

    return cv2.GaussianBlur(image, (0, 0), 2)


def test_shipped_export_matches_the_torch_heads(torch_mfnet):
    """Stale export guard: retrained heads without `python -m rgbt_toolkit.fusion.onnx_model` fail here."""
    onnx_part, torch_part = MfnetWeighting(OnnxMfnet()), MfnetWeighting(torch_mfnet)
    for seed, region, grid in ((0, [40.0, 20.0, 60.0, 60.0], (25, 25)), (1, [-10.0, 30.0, 90.0, 90.0], (31, 31))):
        rgb, thermal = _frames(seed)
        g_onnx, l_onnx = onnx_part(rgb, thermal, np.array(region), grid)
        g_torch, l_torch = torch_part(rgb, thermal, np.array(region), grid)
        assert g_onnx == pytest.approx(g_torch, abs=1e-5)
        assert l_onnx.shape == grid and np.max(np.abs(l_onnx - l_torch)) < 1e-5


def test_a_user_export_loads_and_runs(torch_mfnet, tmp_path):
    pytest.importorskip("onnx")
    path = export_onnx(torch_mfnet, tmp_path / "mine.onnx", patch=64)
    rgb, thermal = _frames(2)
    w_g, w_l = OnnxMfnet(path).patch_weights(rgb[:64, :64], thermal[:64, :64], (9, 9))
    ref_g, ref_l = MfnetWeighting(torch_mfnet).net.patch_weights(rgb[:64, :64], thermal[:64, :64], (9, 9))
    assert w_g == pytest.approx(ref_g, abs=1e-5) and np.allclose(w_l, ref_l, atol=1e-5)


def test_bad_files_get_one_line_errors(tmp_path):
    with pytest.raises(MissingFileError, match="missing.onnx: MFNet ONNX file not found"):
        OnnxMfnet(tmp_path / "missing.onnx")
    junk = tmp_path / "junk.onnx"
    junk.write_bytes(b"not a model")
    with pytest.raises(WeightsError, match="junk.onnx: not a loadable ONNX model"):
        OnnxMfnet(junk)


def test_a_foreign_onnx_model_is_refused(tmp_path):
    shared_nano = TRACKING_ONNX.parents[3].parent / "shared" / "models" / "nanotrack_head_sim.onnx"
    if not shared_nano.is_file():
        pytest.skip("../shared/models absent")
    with pytest.raises(WeightsError, match="not an MFNet export"):
        OnnxMfnet(shared_nano)


def test_default_tracker_starts_without_torch_or_scipy_stats():
    code = ("import sys; from rgbt_toolkit.jmmac.api import build_tracker; from rgbt_toolkit.jmmac.config import preset;"
            "build_tracker(preset('default'));"
            "print(sorted(m for m in ('torch', 'scipy.stats', 'filterpy') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_shipped_ddis_layer_matches_the_torch_backbone():
    """DDIS template features (motion.parts.backbone_features) run the shipped ONNX layer; torch gives the same."""
    import torch

    from rgbt_toolkit.backbones import load_backbone
    from rgbt_toolkit.motion.parts import backbone_features

    rng = np.random.default_rng(4)
    net = load_backbone("efficientnet-lite0")
    for patch in (rng.integers(0, 255, (48, 40, 3), dtype=np.uint8), rng.integers(0, 255, (44, 52), dtype=np.uint8),
                  rng.integers(0, 255, (20, 72, 3), dtype=np.uint8)):
        ours = backbone_features()(patch)
        img = np.repeat(patch[..., None], 3, axis=-1) if patch.ndim == 2 else patch
        x = torch.from_numpy(np.ascontiguousarray(img)).permute(2, 0, 1)[None].float() / 255.0
        ref = net.extract(x, ("shallow",))["shallow"][0].permute(1, 2, 0).numpy()
        assert ours.shape == ref.shape and np.max(np.abs(ours - ref)) < 1e-4 * max(1.0, np.abs(ref).max())


def test_sizes_the_export_cannot_serve_are_refused():
    from rgbt_toolkit.errors import InputError
    from rgbt_toolkit.fusion.onnx_model import SHALLOW_ONNX, OnnxLayers

    with pytest.raises(InputError, match="multiples of 4"):
        OnnxLayers(SHALLOW_ONNX, 4)(np.zeros((45, 48), np.uint8))
    with pytest.raises(InputError, match="multiples of 16"):
        OnnxMfnet().patch_weights(np.zeros((120, 120, 3), np.uint8), np.zeros((120, 120), np.uint8), (9, 9))
