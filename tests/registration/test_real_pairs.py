"""Real aligned visible/infrared pairs from ../shared, warped by known similarities (skipped without ../shared).

The datasets' own alignment is off by a few pixels on some pairs, so the truth is the known warp composed with the
registration of the unwarped pair (see benchmarks/bench_registration.py --warp similarity; the pair indices below are its draws).
"""

import numpy as np
import pytest

from rgbt_toolkit.io.images import read_image
from rgbt_toolkit.registration import SpatialSettings, estimate_transform, overlap_corner_error
from rgbt_toolkit.registration.synthetic import random_similarity, warp_and_crop

PAIRS = [
    ("roadscene", "vi", "ir", "FLIR_00060.jpg"),
    ("roadscene", "vi", "ir", "FLIR_01274.jpg"),
    ("tno", "vi", "ir", "14.png"),
    ("vifb", "VI", "IR", "carWhite.jpg"),
]


# A similarity is recovered within 2 px; a free homography also fits the scene's parallax, which depends on the
# part of the view the crop keeps (one RoadScene pair: 2.95 px), hence its looser bound (docs/registration.md).
BOUND_PX = {"similarity": 2.0, "homography": 4.0}


@pytest.mark.shared
@pytest.mark.parametrize("model", list(BOUND_PX))
@pytest.mark.parametrize("dataset, vis, ir, name", PAIRS)
def test_recovers_warp_of_real_pair(shared_dir, dataset, vis, ir, name, model):
    root = shared_dir / "data" / "fusion" / dataset
    rgb, infrared = read_image(root / vis / name), read_image(root / ir / name)
    rng = np.random.default_rng(sum(map(ord, name)))
    thermal, truth = warp_and_crop(infrared, random_similarity(rng, (infrared.shape[1], infrared.shape[0])))
    settings = SpatialSettings(model=model)
    base = estimate_transform([rgb], [infrared], settings)
    result = estimate_transform([rgb], [thermal], settings)
    error = overlap_corner_error(result.matrix, truth @ base.matrix, (thermal.shape[1], thermal.shape[0]))
    assert error < BOUND_PX[model], f"{dataset}/{name} ({model}): {error:.2f} px"


# Pairs the 2-degree / 192-px coarse search and a 160-px first refinement level lost (warped by the benchmark's own
# seeded similarity, as drawn with --limit 110): VIFB nightCar's roll fell between two grid angles, and FLIR_07428's right coarse peak was then
# refined at a level too coarse to hold it.
REGRESSIONS = [("vifb", "VI", "IR", "nightCar.jpg", 13), ("roadscene", "vi", "ir", "FLIR_07428.jpg", 74)]


@pytest.mark.shared
@pytest.mark.parametrize("dataset, vis, ir, name, index", REGRESSIONS)
def test_pairs_the_coarser_search_lost(shared_dir, dataset, vis, ir, name, index):
    root = shared_dir / "data" / "fusion" / dataset
    rgb, infrared = read_image(root / vis / name), read_image(root / ir / name)
    rng = np.random.default_rng([0, index])  # the warp bench_registration.py --warp similarity --limit 110 draws for this pair
    thermal, truth = warp_and_crop(infrared, random_similarity(rng, (infrared.shape[1], infrared.shape[0])))
    settings = SpatialSettings(model="similarity")
    base = estimate_transform([rgb], [infrared], settings)
    result = estimate_transform([rgb], [thermal], settings)
    error = overlap_corner_error(result.matrix, truth @ base.matrix, (thermal.shape[1], thermal.shape[0]))
    assert error < 2.0, f"{dataset}/{name}: {error:.2f} px"


@pytest.mark.shared
def test_mismatched_real_pair_is_rejected(shared_dir):
    from rgbt_toolkit.errors import RegistrationError

    root = shared_dir / "data" / "fusion" / "tno"
    rgb, other = read_image(root / "vi" / "14.png"), read_image(root / "ir" / "20.png")
    with pytest.raises(RegistrationError, match="registration failed"):
        estimate_transform([rgb], [other])


