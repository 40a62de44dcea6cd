"""Invariants of the fusion metrics and checks of the vectorised code against literal loop versions."""

from __future__ import annotations

import numpy as np
import pytest
from _fmi_reference import fmi_reference

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.metrics import (
    entropy,
    fmi,
    get_convention,
    mef_ssim,
    ms_ssim,
    nabf,
    paper_mutual_information,
    qabf,
    score_triple,
    ssim_same,
    ssim_valid,
)
from rgbt_toolkit.metrics.feature_mi import fmi_features, fmi_of_features
from rgbt_toolkit.metrics.ssim import _mef_ssim_single
from rgbt_toolkit.metrics.wavelet import dmey_filter, dmey_reconstruction_filters, dwt2_dmey


def _scene(shape=(64, 80), seed=0):
    """A smooth scene with edges, plus 8-bit noise: natural enough for every metric, small enough to be fast."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[: shape[0], : shape[1]]
    base = 90 + 60 * np.sin(xx / 9.0) * np.cos(yy / 13.0) + 50 * (xx > shape[1] // 2)
    return np.clip(np.round(base + rng.normal(0, 6, shape)), 0, 255)


def test_entropy_of_constant_and_flat_histogram():
    assert entropy(np.full((20, 30), 77.0)) == 0.0
    assert entropy(np.arange(256 * 4).reshape(32, 32) % 256) == pytest.approx(8.0, abs=1e-12)


def test_identical_images_give_the_ideal_scores():
    a = _scene()
    assert fmi(a, a, a, feature="wavelet") == 1.0
    assert fmi(a, a, a, feature="none") == 1.0
    assert mef_ssim([a, a], a) == pytest.approx(1.0, abs=1e-9)  # the 0.001 added to ed keeps it 1 - O(1e-12)
    assert nabf(a, a, a) == 0.0 and nabf(a, a, a, scale=1 / 255) == 0.0
    standard = 0.9994 / (1 + np.exp(-7.5)) * 0.9879 / (1 + np.exp(-22 * 0.2))
    assert qabf(a, a, a) == pytest.approx(standard, abs=1e-12)
    assert round(qabf(a, a, a), 4) == 0.9748
    assert ssim_valid(a, a) == pytest.approx(1.0) and ssim_same(a, a) == pytest.approx(1.0)
    big = _scene((180, 190))
    assert ms_ssim(big, big) == pytest.approx(1.0)


def test_paper_qabf_legacy_branch_lowers_the_identity_score():
    """On [0, 1] images the original code's tie branch sets G = gF, far below the textbook 0.9748."""
    a = _scene()
    assert qabf(a, a, a, scale=1 / 255, legacy_tie=True) < 0.7
    assert qabf(a, a, a, scale=255, legacy_tie=True) == pytest.approx(0.9994 * 0.9879 / (1 + np.exp(-4.4)), abs=2e-3)


def test_paper_mi_quirk_is_twice_the_fused_entropy():
    a, b = _scene(seed=1), _scene(seed=2)[:, ::-1]
    f = np.round((a + b) / 2)
    assert paper_mutual_information(a, b, f) == 2 * entropy(f)
    scores = score_triple(a, b, f, "paper", ["EN", "MI"])
    assert scores["MI"] == 2 * scores["EN"]
    assert score_triple(a, b, f, "standard", ["MI"])["MI"] < scores["MI"]


def test_dmey_construction_matches_matlab_filter(shared_dir):
    from scipy.io import loadmat

    matlab = loadmat(shared_dir / "reference" / "dmey_matlab_102taps.mat")["dmey"].ravel()
    ours = dmey_filter()
    assert ours.shape == (102,) and ours[-1] == 0.0
    assert np.max(np.abs(ours - matlab)) < 1e-10


def _dwt_1d_direct(x, taps):
    lf = len(taps)
    y = np.pad(x, (lf - 1, lf - 1), mode="symmetric")
    return np.convolve(y, taps[::-1], mode="valid")[1::2]  # conv with the reversed reconstruction filter


