"""Compiled per-sample steps of the recursive estimators (private module).

The bundle method of Section 3 is split around its QP: `bundle_prepare`
evaluates f(k, .) and the Clarke subgradients at the current estimate
and the stored trial points (eqs. (3.2)-(3.3)) and the locality measures
beta_j; `direction_weights` solves the dual of (3.4) with piqp, called
in object mode; `bundle_finish` forms t and phi (eqs. (3.5)-(3.6)), runs
the line search (3.8) with the step classification of Step 3 and finds
the trial point of (3.10) for short and null steps. `bundle_run` loops
over a block of samples: it calls the three, keeps the bundle's trial
points and their distances s_j, and stores the new estimate's internal
signals, in one compiled call that leaves compiled code only for piqp.
"""

import contextlib

import numba
import numpy as np

from ._predictor import (window_predict, store_state, oe_steps,
                         stable_and_finite, _idx)
from ._qp import simplex_solve, QPError
from .._checks import warn, IdentificationWarning

__all__ = []

LONG, SHORT, NULL, STOP, SKIP = 0, 1, 2, 3, 4
#: Step kind of the gradient method: an update at a nonsmooth sample, taken
#: with the Clarke subgradient of the zone eq. (2.2) selects.
SUBGRADIENT = 9


@numba.njit(cache=True)
def project(theta, o, m_min):
    """Keep theta in the model's domain: m1, m2 >= m_min, D1, D2 >= 0."""
    im = _idx(o)[1]
    theta[im] = max(theta[im], m_min)
    theta[im + 1] = max(theta[im + 1], m_min)
    theta[im + 2] = max(theta[im + 2], 0.0)
    theta[im + 3] = max(theta[im + 3], 0.0)


@numba.njit(cache=True)
def _cost(theta, o, u, ystar, y, xs, vs, zs, k, grad):
    yhat, _ = window_predict(theta, o, u, ystar, xs, vs, zs, k, grad)
    e = y[k] - yhat
    return 0.5 * e * e, e


@numba.njit(cache=True)
def bundle_prepare(theta, trials, ntrial, s, o, u, ystar, y, xs, vs, zs, k,
                   gamma, H, beta, grad):
    """Subgradients h_j = -e_j w_j and locality measures of the bundle.

    Row 0 is the current estimate (beta = 0); rows 1.. the stored trial
    points that differ from it. Returns (f0, e0, n) with n the bundle
    size.
    """
    f0, e0 = _cost(theta, o, u, ystar, y, xs, vs, zs, k, grad)
    p = theta.size
    for r in range(p):
        H[0, r] = -e0 * grad[r]
    beta[0] = 0.0
    n = 1
    for j in range(ntrial):
        dist2 = 0.0
        for r in range(p):
            dist2 += (trials[j, r] - theta[r]) ** 2
        if dist2 == 0.0:
            continue
        fj, ej = _cost(trials[j], o, u, ystar, y, xs, vs, zs, k, grad)
        alpha = f0 - fj
        for r in range(p):
            H[n, r] = -ej * grad[r]
            alpha -= H[n, r] * (theta[r] - trials[j, r])
        beta[n] = max(abs(alpha), gamma * s[j] * s[j])
        n += 1
    return f0, e0, n


