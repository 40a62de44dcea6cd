import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.registration.transforms import (
    check_model, corner_error, decompose, is_plausible, overlap_corner_error, parameter_basis, project, similarity,
)


def test_similarity_maps_centre_and_decomposes():
    m = similarity(1.2, np.deg2rad(3.0), (10, 20), (30, 40), shift=(1, -2))
    assert np.allclose(project(m, [[10, 20]]), [[31, 38]])
    parts = decompose(m)
    assert parts["scale"] == pytest.approx(1.2)
    assert parts["rotation_deg"] == pytest.approx(3.0)
    assert parts["anisotropy"] == pytest.approx(1.0)


def test_basis_rows_match_models():
    assert parameter_basis("similarity").shape == (4, 8)
    assert parameter_basis("affine").shape == (6, 8)
    assert parameter_basis("homography").shape == (8, 8)
    with pytest.raises(InputError, match="unknown transform model 'rigid'"):
        check_model("rigid")


def test_corner_errors():
    shift = np.array([[1, 0, 3.0], [0, 1, 4.0], [0, 0, 1]])
    assert corner_error(np.eye(3), np.eye(3), (100, 50)) == 0
    assert corner_error(shift, np.eye(3), (100, 50)) == pytest.approx(5.0)
    assert overlap_corner_error(shift, np.eye(3), (40, 30)) == pytest.approx(5.0)


def test_plausibility_rejects_mirror_and_shear():
    assert is_plausible(np.eye(3), (100, 100))
    assert not is_plausible(np.diag([-1.0, 1.0, 1.0]), (100, 100))
    assert not is_plausible(np.array([[1, 1.5, 0], [0, 1, 0], [0, 0, 1.0]]), (100, 100))