def _mismatch(root, rgb_name, partner_name, index):
    """RGB image of pair ``index`` and the partner's infrared image warped as bench_registration.py's first
    negative for that pair draws it (after the pair's own warp)."""
    rgb, own, other = (read_image(root / sub / name) for sub, name in
                       (("vi", rgb_name), ("ir", rgb_name), ("ir", partner_name)))
    rng = np.random.default_rng([0, index])
    random_similarity(rng, (own.shape[1], own.shape[0]))
    return rgb, warp_and_crop(other, random_similarity(rng, (other.shape[1], other.shape[0])))[0]


@pytest.mark.shared
def test_mismatch_with_shared_street_furniture_is_rejected(shared_dir):
    """RoadScene FLIR_04975 (a van, poles) against FLIR_08749's warped thermal image (a street, poles): correlation
    0.26, coarse z 5.3-5.4. The older rule (correlation >= 0.25) accepted it; evidence ~1.4 < 1.5 does not."""
    from rgbt_toolkit.errors import RegistrationError

    rgb, thermal = _mismatch(shared_dir / "data" / "fusion" / "roadscene", "FLIR_04975.jpg", "FLIR_08749.jpg", 61)
    with pytest.raises(RegistrationError, match=r"evidence 1\.[34]\d"):
        estimate_transform([rgb], [thermal], SpatialSettings(model="similarity"))


@pytest.mark.shared
def test_weak_but_consistent_night_pair_is_accepted_and_right(shared_dir):
    """TNO 40 (smoke, night): evidence 0.6-0.7, below the 1.5 a clear match needs, but 5-6 of 16 blocks of the view
    peak at the estimate on their own (no mismatched pair of 568 had more than 3), and the warp is recovered."""
    root = shared_dir / "data" / "fusion" / "tno"
    rgb, infrared = read_image(root / "vi" / "40.png"), read_image(root / "ir" / "40.png")
    rng = np.random.default_rng([0, 39])  # the draws of bench_registration.py --warp similarity for this pair
    thermal, truth = warp_and_crop(infrared, random_similarity(rng, (infrared.shape[1], infrared.shape[0])))
    settings = SpatialSettings(model="similarity")
    base = estimate_transform([rgb], [infrared], settings)
    result = estimate_transform([rgb], [thermal], settings)
    assert result.details["evidence"] < settings.min_evidence
    assert result.details["blocks_agreeing"] >= settings.min_agreeing_blocks
    error = overlap_corner_error(result.matrix, truth @ base.matrix, (thermal.shape[1], thermal.shape[0]))
    assert error < 2.0, f"tno/40.png: {error:.2f} px"


@pytest.mark.shared
def test_weak_mismatch_with_a_few_agreeing_blocks_is_rejected(shared_dir):
    """RoadScene FLIR_07360 against FLIR_04071's warped thermal image: the weak-evidence mismatch with the most
    agreeing blocks in the benchmark (evidence ~0.9, 2-3 blocks) must stay rejected."""
    from rgbt_toolkit.errors import RegistrationError

    rgb, thermal = _mismatch(shared_dir / "data" / "fusion" / "roadscene", "FLIR_07360.jpg", "FLIR_04071.jpg", 143)
    with pytest.raises(RegistrationError, match=r"evidence 0\.\d+, [0-4] of \d+ blocks agree"):
        estimate_transform([rgb], [thermal], SpatialSettings(model="similarity"))


def _warped_roadscene(root, name, index):
    """RGB image, unwarped infrared image, and the warped one with its truth as bench_registration.py draws them."""
    rgb, infrared = read_image(root / "vi" / name), read_image(root / "ir" / name)
    rng = np.random.default_rng([0, index])
    return rgb, infrared, warp_and_crop(infrared, random_similarity(rng, (infrared.shape[1], infrared.shape[0])))


def _relative_error(rgb, infrared, thermal, truth, result, settings):
    base = estimate_transform([rgb], [infrared], settings)
    return overlap_corner_error(result.matrix, truth @ base.matrix, (thermal.shape[1], thermal.shape[0]))


