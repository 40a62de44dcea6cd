"""Pure ECO maths: Fourier layout, interpolation kernel, regularisation, CG, operators, sample space."""

from __future__ import annotations

import numpy as np
import pytest

from rgbt_toolkit.eco import optimize as opt
from rgbt_toolkit.eco.cg import pcg
from rgbt_toolkit.eco.fourier import (cfft2, evaluate_with_derivatives, full_from_half, half_weights, ip_full,
                                      sample_grid, shift_half)
from rgbt_toolkit.eco.interp import cubic_kernel, cubic_kernel_fourier, interp_coefficients
from rgbt_toolkit.eco.regularization import apply_reg, reg_filter
from rgbt_toolkit.eco.sample_space import SampleSpace


def _rand_half(rng, shape):
    """Random half-layout coefficients of a real function (column kx=0 made Hermitian)."""
    x = rng.standard_normal(shape[:-2] + (shape[-2], 2 * shape[-1] - 1))
    return cfft2(x) / x.shape[-1] ** 2


@pytest.mark.parametrize("n", [7, 8])
def test_cfft2_grid_sampling_reproduces_samples(n):
    # the trigonometric interpolant of n samples passes through them (odd and even n, Nyquist split for even)
    rng = np.random.default_rng(0)
    x = rng.standard_normal((n, n))
    xh = cfft2(x) / n**2
    grid = n + 1 - n % 2
    if n % 2 == 1:
        back = sample_grid(xh, grid)
        # grid index (n-1)/2 is t=0, i.e. sample 0 of x
        np.testing.assert_allclose(np.fft.ifftshift(back), x, atol=1e-10)
    else:
        # evaluate directly at the integer sample positions
        ty, tx = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
        f = evaluate_with_derivatives(np.broadcast_to(xh, (n * n,) + xh.shape), ty.ravel(), tx.ravel(), n)[0]
        np.testing.assert_allclose(f.reshape(n, n), x, atol=1e-10)


def test_full_spectrum_inner_product_matches_full_layout():
    rng = np.random.default_rng(1)
    a, b = _rand_half(rng, (9, 5)), _rand_half(rng, (9, 5))
    full = np.vdot(full_from_half(a), full_from_half(b)).real
    assert ip_full(a, b) == pytest.approx(full, rel=1e-12)
    assert np.sum(half_weights(9, 5)) == 81


def test_shift_moves_the_function():
    rng = np.random.default_rng(2)
    xh = _rand_half(rng, (11, 6))
    t = np.array([1.3]), np.array([-2.2])
    shifted = shift_half(xh, 0.7, -0.4, 11.0)
    f0 = evaluate_with_derivatives(xh[None], t[0] - 0.7, t[1] + 0.4, 11.0)[0]
    f1 = evaluate_with_derivatives(shifted[None], t[0], t[1], 11.0)[0]
    np.testing.assert_allclose(f0, f1, atol=1e-12)


def test_cubic_kernel_and_its_transform():
    assert cubic_kernel(np.array([0.0]))[0] == 1.0
    np.testing.assert_allclose(cubic_kernel(np.array([-2.0, -1.0, 1.0, 2.0, 2.5])), 0.0, atol=1e-15)
    # B(0) is the integral of the kernel (1 for an interpolating cubic); compare B(f) with a dense Riemann sum
    t = np.linspace(-2, 2, 400001)
    dt = t[1] - t[0]
    for f in (0.0, 0.13, 0.37, 0.5):
        direct = np.sum(cubic_kernel(t) * np.cos(2 * np.pi * f * t)) * dt
        assert cubic_kernel_fourier(np.array(f)) == pytest.approx(direct, abs=1e-7)
    assert cubic_kernel_fourier(np.array(0.0)) == pytest.approx(1.0, abs=1e-12)


