"""`rgbt fuse` through ONNX Runtime: the shipped image-fusion export gives the torch heads' fused images (a stale
export fails here), any image size works, and the default command never imports torch.

Tolerance: both networks see the same padded uint8 input and differ only by float32 rounding in about 40 layers;
measured |dW_F| <= 7e-7 on TNO and random images. We allow 1e-5 (the ONNX tracking test's bound). A weight error e
moves a fused value by e * |Y - T| <= 255 e < 0.003 grey levels, so only pixels whose blend lands within 0.003 of a
rounding boundary (x.5) may change, by one level: at most 1 level, on under 0.1 % of the pixels. Heads that are not
the shipped ones (a stale export) differ by orders of magnitude more (the tracking heads: > 0.01).
"""

from __future__ import annotations

import subprocess
import sys

import cv2
import numpy as np
import pytest

from rgbt_toolkit.fusion.fuse_files import load_fusion_net
from rgbt_toolkit.fusion.image_fusion import FuseSettings, fuse_images
from rgbt_toolkit.fusion.onnx_model import IMAGE_ONNX, TRACKING_ONNX, OnnxMfnet

pytest.importorskip("onnxruntime")

W_TOL = 1e-5  # see the module docstring


@pytest.fixture(scope="module")
def torch_net():
    from rgbt_toolkit.fusion.model import MFNet

    return MFNet.from_file()  # the shipped image-fusion heads, weights/mfnet_heads.pt


def _pair(h: int, w: int, seed: int, colour: bool) -> tuple[np.ndarray, np.ndarray]:
    """A textured visible image and a smoother thermal one with a hot region (structure, so W_F varies)."""
    rng = np.random.default_rng(seed)
    base = cv2.resize(rng.integers(0, 255, (h // 6 + 1, w // 6 + 1, 3), dtype=np.uint8), (w, h),
                      interpolation=cv2.INTER_CUBIC)
    thermal = cv2.GaussianBlur(base[:, :, 1], (0, 0), 3)
    thermal[h // 4: h // 2, w // 3: w // 2] = 235
    return (base if colour else base[:, :, 0].copy()), thermal


def _differences(a, b) -> tuple[float, float, int, float]:
    """(|dw_G|, max |dW_F|, max |d fused| in grey levels, fraction of fused values that differ)."""
    d = np.abs(a.fused.astype(int) - b.fused.astype(int))
    return abs(a.w_g - b.w_g), float(np.abs(a.w_f - b.w_f).max()), int(d.max()), float(np.mean(d > 0))


# 640x480 (192x144, no padding), sizes whose network input is padded (139.4 -> 140 -> 144 rows; 37x250), colour and
# grey, and a small image that is not reduced at all
CASES = [((480, 640), True), ((450, 620), False), ((37, 250), True), ((101, 157), False)]


@pytest.mark.parametrize("shape,colour", CASES)
def test_shipped_image_export_matches_the_torch_heads(torch_net, shape, colour):
    """Stale export guard: retraining weights/mfnet_heads.pt without `python -m rgbt_toolkit.fusion.onnx_model`
    fails here."""
    vis, ir = _pair(*shape, seed=sum(shape), colour=colour)
    ours, ref = fuse_images(vis, ir, load_fusion_net()), fuse_images(vis, ir, torch_net)
    dg, dw, dfused, frac = _differences(ours, ref)
    assert ours.fused.shape == vis.shape and ours.w_f.shape == shape
    assert dg < W_TOL and dw < W_TOL and dfused <= 1 and frac < 1e-3


def test_the_guard_catches_other_heads(torch_net):
    """The comparison above has teeth: the tracking export (same graph, other heads) is far outside the tolerance."""
    vis, ir = _pair(144, 192, seed=3, colour=True)
    other = fuse_images(vis, ir, OnnxMfnet(TRACKING_ONNX))
    dg, dw, _, _ = _differences(other, fuse_images(vis, ir, torch_net))
    assert max(dg, dw) > 1000 * W_TOL


@pytest.mark.parametrize("mode", [FuseSettings(use_local=False), FuseSettings(use_global=False)])
def test_ablations_match_too(torch_net, mode):
    vis, ir = _pair(450, 620, seed=5, colour=False)
    ours, ref = fuse_images(vis, ir, load_fusion_net(), mode), fuse_images(vis, ir, torch_net, mode)
    _, dw, dfused, _ = _differences(ours, ref)
    assert dw < W_TOL and dfused <= 1


def test_the_default_network_is_the_onnx_export_and_pt_weights_stay_on_torch(heads_file):
    from rgbt_toolkit.fusion.model import MFNet

    net = load_fusion_net()
    assert isinstance(net, OnnxMfnet) and net.path == IMAGE_ONNX
    assert isinstance(load_fusion_net(heads_file), MFNet)


def test_default_fuse_command_runs_without_torch(tmp_path):
    vis, ir = _pair(120, 170, seed=7, colour=True)
    cv2.imwrite(str(tmp_path / "v.png"), vis)
    cv2.imwrite(str(tmp_path / "t.png"), ir)
    code = ("import sys; from rgbt_cli.main import main\n"
            f"main(['fuse', {str(tmp_path / 'v.png')!r}, {str(tmp_path / 't.png')!r}, '-o', "
            f"{str(tmp_path / 'f.png')!r}], standalone_mode=False)\n"
            "print(sorted(m for m in ('torch', 'torchvision') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "[]"
    fused = cv2.imread(str(tmp_path / "f.png"))
    assert fused is not None and fused.shape == (120, 170, 3)