@pytest.mark.shared
def test_nearly_strong_evidence_with_three_agreeing_blocks_is_accepted(shared_dir):
    """RoadScene FLIR_06099 (night street): evidence ~1.4, under the 1.5 of a clear match, with 4 blocks agreeing
    (no mismatch of 568 with 3 or more blocks reached 0.92)."""
    rgb, infrared, (thermal, truth) = _warped_roadscene(shared_dir / "data" / "fusion" / "roadscene",
                                                        "FLIR_06099.jpg", 93)
    settings = SpatialSettings(model="similarity")
    result = estimate_transform([rgb], [thermal], settings)
    assert settings.min_fair_evidence <= result.details["evidence"] < settings.min_evidence
    assert settings.min_fair_blocks <= result.details["blocks_agreeing"] < settings.min_agreeing_blocks
    error = _relative_error(rgb, infrared, thermal, truth, result, settings)
    assert error < 2.0, f"FLIR_06099: {error:.2f} px"


@pytest.mark.shared
def test_night_pair_refused_plain_is_found_with_equalised_contrast(shared_dir):
    """RoadScene FLIR_06997 (night, street lamps): the plain orientation fields give a wrong answer, rightly refused;
    the second look with locally equalised copies finds the warp, and 5+ blocks agree with it."""
    from rgbt_toolkit.errors import RegistrationError

    rgb, infrared, (thermal, truth) = _warped_roadscene(shared_dir / "data" / "fusion" / "roadscene",
                                                        "FLIR_06997.jpg", 128)
    settings = SpatialSettings(model="similarity")
    with pytest.raises(RegistrationError, match="registration failed"):
        estimate_transform([rgb], [thermal], SpatialSettings(model="similarity", equalise=False))
    result = estimate_transform([rgb], [thermal], settings)
    assert result.details["second_look"] is True
    assert result.details["blocks_agreeing"] >= settings.second_look_blocks
    error = _relative_error(rgb, infrared, thermal, truth, result, settings)
    assert error < 2.0, f"FLIR_06997: {error:.2f} px"


@pytest.mark.shared
def test_closest_mismatch_on_second_look_is_still_rejected(shared_dir):
    """TNO 32 against TNO 11's warped infrared image: refused for weak evidence (0.9), it gets the second look, where
    4 blocks agreed at evidence 0.95 - the benchmark's closest mismatch to the second look's rule (1.0 and 5 blocks)
    without the denser last refinement level (docs/decisions.md, D25); with it, 2 blocks at 0.85."""
    from rgbt_toolkit.errors import RegistrationError

    rgb, thermal = _mismatch(shared_dir / "data" / "fusion" / "tno", "32.png", "11.png", 31)
    with pytest.raises(RegistrationError, match="registration failed") as refused:
        estimate_transform([rgb], [thermal], SpatialSettings(model="similarity"))
    look = refused.value.details["second_look"]  # the second look ran and came close
    assert look["evidence"] > 0.8 and look["blocks_agreeing"] >= 2


# Pairs whose estimate depended on where a sparse sample grid fell on the edges: with every 4th pixel of the
# full-size level (fields smoothed by 1 px) TNO 04 and VIFB manCall / manwithbag were 2.4 / 2.1 / 2.7 px off; the
# last level now samples twice as densely in each direction (SpatialSettings.final_density)
DENSE_LAST_LEVEL = [("tno", "vi", "ir", "04.png", 3), ("vifb", "VI", "IR", "manCall.jpg", 8),
                    ("vifb", "VI", "IR", "manwithbag.jpg", 12)]


@pytest.mark.shared
@pytest.mark.parametrize("dataset, vis, ir, name, index", DENSE_LAST_LEVEL)
def test_pairs_the_sparse_last_level_missed(shared_dir, dataset, vis, ir, name, index):
    root = shared_dir / "data" / "fusion" / dataset
    error = _benchmark_error(read_image(root / vis / name), read_image(root / ir / name), index)
    assert error < 2.0, f"{dataset}/{name}: {error:.2f} px"


