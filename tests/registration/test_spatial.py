"""Spatial registration on procedural pairs with known transforms, and the failures it must report."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError, RegistrationError
from rgbt_toolkit.registration import SpatialSettings, corner_error, estimate_transform
from rgbt_toolkit.registration.synthetic import procedural_scene
from rgbt_toolkit.registration.transforms import decompose


def test_recovers_known_homographies(make_pair):
    errors = []
    for seed in range(3):
        visible, thermal, truth = make_pair(seed)
        result = estimate_transform([visible], [thermal])
        errors.append(corner_error(result.matrix, truth, (visible.shape[1], visible.shape[0])))
        assert result.quality > 0.4 and result.overlap > 0.9
        assert result.thermal_size == (thermal.shape[1], thermal.shape[0])
    assert np.median(errors) < 1.0, errors
    assert max(errors) < 2.0, errors


@pytest.mark.parametrize("model", ["similarity", "affine"])
def test_restricted_models_keep_their_form(make_pair, model):
    visible, thermal, truth = make_pair(1, perspective=0.0)
    result = estimate_transform([visible], [thermal], SpatialSettings(model=model))
    assert np.allclose(result.matrix[2], [0, 0, 1])
    if model == "similarity":
        assert decompose(result.matrix)["anisotropy"] == pytest.approx(1.0, abs=1e-6)
    assert corner_error(result.matrix, truth, (visible.shape[1], visible.shape[0])) < 1.5


def test_several_pairs_are_aggregated(make_pair):
    # two frame pairs of one rig: the second thermal frame is nearly blank (lens cap) and must not spoil the estimate
    visible, thermal, truth = make_pair(2)
    capped = np.full_like(thermal, 90)
    result = estimate_transform([visible, visible], [thermal, capped])
    assert result.pairs_used == 1
    assert corner_error(result.matrix, truth, (visible.shape[1], visible.shape[0])) < 1.5


def test_blank_frames_raise(pair):
    visible, thermal, _ = pair
    with pytest.raises(RegistrationError, match="thermal frames are blank"):
        estimate_transform([visible], [np.zeros_like(thermal)])
    with pytest.raises(RegistrationError, match="RGB frames are blank"):
        estimate_transform([np.full_like(visible, 200)], [thermal])


def test_unrelated_views_are_rejected_not_reported():
    # two different scenes: whatever transform fits best must not come back as a result
    for seed in range(3):
        visible, _ = procedural_scene(np.random.default_rng(seed))
        _, thermal = procedural_scene(np.random.default_rng(seed + 50))
        with pytest.raises(RegistrationError, match="registration failed"):
            estimate_transform([visible], [thermal])


def test_views_that_do_not_overlap_are_rejected():
    rng = np.random.default_rng(7)
    visible, thermal = procedural_scene(rng, (640, 240))
    with pytest.raises(RegistrationError, match="registration failed|do not overlap"):
        estimate_transform([visible[:, :320]], [thermal[:, 320:]])


def test_input_checks(pair):
    visible, thermal, _ = pair
    with pytest.raises(InputError, match="got 2 RGB frames but 1 thermal"):
        estimate_transform([visible, visible], [thermal])
    with pytest.raises(InputError, match="RGB frames differ in size"):
        estimate_transform([visible, visible[:-2]], [thermal, thermal])
    with pytest.raises(InputError, match="unknown transform model"):
        estimate_transform([visible], [thermal], SpatialSettings(model="rigid"))


@pytest.mark.parametrize("evidence, agreeing, accepted", [(0.8, 5, True), (0.8, 4, False), (0.4, 12, False),
                                                          (1.6, 0, True)])
def test_weak_evidence_needs_agreeing_blocks(evidence, agreeing, accepted):
    """The acceptance rule alone: evidence >= 1.5, or >= 0.5 with at least 5 blocks agreeing."""
    from rgbt_toolkit.registration.spatial import SpatialResult, _accept

    details = {"evidence": evidence, "similarity_correlation": 0.2, "coarse_z": evidence / 0.2,
               "blocks_agreeing": agreeing, "blocks_textured": 16}
    result = SpatialResult(np.eye(3), "similarity", 0.2, 2.0, 0.9, 1, (320, 240), (320, 240), details)
    if accepted:
        _accept(result, SpatialSettings())
    else:
        with pytest.raises(RegistrationError, match=f"{agreeing} of 16 blocks agree"):
            _accept(result, SpatialSettings())