@numba.njit(cache=True)
def bundle_finish(theta, lam, H, beta, n, f0, e0, o, u, ystar, y, xs, vs,
                  zs, ys, k, eta0, eta_max, rho, n_ls, q, q_star, gamma,
                  delta, step_bound, m_min, theta_new, trial, t, grad,
                  full_step_test=False):
    """Direction, line search and step classification (Steps 2-3).

    Writes the new estimate into `theta_new` and the new trial point into
    `trial`. Returns (kind, eta, phi). With `full_step_test`, a step found
    with eta >= eta0 is long only if eq. (3.9), read literally, holds:
    f(k, theta + t) < f(k, theta); otherwise the backtracking goes on
    below eta0 (a short or null step).
    """
    p = theta.size
    for r in range(p):
        acc = 0.0
        for j in range(n):
            acc -= lam[j] * H[j, r]
        t[r] = acc
    tt = 0.0
    for r in range(p):
        tt += t[r] * t[r]
    lb = 0.0
    for j in range(n):
        lb += lam[j] * beta[j]
    phi = -tt - lb                                        # eq. (3.6)
    theta_new[:] = theta
    trial[:] = theta
    if phi >= -delta:                                     # Step 2
        return STOP, 0.0, phi
    eta = eta_max
    if step_bound:                                        # eqs. (4.1)-(4.2)
        e2 = e0 * e0
        if e2 == 0.0 or lb > 2.0 * tt:
            eta = 0.0
        else:
            hh = tt / e2                     # ||h_bar||^2, t = e h_bar
            eta = min(eta, (2.0 * tt - lb) / (tt * (1.0 + hh)))
    accepted = False
    f_new = f0
    tried = eta
    if eta > 0.0:
        for _ in range(n_ls + 1):                         # eq. (3.8)
            for r in range(p):
                theta_new[r] = theta[r] + eta * t[r]
            project(theta_new, o, m_min)
            f_try, _ = _cost(theta_new, o, u, ystar, y, xs, vs, zs, k, grad)
            tried = eta
            if f_try <= f0 + q * eta * phi:
                accepted = True
                f_new = f_try
                break
            eta *= rho
    long_ok = True
    if accepted and eta >= eta0 * (1.0 - 1e-12) and full_step_test:
        for r in range(p):                                # eq. (3.9)
            trial[r] = theta[r] + t[r]
        project(trial, o, m_min)
        f_full, _ = _cost(trial, o, u, ystar, y, xs, vs, zs, k, grad)
        if not f_full < f0:
            # no long step: go on backtracking below eta0 (short or null)
            long_ok = False
            accepted = False
            for _ in range(n_ls):
                eta *= rho
                if eta >= eta0 * (1.0 - 1e-12):
                    continue
                for r in range(p):
                    theta_new[r] = theta[r] + eta * t[r]
                project(theta_new, o, m_min)
                f_try, _ = _cost(theta_new, o, u, ystar, y, xs, vs, zs, k,
                                 grad)
                tried = eta
                if f_try <= f0 + q * eta * phi:
                    accepted = True
                    f_new = f_try
                    break
            if not accepted:
                theta_new[:] = theta
    if accepted and long_ok and eta >= eta0 * (1.0 - 1e-12):
        trial[:] = theta_new                              # long step
        return LONG, eta, phi
    if accepted:
        kind = SHORT
        eta_star = eta / rho
    else:
        kind = NULL
        theta_new[:] = theta
        eta = 0.0
        eta_star = tried
    # Trial point theta* = theta + eta* t with eta* > eta satisfying (3.10);
    # if no candidate up to eta_max does, the largest one is used.
    if eta_star <= 0.0:
        eta_star = eta_max * rho ** n_ls
    top = eta_max if eta_max > eta_star else eta_star
    while True:
        for r in range(p):
            trial[r] = theta[r] + eta_star * t[r]
        project(trial, o, m_min)
        f_star, e_star = _cost(trial, o, u, ystar, y, xs, vs, zs, k, grad)
        alpha = f_new - f_star
        ht = 0.0
        dist2 = 0.0
        for r in range(p):
            h = -e_star * grad[r]
            alpha -= h * (theta_new[r] - trial[r])
            ht += h * t[r]
            dist2 += (theta_new[r] - trial[r]) ** 2
        b_star = max(abs(alpha), gamma * dist2)
        if -b_star + ht >= q_star * phi or eta_star >= top:
            break
        eta_star = min(eta_star / rho, top)
    return kind, eta, phi