def _benchmark_error(rgb, infrared, index):
    """Relative error (px) of the similarity estimate on the warp bench_registration.py draws for pair ``index``."""
    rng = np.random.default_rng([0, index])
    thermal, truth = warp_and_crop(infrared, random_similarity(rng, (infrared.shape[1], infrared.shape[0])))
    settings = SpatialSettings(model="similarity")
    result = estimate_transform([rgb], [thermal], settings)
    return _relative_error(rgb, infrared, thermal, truth, result, settings)


# TNO 09 and 10's infrared images carry black bars (the dataset's own warp): their straight edge, which the visible
# image does not have, drew the warped pairs' estimates 4.9 / 5.3 px off the unwarped ones until orientation fields
# ignored a no-data fill at the frame edge (features.fill_mask)
FILLED_EDGES = [("09.png", 8), ("10.png", 9)]


@pytest.mark.shared
@pytest.mark.parametrize("name, index", FILLED_EDGES)
def test_pairs_whose_infrared_frame_has_a_black_fill(shared_dir, name, index):
    from rgbt_toolkit.registration.features import fill_mask, to_grey

    root = shared_dir / "data" / "fusion" / "tno"
    rgb, infrared = read_image(root / "vi" / name), read_image(root / "ir" / name)
    fill = fill_mask(to_grey(infrared))
    assert fill is not None and 0.05 < fill.mean() < 0.08  # two bars along the frame edge
    error = _benchmark_error(rgb, infrared, index)
    assert error < 2.0, f"tno/{name}: {error:.2f} px"


@pytest.mark.shared
def test_mismatch_with_strong_evidence_but_a_blunt_peak_is_refused(shared_dir):
    """TNO 33's visible frame against TNO 05's infrared frame warped by a similarity (the full benchmark's one accepted
    mismatch, 3 Dec 2026): evidence 1.60 passes the clear-match bar, but the peak is blunt (ratio 1.10) and no block
    of the view agrees, so it is refused; TNO 33's own warped pair is still accepted."""
    from rgbt_toolkit.errors import RegistrationError

    root = shared_dir / "data" / "fusion" / "tno"
    rgb, other = read_image(root / "vi" / "33.png"), read_image(root / "ir" / "05.png")
    rng = np.random.default_rng([7, 32])
    thermal, _ = warp_and_crop(other, random_similarity(rng, (other.shape[1], other.shape[0])))
    with pytest.raises(RegistrationError, match="0 of 8 blocks agree") as refused:
        estimate_transform([rgb], [thermal], SpatialSettings())
    assert refused.value.details["evidence"] >= SpatialSettings().min_evidence
    own = read_image(root / "ir" / "33.png")
    thermal, truth = warp_and_crop(own, random_similarity(np.random.default_rng(3), (own.shape[1], own.shape[0])))
    result = estimate_transform([rgb], [thermal], SpatialSettings())
    assert result.peak_ratio >= 1.3 or result.details["blocks_agreeing"] >= 1


STABLE = [("tno", "vi", "ir", "18.png"), ("msrs", "vi", "ir", "00036N.png"), ("roadscene", "vi", "ir", "FLIR_05857.jpg")]


@pytest.mark.shared
@pytest.mark.parametrize("dataset, vis, ir, name", STABLE)
def test_real_fit_does_not_move_when_a_border_is_cut_off(shared_dir, dataset, vis, ir, name):
    # the content is the same but for 4 px at each edge, so the fit must be too: 0.13 / 0.65 / 0.36 px measured
    # (0.50 for the last with numpy's OpenBLAS on its AVX-512 kernels; 0.06 / 0.31 / 0.20 with D46's frozen weak
    # directions, which rig warps of real pairs pay for: D53); the bound is half the benchmarks' 2 px per 640 px
    root = shared_dir / "data" / "fusion" / dataset
    rgb, infrared = read_image(root / vis / name), read_image(root / ir / name)
    whole = estimate_transform([rgb], [infrared])
    cut = infrared[4:-4, 4:-4]
    part = estimate_transform([rgb], [cut])
    to_cut = np.array([[1, 0, -4], [0, 1, -4], [0, 0, 1.0]])
    assert overlap_corner_error(part.matrix, to_cut @ whole.matrix, (cut.shape[1], cut.shape[0])) < 1.0
