"""Preconditioned conjugate gradient with warm state, as ECO uses it (``pcg_ccot``).

Vectors are lists of numpy arrays (one per feature block, plus projection matrices in the joint first-frame problem).
The inner product is passed in, because the filter coefficients live in the half Fourier layout whose inner product
counts most coefficients twice. Polak-Ribiere updates and carrying the search direction from one call to the next
(scaled by a forgetting factor) are what make 5 iterations every 5th frame enough (ECO, Sec. 4.3).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

Vec = list  # list[np.ndarray]
Operator = Callable[[Vec], Vec]
InnerProduct = Callable[[Vec, Vec], float]


@dataclass
class CGState:
    """What one call leaves for the next: search direction, its ``rho`` and the previous residual."""

    p: Vec | None = None
    rho: float | None = None
    r_prev: Vec | None = None


def axpy(a: float, x: Sequence[np.ndarray], y: Sequence[np.ndarray]) -> Vec:
    """``a * x + y`` elementwise over lists."""
    return [a * xi + yi for xi, yi in zip(x, y)]


def pcg(apply_a: Operator, b: Vec, x0: Vec, inner: InnerProduct, precond: Vec | None, iterations: int, *,
        state: CGState | None = None, forget_factor: float = 1.0, polak_ribiere: bool = True) -> tuple[Vec, CGState]:
    """Run ``iterations`` steps of preconditioned CG on ``A x = b`` from ``x0``.

    Parameters
    ----------
    apply_a : callable
        The (Hermitian positive definite) operator.
    b, x0 : list of arrays
        Right-hand side and starting point.
    inner : callable
        Real inner product of two vectors.
    precond : list of arrays, optional
        Diagonal preconditioner ``M`` (the step uses ``M^-1 r``).
    state : CGState, optional
        State of the previous call; its direction is reused, with ``rho`` divided by ``forget_factor`` (< 1), which
        shrinks the weight of the old direction (ECO's ``CG_forgetting_rate``).

    Returns
    -------
    (x, state)
    """
    x = [xi.copy() for xi in x0]
    r = axpy(-1.0, apply_a(x), b)
    p = None if state is None or state.p is None else state.p
    rho = None if p is None else state.rho / forget_factor
    r_prev = None if state is None else state.r_prev
    for _ in range(iterations):
        z = r if precond is None else [ri / mi for ri, mi in zip(r, precond)]
        rho_old = rho
        rho = inner(r, z)
        if not np.isfinite(rho) or rho == 0.0:
            break
        if p is None or rho_old is None:
            p = z
        else:
            if polak_ribiere and r_prev is not None:
                beta = (rho - inner(r_prev, z)) / rho_old
            else:
                beta = rho / rho_old
            beta = max(0.0, beta) if np.isfinite(beta) else 0.0
            p = axpy(beta, p, z)
        q = apply_a(p)
        pq = inner(p, q)
        if not np.isfinite(pq) or pq <= 0:
            break
        alpha = rho / pq
        x = axpy(alpha, p, x)
        if polak_ribiere:
            r_prev = r
        r = axpy(-alpha, q, r)
    return x, CGState(p=p, rho=rho, r_prev=r_prev)
