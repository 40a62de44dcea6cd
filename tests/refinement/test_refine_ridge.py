"""Closed-form ridge: agrees with the primal solution and with brute-force leave-one-out."""

import numpy as np
import pytest

from rgbt_toolkit.errors import InputError
from rgbt_toolkit.refinement.ridge import fit_ridge


def _problem(n=60, d=8, k=2, noise=0.05, seed=0):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, d)) * rng.uniform(0.5, 3, d) + rng.normal(size=d)
    w = rng.normal(size=(d, k))
    y = x @ w + 0.3 + noise * rng.normal(size=(n, k))
    return x, y


def test_matches_primal_ridge():
    x, y = _problem()
    m = fit_ridge(x, y, fixed_alpha=0.1)
    xs = (x - x.mean(0)) / x.std(0)
    gram_unit = np.linalg.eigvalsh(xs @ xs.T).clip(0).mean()
    w = np.linalg.solve(xs.T @ xs + 0.1 * gram_unit * np.eye(x.shape[1]), xs.T @ (y - y.mean(0)))
    np.testing.assert_allclose(m.weights, w, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(m.predict(x[:3]), xs[:3] @ w + y.mean(0), rtol=1e-8)


def test_leave_one_out_matches_refitting():
    x, y = _problem(n=25, d=5)
    m = fit_ridge(x, y, fixed_alpha=0.3)
    # the hat-matrix identity is exact for ridge on the once-centred data (intercept fixed at the full mean)
    xs = (x - m.mean) / m.scale
    yc = y - y.mean(0)
    lam_abs = 0.3 * np.linalg.eigvalsh(xs @ xs.T).clip(0).mean()
    errs = []
    for i in range(len(x)):
        keep = np.arange(len(x)) != i
        w = np.linalg.solve(xs[keep].T @ xs[keep] + lam_abs * np.eye(5), xs[keep].T @ yc[keep])
        errs.append(xs[i] @ w - yc[i])
    assert m.loo_error == pytest.approx(np.mean(np.square(errs)), rel=1e-8)
    assert m.loo_error < 0.1 * m.identity_error


def test_recovers_a_linear_map():
    x, y = _problem(n=300, noise=0.0)
    m = fit_ridge(x, y, alphas=(1e-6,))
    np.testing.assert_allclose(m.predict(x), y, atol=1e-3)


def test_shape_errors():
    with pytest.raises(InputError, match="same n"):
        fit_ridge(np.zeros((5, 3)), np.zeros((4, 2)))
