"""Learning the filter: the first-frame factorised problem and the sparse updates (ECO Sec. 3.1, 4.3)."""

from __future__ import annotations

from functools import partial

import numpy as np

from rgbt_toolkit.eco import optimize as opt
from rgbt_toolkit.eco.cg import CGState, pcg
from rgbt_toolkit.eco.params import EcoParams


def train_first_frame(X: list, P: list, blocks: list, out_shape: tuple[int, int], params: EcoParams):
    """Jointly learn filter and projection on the first sample by Gauss-Newton, each step solved by CG.

    Parameters
    ----------
    X : list of (D, Ny, Nxh) complex arrays
        Interpolated, unprojected first-frame sample per block.
    P : list of (D, C) arrays
        Initial projections (PCA).

    Returns
    -------
    (F, P) : filters per block (C, Ny, Nxh) and the learned projections.
    """
    n = len(X)
    labels = [b.label for b in blocks]
    regs = [b.reg for b in blocks]
    F = [np.zeros((p.shape[1],) + x.shape[-2:], np.complex64) for p, x in zip(P, X)]
    P = [p.astype(np.float32) for p in P]
    # preconditioner of the projection part (ECO: proj_energy)
    y_energy = sum(float(np.sum(np.abs(b.label) ** 2)) for b in blocks[:1])
    total_dim = sum(x.shape[0] for x in X)
    cg_per_gn = max(1, params.init_cg_iter // params.init_gn_iter)
    for _ in range(params.init_gn_iter):
        Z = opt.project(P, X)
        energy = [np.abs(z) ** 2 for z in Z]
        m_f = opt.preconditioner(energy, [b.reg_energy for b in blocks], params.precond_data, params.precond_reg)
        m_p = [np.full(p.shape, params.precond_proj * (2 * y_energy / total_dim + params.projection_reg), np.float32)
               for p in P]
        apply_a = partial(opt.joint_lhs, X=X, Z=Z, F0=F, regs=regs, out_shape=out_shape,
                          proj_reg=params.projection_reg)
        b = opt.joint_rhs(X, Z, F, P, labels, params.projection_reg)
        x0 = F + [np.zeros_like(p) for p in P]
        sol, _ = pcg(apply_a, b, x0, partial(opt.joint_inner, n_blocks=n), m_f + m_p, cg_per_gn)
        F = [f.astype(np.complex64) for f in sol[:n]]
        P = [(p + dp).astype(np.float32) for p, dp in zip(P, sol[n:])]
    return F, P


def train_filter(F: list, samples: list, weights: np.ndarray, sample_energy: list, blocks: list,
                 out_shape: tuple[int, int], params: EcoParams, state: CGState | None):
    """A few warm-started CG iterations on the filter over the GMM components (projection fixed)."""
    regs = [b.reg for b in blocks]
    labels = [b.label for b in blocks]
    rhs = opt.filter_rhs(samples, weights, labels)
    m_f = opt.preconditioner(sample_energy, [b.reg_energy for b in blocks], params.precond_data, params.precond_reg)
    apply_a = partial(opt.filter_lhs, Z=samples, weights=weights, regs=regs, out_shape=out_shape)
    forget = (1 - params.learning_rate) ** params.cg_forgetting_rate
    F, state = pcg(apply_a, rhs, F, opt.filter_inner, m_f, params.cg_iter, state=state, forget_factor=forget)
    return [f.astype(np.complex64) for f in F], state
