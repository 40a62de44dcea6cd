"""The compiled filter arithmetic (eco/_spectra.c) against the numpy expressions it replaces."""

import platform

import numpy as np
import pytest

from rgbt_toolkit._native import load_compiled
from rgbt_toolkit.eco.optimize import channel_products, sample_backprojection
from rgbt_toolkit.eco.regularization import apply_reg, apply_reg_numpy, reg_filter

_spectra = load_compiled("rgbt_toolkit.eco._spectra")


# bit for bit where the kernels mirror numpy's run-time choice of fused multiply-add (x86); elsewhere float32 rounding
EXACT = platform.machine().lower() in ("x86_64", "amd64", "i386", "i686")


def assert_numpys(got, expected):
    if EXACT:
        np.testing.assert_array_equal(got, expected)
    else:  # pragma: no cover - other CPUs
        np.testing.assert_allclose(got, expected, rtol=1e-5, atol=1e-5)


def spectra(rng, *shape, dtype=np.complex64):
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(dtype)


@pytest.mark.parametrize("shape", [(7, 10, 63, 32), (50, 3, 63, 32), (10, 35, 18), (1, 1, 5, 3), (2, 4, 6, 5, 3)])
def test_channel_products_are_numpys_numbers(shape):
    rng = np.random.default_rng(sum(shape))
    z, f = spectra(rng, *shape), spectra(rng, *shape[-3:])
    assert_numpys(channel_products(z, f), (z * f).sum(axis=-3))


@pytest.mark.parametrize("shape", [(50, 10, 63, 32), (7, 3, 63, 32), (1, 31, 35, 18), (3, 1, 1, 1)])
def test_sample_backprojection_is_numpys_numbers(shape):
    rng = np.random.default_rng(sum(shape))
    z, p = spectra(rng, *shape), spectra(rng, shape[0], *shape[2:])
    assert_numpys(sample_backprojection(z, p), (np.conj(z) * p[:, None]).sum(axis=0))


@pytest.mark.parametrize("shape, target, sparsity", [
    ((10, 49, 25), (20.0, 30.0), 0.15),  # hc's fHOG block as `rgbt track` runs it (a 3 x 3 window)
    ((3, 11, 6), (86.0, 29.0), 0.15),
    ((4, 2, 3, 31, 16), (10.0, 40.0), 0.02),  # leading axes, an 11 x 11 window
    ((2, 5, 1), (4.0, 4.0), 0.05),  # a single column: no mirrored columns to add
])
@pytest.mark.parametrize("symmetric", [True, False])
def test_regularisation_is_numpys_numbers(shape, target, sparsity, symmetric):
    rng = np.random.default_rng(sum(shape))
    reg = reg_filter(2 * shape[-2] + 1, target, reg_min=1e-4, reg_edge=1e-2, power=2,
                     sparsity=sparsity).astype(np.float32)
    if not symmetric:  # the loop must follow numpy's taps, not lean on the window's symmetry
        reg = reg + 0.01 * rng.standard_normal(reg.shape).astype(np.float32)
    fh = spectra(rng, *shape)
    assert_numpys(apply_reg(fh, reg), apply_reg_numpy(fh, reg))
    assert_numpys(apply_reg(fh[..., ::-1, :], reg), apply_reg_numpy(fh[..., ::-1, :], reg))  # a view


def test_views_and_other_dtypes_give_the_same_results():
    rng = np.random.default_rng(3)
    z = spectra(rng, 6, 4, 9, 10)[:, :, 1:8, :5]  # a crop: not contiguous
    f = spectra(rng, 4, 7, 5)
    assert_numpys(channel_products(z, f), (z * f).sum(axis=-3))
    z128, p128 = spectra(rng, 5, 2, 4, 3, dtype=np.complex128), spectra(rng, 5, 4, 3, dtype=np.complex128)
    np.testing.assert_allclose(sample_backprojection(z128, p128), (np.conj(z128) * p128[:, None]).sum(axis=0))


def test_buffers_that_do_not_fit_their_shapes_are_refused():
    z, f = np.zeros((2, 3, 4), np.complex64), np.zeros((3, 4), np.complex64)
    with pytest.raises(ValueError, match="out: buffer has"):
        _spectra.channel_products(z, f, 2, 3, 4, np.empty(7, np.complex64))
    with pytest.raises(ValueError, match="z: buffer has"):
        _spectra.sample_backprojection(z, np.zeros((2, 4), np.complex64), 3, 3, 4, np.empty((3, 4), np.complex64))
    with pytest.raises(ValueError, match="no samples"):
        _spectra.sample_backprojection(z[:0], np.zeros((0, 4), np.complex64), 0, 3, 4, np.empty((3, 4), np.complex64))
    with pytest.raises(ValueError, match="regularisation: k has"):
        _spectra.regularisation(f, np.zeros((3, 2), np.float32), 1, 3, 4, 3, 3, np.empty((3, 4), np.complex64))
