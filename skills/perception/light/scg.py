"""Scaled conjugate gradient (Moller, Neural Networks 6(4):525-533, 1993).

A conjugate-gradient method without a line search: second-order information
comes from a finite-difference Hessian-vector product along the search
direction, and a Levenberg-Marquardt style scale ``lam`` keeps the effective
curvature positive.  The scale is raised when the quadratic model predicts
the error badly (comparison ratio < 0.25) and lowered when it predicts it
well (> 0.75).  Directions are Polak-Ribiere-like with a restart every N
successful steps (N = number of weights).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np


@dataclass
class ScgResult:
    x: np.ndarray
    f: float
    iterations: int
    evaluations: int
    converged: bool
    history: list[float] = field(default_factory=list)


def scg(f: Callable[[np.ndarray], float], grad: Callable[[np.ndarray], np.ndarray], x0: np.ndarray,
        max_iter: int = 500, sigma0: float = 5e-5, lam0: float = 5e-7, gtol: float = 1e-6,
        ftol: float = 0.0, callback: Callable[[int, np.ndarray, float], bool | None] | None = None
        ) -> ScgResult:
    """Minimise ``f`` from ``x0``.

    Stops after ``max_iter`` iterations, when the gradient norm falls below
    ``gtol``, when a successful step lowers ``f`` by less than ``ftol``, or
    when ``callback(k, x, fx)`` returns True.
    """
    w = np.asarray(x0, dtype=np.float64).copy()
    n = w.size
    fw = float(f(w))
    r = -grad(w)
    p = r.copy()
    lam, lam_bar = lam0, 0.0
    success = True
    evals = 2
    history = [fw]
    delta = 0.0
    converged = False
    k = 0
    for k in range(1, max_iter + 1):
        p2 = float(p @ p)
        if p2 == 0.0:
            converged = True
            break
        if success:
            sigma = sigma0 / np.sqrt(p2)
            s = (grad(w + sigma * p) + r) / sigma      # (E'(w + sigma p) - E'(w)) / sigma
            evals += 1
            delta = float(p @ s)
        # scale the curvature estimate
        delta += (lam - lam_bar) * p2
        if delta <= 0.0:                               # make the Hessian positive definite
            lam_bar = 2.0 * (lam - delta / p2)
            delta = -delta + lam * p2
            lam = lam_bar
        mu = float(p @ r)
        alpha = mu / delta
        w_new = w + alpha * p
        f_new = float(f(w_new))
        evals += 1
        comparison = 2.0 * delta * (fw - f_new) / (mu * mu) if mu != 0.0 else -1.0
        if comparison >= 0.0:                          # a successful reduction
            improvement = fw - f_new
            w, fw = w_new, f_new
            r_old = r
            r = -grad(w)
            evals += 1
            lam_bar = 0.0
            success = True
            history.append(fw)
            if k % n == 0:
                p = r.copy()
            else:
                beta = (float(r @ r) - float(r @ r_old)) / mu
                p = r + beta * p
            if comparison >= 0.75:
                lam *= 0.25
            if np.sqrt(float(r @ r)) < gtol or (ftol > 0.0 and improvement < ftol):
                converged = True
                if comparison < 0.25:
                    lam += delta * (1.0 - comparison) / p2
                break
        else:
            lam_bar = lam
            success = False
        if comparison < 0.25:
            lam += delta * (1.0 - comparison) / p2
        if callback is not None and callback(k, w, fw):
            break
    return ScgResult(w, fw, k, evals, converged, history)