@numba.njit(cache=True)
def _pairwise_sum(a, n):
    """a[:n].sum() added up in numpy's order for n <= 128 (numpy's
    pairwise summation splits longer arrays), so that the compiled
    `direction_weights` rounds exactly as the same steps in numpy do.
    (Not recursive: numba's cache does not reload recursive functions
    reliably.)"""
    res = -0.0
    if n < 8:
        for i in range(n):
            res += a[i]
        return res
    r = a[:8].copy()
    i = 8
    while i < n - n % 8:
        for j in range(8):
            r[j] += a[i + j]
        i += 8
    res = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for j in range(i, n):
        res += a[j]
    return res


def _solve_direction(P, c, lam, sample):
    """piqp's part of `direction_weights` (run in object mode)."""
    try:
        lam[:c.size] = simplex_solve(P, c)
    except QPError as exc:
        _direction_failed(sample, exc)
        return False
    return True


#: the bundle QP failures of the run under way, (sample, reason): told in
#: one warning at its end (`one_qp_warning`), not one a sample (2,400 of
#: them on data in other units)
QP_FAILURES = []
_QP_RUNS = []           # the `one_qp_warning` blocks open, innermost last


def _direction_failed(sample, reason):
    if _QP_RUNS:
        QP_FAILURES.append((sample, str(reason)))
    else:
        warn(f"bundle QP failed at sample {sample} ({reason}); using the "
             f"current subgradient only", IdentificationWarning)


@contextlib.contextmanager
def one_qp_warning():
    """The bundle QP failures within the block (and blocks nested in it)
    told in one IdentificationWarning when the outermost block ends."""
    if not _QP_RUNS:
        del QP_FAILURES[:]
    _QP_RUNS.append(True)
    try:
        yield
    finally:
        _QP_RUNS.pop()
        if not _QP_RUNS and QP_FAILURES:
            (sample, reason), n = QP_FAILURES[0], len(QP_FAILURES)
            del QP_FAILURES[:]
            warn(f"bundle QP failed at {n} sample(s), first at sample "
                 f"{sample} ({reason}); the current subgradient alone was "
                 f"used there", IdentificationWarning)


@numba.njit(cache=True)
def direction_weights(H, beta, n, lam, sample):
    """Bundle weights lam[:n] from the dual of (3.4), for n >= 2.

    On P = H[:n] H[:n]' (the product by BLAS, as numpy's) and c =
    beta[:n]: both are scaled by the largest of P's diagonal and |c|,
    which leaves the minimiser unchanged and keeps piqp's absolute
    tolerances meaningful when the subgradients are tiny; piqp solves the
    problem in object mode (`simplex_solve`), and its minimiser is
    clipped to >= 0 and renormalised to sum to one (it is feasible only
    to piqp's tolerance). If piqp stops at its iteration limit (it can on
    nearly collinear bundles) its last iterate, projected the same way,
    is used: any point of the simplex gives a valid convex combination
    of subgradients. If piqp fails, warns and uses the
    current subgradient only (lam = e_1); `sample` is the sample number
    the warning quotes.
    """
    Hn = H[:n]
    P = np.dot(Hn, Hn.T)
    scale = max(np.max(np.diag(P)), np.max(np.abs(beta[:n])), 1e-300)
    P /= scale
    c = beta[:n] / scale
    with numba.objmode(ok='boolean'):
        ok = _solve_direction(P, c, lam, sample)
    if ok:
        for j in range(n):
            if lam[j] < 0.0:
                lam[j] = 0.0
        total = _pairwise_sum(lam, n)
        if total > 0.0:
            for j in range(n):
                lam[j] /= total
        else:
            ok = False
            with numba.objmode():
                _direction_failed(sample,
                                  "piqp returned no point of the simplex")
    if not ok:
        for j in range(n):
            lam[j] = 0.0
        lam[0] = 1.0


