"""Feature extractors: shapes, value ranges, invariances, the colour table loader, and a reference comparison."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from rgbt_toolkit.errors import FileFormatError, InputError, MissingFileError
from rgbt_toolkit.features.colornames import TERMS, ColourNames, load_colour_table, membership, own_table, table_index
from rgbt_toolkit.features.fhog import FHog
from rgbt_toolkit.features.intensity import Intensity
from rgbt_toolkit.features.pooling import cells_at_scales


def _patches(n=2, size=48, seed=0, colour=True):
    rng = np.random.default_rng(seed)
    x = rng.random((n, size, size, 3 if colour else 1)).astype(np.float32)
    x = np.stack([cv2.GaussianBlur(p, (0, 0), 1.5).reshape(p.shape) for p in x])
    x = (255 * (x - x.min()) / (x.max() - x.min())).astype(np.uint8)
    return x if colour else x[..., 0]


def test_fhog_shape_range_and_grey_equals_replicated_grey():
    p = _patches()
    h = FHog().compute(p)[0]
    assert h.shape == (2, 12, 12, 31) and h.dtype == np.float32
    assert h.min() >= 0 and h[..., :27].max() <= 4 * 0.2 * 0.5 + 1e-6  # four clipped terms, halved
    grey = p[..., 0]
    np.testing.assert_allclose(FHog().compute(grey)[0], FHog().compute(np.repeat(grey[..., None], 3, -1))[0],
                               atol=1e-6)


def test_fhog_is_invariant_to_contrast_and_brightness():
    p = _patches(colour=False)
    low = (p.astype(np.float32) * 0.5 + 40).astype(np.uint8)  # affine change without clipping
    high = (low.astype(np.float32) * 2.0 - 80).clip(0, 255).astype(np.uint8)
    a, b = FHog().compute(low)[0], FHog().compute(high)[0]
    assert np.abs(a - b).max() < 0.03  # block normalisation (eps and 8-bit rounding aside)


def test_fhog_orientation_bins_follow_the_gradient_direction():
    # a vertical step edge (intensity rising to the right) has gradient angle 0 -> contrast-sensitive bin 0
    p = np.zeros((1, 32, 32), np.uint8)
    p[:, :, 16:] = 200
    h = FHog().compute(p)[0]
    cell = h[0, 4, 3]  # a cell on the edge (cells 3/4 straddle column 16)
    assert np.argmax(cell[:18]) in (0, 17) and np.argmax(cell[18:27]) in (0, 8)
    # the mirrored edge (falling to the right) points the other way: bin 9
    q = 200 - p
    assert np.argmax(FHog().compute(q)[0][0, 4, 3, :18]) in (8, 9, 10)


def test_colour_names_shape_membership_and_uniform_patch():
    assert own_table().shape == (32768, 10)
    probs = membership(np.array([[220, 20, 30], [30, 60, 210], [250, 250, 250], [5, 5, 5]], np.uint8))
    np.testing.assert_allclose(probs.sum(1), 1.0)
    assert [TERMS[i] for i in probs.argmax(1)] == ["red", "blue", "white", "black"]
    uniform = np.full((1, 16, 16, 3), (30, 160, 60), np.uint8)
    cn = ColourNames().compute(uniform)[0]
    assert cn.shape == (1, 4, 4, 10)
    np.testing.assert_allclose(cn, np.broadcast_to(cn[:, :1, :1], cn.shape), atol=1e-6)  # the same everywhere
    np.testing.assert_allclose(cn[0, 0, 0], own_table()[table_index(uniform[0, 0, 0])], atol=1e-6)


def test_colour_table_built_in_the_background_is_the_table_and_is_built_once(monkeypatch):
    from rgbt_toolkit.features import colornames

    expected = own_table().copy()
    builds = []
    real_membership = colornames.membership
    monkeypatch.setattr(colornames, "membership", lambda rgb: builds.append(len(rgb)) or real_membership(rgb))
    colornames._build_own_table.cache_clear()
    try:
        thread = colornames.build_table_in_background()
        table = own_table()  # whichever of the two threads comes second finds the table built
        assert colornames.build_table_in_background() is None  # built: nothing to start
        thread.join()
    finally:
        colornames._build_own_table.cache_clear()
    assert builds == [32768]
    np.testing.assert_array_equal(table, expected)


def test_colour_table_loader(tmp_path):
    from scipy.io import savemat

    good = tmp_path / "t.mat"
    savemat(good, {"CNnorm": np.ones((32768, 10), np.float32)})
    assert load_colour_table(good).shape == (32768, 10)
    bad = tmp_path / "bad.mat"
    savemat(bad, {"x": np.ones((5, 10))})
    with pytest.raises(FileFormatError, match="32768-row"):
        load_colour_table(bad)
    junk = tmp_path / "junk.mat"
    junk.write_bytes(b"not a mat file at all")
    with pytest.raises(FileFormatError, match="not a MATLAB"):
        load_colour_table(junk)
    with pytest.raises(MissingFileError):
        load_colour_table(tmp_path / "none.mat")


def test_own_colour_names_against_the_original_table(shared_dir):
    # Origin of the reference: ../shared/models/colornames_tables/CNnorm.mat (van de Weijer et al. 2009 table as
    # normalised by ECO). Our prototype construction is independent; a linear map from our 11 memberships explains
    # most of the reference's variance on the pixels of a real sequence (measured R^2 0.8; see docs/benchmarks_eco.md).
    from scipy.io import loadmat

    from rgbt_toolkit.io.images import read_image

    ref = loadmat(shared_dir / "models/colornames_tables/CNnorm.mat")["CNnorm"].astype(np.float64)
    img = read_image(shared_dir / "data/tracking/sequences/OTB_Crossing/img/0001.jpg")
    idx = table_index(img).ravel()
    ours = np.c_[own_table()[idx], np.ones(idx.size)]
    coef = np.linalg.lstsq(ours, ref[idx], rcond=None)[0]
    resid = ref[idx] - ours @ coef
    r2 = 1 - (resid**2).sum() / ((ref[idx] - ref[idx].mean(0)) ** 2).sum()
    assert r2 > 0.6
    # and the loader reads the user's table in that format
    assert ColourNames(table=load_colour_table(shared_dir / "models/colornames_tables/CNnorm.mat")).blocks[0].dim == 10


def test_intensity_channels():
    p = _patches(colour=False)
    f = Intensity(bins=6).compute(p)[0]
    assert f.shape == (2, 12, 12, 7)
    np.testing.assert_allclose(f[..., 1:].sum(-1), 1.0, atol=1e-5)  # memberships sum to one
    bright = Intensity().compute(np.full((1, 8, 8), 255, np.uint8))[0]
    assert bright[0, 0, 0, 0] == pytest.approx(0.5) and bright[0, 0, 0, -1] == pytest.approx(1.0)


def test_multi_scale_cells_match_single_scale_extraction():
    # reading the cells of a 2% larger scale off a larger base patch equals extracting that patch directly
    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.random((200, 200)).astype(np.float32), (0, 0), 3.0)
    votes_big = img[..., None]
    direct = cells_at_scales(votes_big, 1, 4, 96, np.array([1.0]), 200)
    same = cells_at_scales(votes_big, 1, 4, 96, np.array([1.0, 1.02]), 200)
    np.testing.assert_allclose(same[0], direct[0], rtol=1e-6)  # one scale sums the blur in another order
    assert np.abs(same[1] - same[0]).mean() < 0.2 * np.abs(direct[0] - direct[0].mean()).mean()


def test_bad_patches_are_clear_errors():
    with pytest.raises(InputError, match="multiple of the cell size"):
        FHog().compute(np.zeros((1, 30, 30), np.uint8))
    with pytest.raises(InputError, match="patches must be"):
        FHog().compute(np.zeros((30, 30), np.uint8))


def test_deep_features_shapes():
    pytest.importorskip("torch")
    from rgbt_toolkit.errors import WeightsError
    from rgbt_toolkit.features.deep import DeepFeatures

    try:
        feat = DeepFeatures()
    except WeightsError as exc:  # pragma: no cover - packaged weights missing
        pytest.skip(str(exc))
    assert [b.stride for b in feat.blocks] == [4, 16]
    out = feat.compute(_patches(n=1, size=64))
    assert out[0].shape == (1, 16, 16, feat.blocks[0].dim) and out[1].shape == (1, 4, 4, feat.blocks[1].dim)
    assert all(np.isfinite(o).all() for o in out)
    grey = feat.compute(_patches(n=1, size=64, colour=False))
    assert grey[1].shape == out[1].shape
    with pytest.raises(InputError, match="has no layer"):
        DeepFeatures(layers=("shallow", "nope"))