def test_dwt2_matches_direct_convolution_and_keeps_flat_regions_exact():
    lo, hi = dmey_reconstruction_filters()
    x = np.random.default_rng(1).integers(0, 256, (23, 41)).astype(float)
    ca, ch, cv, cd = dwt2_dmey(x)
    rows_lo = np.array([_dwt_1d_direct(r, lo) for r in x])
    rows_hi = np.array([_dwt_1d_direct(r, hi) for r in x])
    expect = {
        "cA": np.array([_dwt_1d_direct(c, lo) for c in rows_lo.T]).T,
        "cH": np.array([_dwt_1d_direct(c, hi) for c in rows_lo.T]).T,
        "cV": np.array([_dwt_1d_direct(c, lo) for c in rows_hi.T]).T,
        "cD": np.array([_dwt_1d_direct(c, hi) for c in rows_hi.T]).T,
    }
    for got, (name, want) in zip((ca, ch, cv, cd), expect.items()):
        assert got.shape == ((23 + 101) // 2, (41 + 101) // 2), name
        np.testing.assert_allclose(got, want, atol=1e-10, err_msg=name)
    flat = np.full((260, 300), 77.0)
    flat[:, :40] = x[0, :40]
    for band in dwt2_dmey(flat):
        assert np.unique(band[:120, 130:]).size == 1  # FMI's flat-window test needs exact equality


@pytest.mark.parametrize("feature", ["wavelet", "dct", "gradient", "none", "edge"])
def test_vectorised_fmi_matches_the_literal_algorithm(feature):
    rng = np.random.default_rng(7)
    a = _scene((22, 26), seed=3)
    b = _scene((22, 26), seed=4)[::-1]
    f = np.round(0.6 * a + 0.4 * b + rng.normal(0, 4, a.shape))
    a[:6, :7] = 10.0  # flat patches, a flat/flat pair and an exact copy exercise every branch
    f[:6, :7] = 30.0
    b[12:18, 12:20] = f[12:18, 12:20]
    features = [fmi_features(x, feature) for x in (a, b, f)]
    if feature == "wavelet":  # the 102-tap bands are large; the window logic is checked on a crop of them
        features = [x[50:80, 55:85] for x in features]
        assert fmi(a, b, f, feature=feature) == pytest.approx(fmi_of_features(*(fmi_features(x, feature)
                                                                                for x in (a, b, f))))
    assert fmi_of_features(*features) == pytest.approx(fmi_reference(*features), abs=1e-12)


def _mef_single_loop(seq, f, c, w=11):
    """Ma et al.'s mef_ssim, window by window (the published MATLAB loop)."""
    g = np.exp(-((np.arange(w) - w // 2) ** 2) / (2 * 1.5**2))
    win = np.outer(g, g) / np.outer(g, g).sum()
    r = w // 2
    eps = np.finfo(float).eps
    out = []
    for i in range(r, f.shape[0] - r):
        for j in range(r, f.shape[1] - r):
            blocks = [s[i - r : i + r + 1, j - r : j + r + 1] for s in seq]
            mus = [bk.mean() for bk in blocks]
            eds = [np.sqrt(max(np.sum((bk - m) ** 2), 0)) + 0.001 for bk, m in zip(blocks, mus)]
            den = sum(np.linalg.norm(bk - m) for bk, m in zip(blocks, mus))
            tot = sum(blocks)
            rr = (np.linalg.norm(tot - tot.mean()) + eps) / (den + eps)
            rr = 1 - eps if rr > 1 else rr
            p = min(np.tan(np.pi / 2 * rr), 10.0)
            wts = np.array([(e / w) ** p + eps for e in eds])
            wts /= wts.sum()
            rb = sum(wk * (bk - m) / e for wk, bk, m, e in zip(wts, blocks, mus, eds))
            if np.linalg.norm(rb) > 0:
                rb = rb / np.linalg.norm(rb) * max(eds)
            fb = f[i - r : i + r + 1, j - r : j + r + 1]
            m1, m2 = np.sum(win * rb), np.sum(win * fb)
            s1, s2 = np.sum(win * (rb - m1) ** 2), np.sum(win * (fb - m2) ** 2)
            s12 = np.sum(win * (rb - m1) * (fb - m2))
            out.append((2 * s12 + c) / (s1 + s2 + c))
    return float(np.mean(out))


@pytest.mark.parametrize("offset", [0.0, 0.3])  # 8-bit grid (exact flat test) and arbitrary floats (max/min test)
def test_vectorised_mef_ssim_matches_the_window_loop(offset):
    a = _scene((30, 34), seed=5) + offset
    b = _scene((30, 34), seed=6)[:, ::-1]
    a[:12, :12] = 40.0 + offset  # a flat source patch
    f = np.round(0.5 * a + 0.5 * b)
    c = (0.03 * 255) ** 2
    assert _mef_ssim_single([b, a], f, c, 11) == pytest.approx(_mef_single_loop([b, a], f, c), abs=1e-10)


def test_errors_name_the_problem():
    a = _scene()
    with pytest.raises(InputError, match="sizes differ.*the fused image must have the sources' size"):
        score_triple(a, a, a[:, :-1])
    with pytest.raises(InputError, match="sizes differ.*visible and infrared images must be registered"):
        score_triple(a, a[:, :-1], a)  # the sources themselves differ: the fused image is not what to fix
    with pytest.raises(InputError, match="unknown metric 'XYZ'"):
        score_triple(a, a, a, "paper", ["XYZ"])
    with pytest.raises(InputError, match="unknown convention"):
        get_convention("matlab")
    with pytest.raises(InputError, match="outside 0..255"):
        entropy(a + 300)
    with pytest.raises(InputError, match="at least 176"):
        ms_ssim(a, a)


def test_colour_inputs_follow_the_convention():
    grey = _scene()
    colour = np.stack([grey, np.clip(grey + 20, 0, 255), np.clip(grey - 20, 0, 255)], axis=2).astype(np.uint8)
    per_channel = score_triple(colour, grey.astype(np.uint8), colour, "vifb", ["EN", "SD"])
    channel_en = np.mean([entropy(colour[..., k].astype(float)) for k in range(3)])
    assert per_channel["EN"] == pytest.approx(channel_en)
    grey_scores = score_triple(colour, grey.astype(np.uint8), colour, "standard", ["EN"])
    from rgbt_toolkit.io.images import rgb_to_grey

    assert grey_scores["EN"] == pytest.approx(entropy(rgb_to_grey(colour).astype(float)))


@pytest.mark.parametrize("window", [5, 7])
def test_fmi_larger_windows_match_the_literal_algorithm(window):
    rng = np.random.default_rng(2)
    a, b = (rng.integers(0, 256, (14, 16)).astype(float) for _ in range(2))
    f = np.round((a + b) / 2 + rng.normal(0, 3, a.shape))
    assert fmi_of_features(a, b, f, window) == pytest.approx(fmi_reference(a, b, f, window), abs=1e-12)
    with pytest.raises(InputError, match="odd size of at least 3"):
        fmi(a, b, f, feature="none", window=4)