@numba.njit(cache=True)
def bundle_run(theta, trials, ntrial, s, o, u, ystar, y, xs, vs, zs, ys,
               k0, k1, n_before, eta0, eta_max, rho, n_ls, q, q_star, gamma,
               delta, step_bound, m_min, full_step_test, divergence_limit,
               H, beta, lam, grad, theta_new, trial, t, history, errors,
               kinds):
    """The bundle method over samples k0..k1-1 (Steps 1-3 per sample).

    Updates `theta` in place, keeps the last len(trials) trial points and
    their distances s_j to the estimate in `trials` and `s` (the first
    `ntrial` rows in use), and writes theta(k), e(k) and the step kind of
    each sample into `history`, `errors` and `kinds`. `n_before` is the
    number of samples processed before k0 (for warnings). Stops before a
    sample whose new estimate is non-finite or exceeds `divergence_limit`
    in absolute value, leaving theta at the last finite estimate. Returns
    (the first sample not processed, k1 if all were; ntrial).
    """
    p = theta.size
    cap = trials.shape[0] if H.shape[0] > 1 else 0
    for k in range(k0, k1):
        f0, e0, n = bundle_prepare(theta, trials, ntrial, s, o, u, ystar, y,
                                   xs, vs, zs, k, gamma, H, beta, grad)
        if n == 1:
            lam[0] = 1.0
        else:
            direction_weights(H, beta, n, lam, n_before + k - k0)
        kind, _, _ = bundle_finish(
            theta, lam, H, beta, n, f0, e0, o, u, ystar, y, xs, vs, zs, ys,
            k, eta0, eta_max, rho, n_ls, q, q_star, gamma, delta,
            step_bound, m_min, theta_new, trial, t, grad, full_step_test)
        for r in range(p):
            if not np.isfinite(theta_new[r]) or (abs(theta_new[r])
                                                 > divergence_limit):
                return k, ntrial
        if kind != STOP and cap:
            for r in range(p):
                t[r] = theta_new[r] - theta[r]
            step = np.sqrt(np.dot(t, t))    # np.linalg.norm, bit for bit
            for j in range(ntrial):
                s[j] += step
            if ntrial == cap:
                for j in range(cap - 1):
                    trials[j] = trials[j + 1]
                    s[j] = s[j + 1]
                ntrial -= 1
            for r in range(p):
                trials[ntrial, r] = trial[r]
                t[r] = theta_new[r] - trial[r]
            s[ntrial] = np.sqrt(np.dot(t, t))
            ntrial += 1
        for r in range(p):
            theta[r] = theta_new[r]
            history[k, r] = theta_new[r]
        store_state(theta, o, u, ystar, xs, vs, zs, ys, k, grad)
        errors[k] = e0
        kinds[k] = kind
    return k1, ntrial


@numba.njit(cache=True)
def gradient_run(theta, o, u, y, series_parallel, xs, vs, zs, ys, k0, k1,
                 mu, skip_nonsmooth, m_min, history, errors, kinds, grad):
    """The traditional gradient method over samples k0..k1-1.

    theta(k+1) = theta(k) + mu e(k) w(k). At a nonsmooth sample (a zone
    switch in the predictor window) the update is skipped (kind SKIP) when
    `skip_nonsmooth`, and otherwise taken with w the gradient of the zone
    eq. (2.2) selects, a Clarke subgradient (kind SUBGRADIENT). Returns
    the index of the first non-finite estimate, or -1.
    """
    for k in range(k0, k1):
        ystar = y if series_parallel else ys
        yhat, nonsmooth = window_predict(theta, o, u, ystar, xs, vs, zs, k,
                                         grad)
        e = y[k] - yhat
        errors[k] = e
        if nonsmooth and skip_nonsmooth:
            kinds[k] = SKIP
        else:
            kinds[k] = SUBGRADIENT if nonsmooth else LONG
            for r in range(theta.size):
                theta[r] += mu * e * grad[r]
            project(theta, o, m_min)
        for r in range(theta.size):
            if not np.isfinite(theta[r]):
                return k
            history[k, r] = theta[r]
        store_state(theta, o, u, ystar, xs, vs, zs, ys, k, grad)
    return -1


RPEM_OK, RPEM_LIMITED, RPEM_REJECTED, RPEM_RESET = 8, 5, 6, 7