def test_centered_interpolation_puts_the_middle_sample_at_the_origin():
    # an impulse at the central sample interpolates to a function peaking at t=0
    n = 9
    x = np.zeros((n, n))
    x[n // 2, n // 2] = 1.0
    c = interp_coefficients(n)
    xh = cfft2(x) * (c[:, None] * c[None, n // 2 :])
    ty = np.array([0.0, 0.5, -0.5, 0.0, 0.0])
    tx = np.array([0.0, 0.0, 0.0, 0.5, -0.5])
    f, gy, gx = evaluate_with_derivatives(np.broadcast_to(xh, (5,) + xh.shape), ty, tx, n)[:3]
    assert abs(gy[0]) < 1e-9 and abs(gx[0]) < 1e-9
    assert np.all(f[0] > f[1:]) and f[0] > 0.5
    # without centering the bump sits at the sample's own position, (n-1)/2 away from the origin
    c0 = interp_coefficients(n, centering=False)
    xh0 = cfft2(x) * (c0[:, None] * c0[None, n // 2 :])
    f0 = evaluate_with_derivatives(xh0[None], np.array([0.0]), np.array([0.0]), n)[0]
    assert f0[0] < 0.2 * f[0]


def test_reg_filter_keeps_the_window_minimum_and_is_self_adjoint_psd():
    reg = reg_filter(204, (86.0, 29.0), reg_min=1e-4, reg_edge=1e-2, power=2, sparsity=0.15)
    assert reg.shape[0] % 2 == 1 and np.allclose(reg, reg[::-1, ::-1])
    rng = np.random.default_rng(3)
    a, b = _rand_half(rng, (3, 11, 6)), _rand_half(rng, (3, 11, 6))
    assert ip_full(a, apply_reg(b, reg)) == pytest.approx(ip_full(apply_reg(a, reg), b), rel=1e-9)
    assert ip_full(a, apply_reg(a, reg)) > 0


def _operator_setup(rng, n_samples=4):
    shapes = [(3, 11, 6), (2, 7, 4)]
    Z = [_rand_half(rng, (n_samples,) + s).astype(np.complex128) for s in shapes]
    regs = [np.array([[0, -0.1, 0], [-0.05, 0.4, -0.05], [0, -0.1, 0]])] * 2
    return shapes, Z, regs


def test_filter_operator_is_hermitian_positive_definite():
    rng = np.random.default_rng(4)
    shapes, Z, regs = _operator_setup(rng)
    w = np.array([0.4, 0.3, 0.2, 0.1])
    a = [_rand_half(rng, s) for s in shapes]
    b = [_rand_half(rng, s) for s in shapes]
    lhs = lambda v: opt.filter_lhs(v, Z, w, regs, (11, 6))  # noqa: E731
    assert opt.filter_inner(a, lhs(b)) == pytest.approx(opt.filter_inner(lhs(a), b), rel=1e-9)
    assert opt.filter_inner(a, lhs(a)) > 0


def test_joint_operator_is_the_normal_operator_of_the_linearised_score():
    rng = np.random.default_rng(5)
    shapes = [(3, 11, 6), (2, 7, 4)]
    dims = [5, 4]
    X = [_rand_half(rng, (d,) + s[1:]) for d, s in zip(dims, shapes)]
    P = [rng.standard_normal((d, s[0])) for d, s in zip(dims, shapes)]
    F0 = [_rand_half(rng, s) for s in shapes]
    Z = opt.project(P, X)
    regs = [np.zeros((1, 1))] * 2
    lhs = lambda v: opt.joint_lhs(v, X, Z, F0, regs, (11, 6), 0.0)  # noqa: E731
    v = [_rand_half(rng, s) for s in shapes] + [rng.standard_normal(p.shape) for p in P]
    # J v, computed independently: S(F, P) + S(F0, dP)
    jv = opt.scores(v[:2], Z, (11, 6)) + opt.scores(F0, opt.project(v[2:], X), (11, 6))
    assert opt.joint_inner(v, lhs(v), 2) == pytest.approx(ip_full(jv, jv), rel=1e-9)


def test_pcg_solves_a_small_spd_system():
    rng = np.random.default_rng(6)
    m = rng.standard_normal((20, 20))
    a = m @ m.T + 20 * np.eye(20)
    b = rng.standard_normal(20)
    x, _ = pcg(lambda v: [a @ v[0]], [b], [np.zeros(20)], lambda u, v: float(u[0] @ v[0]), [np.diag(a)], 60)
    np.testing.assert_allclose(x[0], np.linalg.solve(a, b), rtol=1e-8)


def test_sample_space_weights_distances_and_merging():
    rng = np.random.default_rng(7)
    ipw = np.ones(6)
    space = SampleSpace(3, 6, ipw, learning_rate=0.1, min_weight=1e-9, dtype=np.complex128)
    samples = [rng.standard_normal(6) + 1j * rng.standard_normal(6) for _ in range(3)]
    for s in samples:
        space.add(s)
    assert space.count == 3
    np.testing.assert_allclose(space.weights.sum(), 1.0)
    d01 = np.sum(np.abs(samples[0] - samples[1]) ** 2)
    assert space.distance[0, 1] == pytest.approx(d01, rel=1e-9)
    # a near-copy of sample 2 is merged into it, the count stays at 3
    info = space.add(samples[2] + 1e-3)
    assert info["merged"] == 2 and space.count == 3
    np.testing.assert_allclose(space.weights.sum(), 1.0)
    # a far-away sample forces the closest existing pair to merge and takes the freed slot
    info = space.add(100 * np.ones(6, complex))
    assert info["new"] is not None and info["merged"] is not None
    np.testing.assert_allclose(space.samples[info["new"]], 100)
