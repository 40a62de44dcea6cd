"""PSR and MAX-PSR (paper Eq. 4-5)."""

import numpy as np
import pytest
import torch

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.motion.quality import ideal_max_psr, max_psr, psr


def test_hand_computed_map():
    r = np.array([[0.0, 0.0], [0.0, 4.0]])  # max 4, mean 1, var 3, std sqrt(3)
    assert psr(r) == pytest.approx(1.0)
    assert psr(r, "std") == pytest.approx(3.0 / np.sqrt(3.0))
    assert max_psr(r) == pytest.approx(4.0)
    assert max_psr(r, "std") == pytest.approx(4.0 * np.sqrt(3.0))


def test_variance_form_is_amplitude_free_std_form_is_not():
    rng = np.random.default_rng(0)
    r = rng.random((31, 31)) * 0.1
    r[15, 15] = 1.0
    assert max_psr(7.0 * r) == pytest.approx(max_psr(r))
    assert max_psr(7.0 * r, "std") == pytest.approx(7.0 * max_psr(r, "std"))


def test_sharper_peak_is_more_reliable():
    assert ideal_max_psr((63, 63), 1.0) > ideal_max_psr((63, 63), 3.0)


def test_ideal_gaussian_value():
    # for a Gaussian far from the edges, q = MN / (pi sigma^2) (integrals of the peak and its square)
    assert ideal_max_psr((201, 201), 4.0) == pytest.approx(201 * 201 / (np.pi * 16.0), rel=0.01)


def test_torch_input_and_stacked_scales():
    r = np.random.default_rng(1).random((5, 9, 9))
    assert max_psr(torch.from_numpy(r)) == pytest.approx(max_psr(r))


def test_constant_map_and_errors():
    assert psr(np.ones((4, 4))) == 0.0
    with pytest.raises(InputError, match="PSR form"):
        psr(np.ones((4, 4)), "mad")
    with pytest.raises(InputError, match="finite"):
        max_psr(np.array([[np.nan, 1.0]]))