@numba.njit(cache=True)
def rpem_run(theta, P, o, u, y, xs, vs, zs, ys, Sx, Sv, Sy, k0, k1,
             n_before, warmup, lam_state, lam0, P0, p_max, max_step, m_min,
             err_limit, history, errors, kinds, psi, Ppsi, dtheta, trial):
    """Recursive prediction-error (Gauss-Newton) estimator, samples k0..k1-1.

    Output-error predictor with exact recursive sensitivities (`oe_steps`);
    for the first `warmup` samples the predictor is series-parallel.
    Forgetting factor lam(k) = lam0 lam(k-1) + 1 - lam0 (lam_state[0]).
    Safeguards: the step is limited to `max_step` (2-norm); it is halved
    until m1, m2 >= m_min, D >= 0 and L1, L2 are stable, else rejected;
    P is reset to P0 I if its trace exceeds p_max or turns non-finite; a
    non-finite or huge prediction error resets the model's stored signals
    and P. Returns the number of P resets.
    """
    p = theta.size
    resets = 0
    for k in range(k0, k1):
        sp = (n_before + k - k0) < warmup
        if sp:
            yhat = oe_steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, k,
                            k + 1, y, False)
        else:
            yhat = oe_steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, k,
                            k + 1, ys, True)
        e = y[k] - yhat
        errors[k] = e
        kind = RPEM_OK
        if not np.isfinite(e) or abs(e) > err_limit:
            # the simulated model ran away: restart its signals and P
            for t in range(k - 30 if k >= 30 else 0, k + 1):
                xs[t] = 0.0
                vs[t] = 0.0
                ys[t] = y[t]
                zs[t] = 0
                for r in range(p):
                    Sx[t, r] = 0.0
                    Sv[t, r] = 0.0
                    Sy[t, r] = 0.0
            for i in range(p):
                for j in range(p):
                    P[i, j] = P0 if i == j else 0.0
            resets += 1
            kinds[k] = RPEM_RESET
            for r in range(p):
                history[k, r] = theta[r]
            continue
        lam = lam_state[0]
        for r in range(p):
            psi[r] = Sy[k, r]
        s = lam
        for i in range(p):
            acc = 0.0
            for j in range(p):
                acc += P[i, j] * psi[j]
            Ppsi[i] = acc
            s += psi[i] * acc
        norm2 = 0.0
        for r in range(p):
            dtheta[r] = Ppsi[r] / s * e
            norm2 += dtheta[r] * dtheta[r]
        if norm2 > max_step * max_step:
            scale = max_step / np.sqrt(norm2)
            for r in range(p):
                dtheta[r] *= scale
            kind = RPEM_LIMITED
        accepted = False
        for _ in range(8):
            for r in range(p):
                trial[r] = theta[r] + dtheta[r]
            project(trial, o, m_min)
            if stable_and_finite(trial, o):
                accepted = True
                break
            for r in range(p):
                dtheta[r] *= 0.5
            kind = RPEM_LIMITED
        if accepted:
            for r in range(p):
                theta[r] = trial[r]
        else:
            kind = RPEM_REJECTED
        # covariance update (also after a rejected step: data still inform)
        tr = 0.0
        for i in range(p):
            for j in range(p):
                P[i, j] = (P[i, j] - Ppsi[i] * Ppsi[j] / s) / lam
        for i in range(p):
            for j in range(i + 1, p):
                avg = 0.5 * (P[i, j] + P[j, i])
                P[i, j] = avg
                P[j, i] = avg
            tr += P[i, i]
        if not np.isfinite(tr) or tr > p_max:
            for i in range(p):
                for j in range(p):
                    P[i, j] = P0 if i == j else 0.0
            resets += 1
            kind = RPEM_RESET
        lam_state[0] = lam0 * lam + 1.0 - lam0
        kinds[k] = kind
        for r in range(p):
            history[k, r] = theta[r]
    return resets
