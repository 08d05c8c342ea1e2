r"""The linear output-error core on scaled data (private).

`fit_oe` fits MATLAB ``oe``'s model y = B(q) / F(q) u(t - nk) + e on
arrays already scaled to order one (`identify_linear` scales and checks;
the sandwich search reuses the core for its baseline and its re-fits of
L2). The method is described in `linear`: integrators factored out by
integrating the input, an ARX start with unstable roots reflected, a few
Steiglitz-McBride iterations, then Levenberg-Marquardt with exact
gradients and every iterate stable. `wants_integrator` is the rule, shared
by `identify_linear` and `identify`, for when ``integrators='auto'`` tries
one integrator.
"""

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import lfilter

from . import _predictor
from .._checks import PINNED
from ._problem import integrator_poly

__all__ = []

RADIUS = 1 - 1e-6        # free poles must satisfy |p| < RADIUS
_START_RADIUS = 0.999     # reflected start poles are kept inside this
_SM_ITER = 5              # Steiglitz-McBride iterations of the start
#: Samples an experiment must have on average for `_lagged_normal`
#: (with 600 experiments of 100 samples it took 358 ms against the
#: Jacobian's 66).
LAGGED_FROM = 1000
#: A run has converged to the data's precision when its last
#: `PRECISION_WINDOW` steps together lowered the cost by at most
#: `PRECISION` times p / N of it, and the Gauss-Newton step at the iterate
#: predicts at most p / N more (p free parameters, N samples). p / N of
#: the cost is what moving the parameters by about one standard error
#: is worth, so the iterate is then within a fraction of a standard error
#: of where the crawl would end. On records of a speed drive (an
#: integrator, so the input is integrated) the fit of nb = 3, nf = 4
#: crawls along a curved valley of F', the Gauss-Newton step predicting
#: a relative decrease of 1e-4 while each step achieves 5e-8: 4 of the 20
#: drives of benchmarks/bench_servo.py's tuning set ran out of the 100
#: iterations (one out of 1,000) at fits equal to four decimals to those
#: 1,000 iterations reach
PRECISION = 0.1
PRECISION_WINDOW = 10


def _segs(x):
    """Experiments as a list of arrays (one array is one experiment)."""
    return list(x) if isinstance(x, (list, tuple)) else [x]


def _split(x, like):
    """Cut the concatenated array x into pieces as long as `like`'s."""
    out, at = [], 0
    for part in like:
        out.append(x[at:at + part.size])
        at += part.size
    return out


def _filt(b, a, x):
    """lfilter over each experiment from zero initial conditions,
    concatenated."""
    return np.concatenate([lfilter(b, a, part) for part in _segs(x)])


def _delays(x, first, count, out=None, negate=False):
    """Matrix whose column j is x delayed by first + j samples (zero ICs),
    experiment by experiment (negated with `negate`); written into `out`
    (one row per sample, `count` columns) when given."""
    parts = _segs(x)
    if out is None:
        out = np.empty((sum(part.size for part in parts), count))
    at = 0
    for part in parts:
        n = part.size
        for j in range(count):
            d = min(first + j, n)
            col = out[at:at + n, j]
            col[:d] = 0.0
            if negate:
                np.negative(part[:n - d], out=col[d:])
            else:
                col[d:] = part[:n - d]
        at += n
    return out


def max_root(fp):
    """Largest root modulus of the monic polynomial fp (0 if constant)."""
    if fp.size <= 1:
        return 0.0
    if not np.all(np.isfinite(fp)):
        return np.inf
    if fp.size == 2:
        return abs(fp[1])
    return float(np.max(np.abs(np.roots(fp))))


def _simulate(b, fp, v, nk):
    """yhat = q^-nk B / F' v from zero initial conditions."""
    return _filt(np.concatenate([np.zeros(nk), b]), fp, v)


def _offsets_signal(parts, offsets):
    """One constant per experiment, as long as `parts`, concatenated."""
    return np.concatenate([np.full(part.size, c)
                           for part, c in zip(parts, offsets)])


def fit_output(fit, u, nk):
    """The output of a `fit_oe` result `fit` (its B, F with the
    integrators, and offsets) on the inputs `u` (a list of experiments;
    zero initial conditions)."""
    u = _segs(u)
    return _simulate(fit['B'], fit['F'], u, nk) + _offsets_signal(
        u, fit['offsets'])


def _cost(y, yhat):
    """Half the sum of squared errors; inf for a diverged output (whose
    overflow is that answer, not a warning for the user)."""
    with np.errstate(over='ignore', invalid='ignore'):
        r = y - yhat
        c = 0.5 * (r @ r)
    return c if np.isfinite(c) else np.inf


def _lstsq(phi, y):
    """Least squares by column-scaled normal equations, refined once.

    Much faster than a QR for N >> p; the refinement step recovers most
    of the accuracy lost by squaring the condition number.
    """
    d = np.linalg.norm(phi, axis=0)
    d = np.where(d > 0, d, 1.0)
    a = (phi.T @ phi) / np.outer(d, d)
    x = np.linalg.lstsq(a, (phi.T @ y) / d, rcond=None)[0]
    x = x + np.linalg.lstsq(a, (phi.T @ (y - phi @ (x / d))) / d,
                            rcond=None)[0]
    return x / d


def _centred(x, segs, offsets):
    """x (samples stacked over the experiments `segs`, rows for a matrix)
    with each experiment's mean removed, if `offsets`: least squares on
    centred columns is least squares with a constant per experiment. In
    place: every caller passes an array it has just made (on a million
    samples a copy of the Jacobian cost as much as filtering it)."""
    if not offsets:
        return x
    at = 0
    for part in segs:
        rows = x[at:at + part.size]
        rows -= rows.mean(axis=0)
        at += part.size
    return x


def _arx(v, y, nb, m, nk, offsets=False):
    """ARX least squares: F'(q) y = q^-nk B(q) v (+ a constant per
    experiment with `offsets`) + e; returns b, F'."""
    segs = _segs(y)
    theta = _lstsq(
        _centred(np.hstack([_delays(v, nk, nb),
                            _delays(y, 1, m, negate=True)]), segs, offsets),
        _centred(np.concatenate(segs), segs, offsets))
    return theta[:nb], np.concatenate([[1.0], theta[nb:]])


def _b_given_f(v, y, fp, nb, nk, offsets=False):
    """Least-squares B for a fixed denominator F'."""
    segs = _segs(y)
    return _lstsq(
        _centred(_delays(_split(_filt([1.0], fp, v), _segs(v)), nk, nb),
                 segs, offsets),
        _centred(np.concatenate(segs), segs, offsets))


def _stabilise(fp):
    """Reflect roots outside the unit circle in, keep them < _START_RADIUS."""
    if fp.size <= 1 or max_root(fp) < _START_RADIUS:
        return fp
    roots = np.roots(fp)
    mag = np.abs(roots)
    roots = np.where(mag > 1, roots / mag ** 2, roots)     # 1 / conj(p)
    mag = np.abs(roots)
    roots = np.where(mag > _START_RADIUS, roots * _START_RADIUS / mag,
                     roots)
    return np.real(np.poly(roots))


def _jacobian(b, fp, v, yhat, nk):
    """d yhat / d [b, f'] by filtering through 1 / F'."""
    nb, m = b.size, fp.size - 1
    segs = _segs(v)
    # one matrix, filled column by column (each column contiguous): on a
    # million samples, stacking copies cost more than the filtering
    jac = np.empty((sum(part.size for part in segs), nb + m), order='F')
    _delays(_split(_filt([1.0], fp, segs), segs), nk, nb, out=jac[:, :nb])
    if m:
        _delays(_split(_filt([1.0], fp, _split(yhat, segs)), segs), 1, m,
                out=jac[:, nb:], negate=True)
    return jac


def _normal(jac, r):
    """Column-scaled normal equations: J'J / dd', J'r / d and d = |J_:j|
    (from the diagonal of J'J)."""
    return _scaled(jac.T @ jac, jac.T @ r)


def _scaled(a, g):
    """J'J and J'r scaled by d = |J_:j| (from the diagonal of J'J)."""
    d = np.sqrt(np.maximum(np.diag(a), 0.0))
    d = np.maximum(d, 1e-12 * max(d.max(), 1e-300))
    return a / np.outer(d, d), g / d, d


def _lagged_normal(b, fp, v, yhat, r, nk, *, offsets):
    """`_normal` of the centred `_jacobian` and residual r, without the
    Jacobian: its columns are delayed copies of two filtered signals, so
    each product is a correlation of the two at one lag (a dot product,
    shared by every pair of columns at that lag) less the few samples that
    the later column's zero start leaves out. On a million samples this
    reads three signals some 30 times instead of writing and reading a
    matrix of a column per parameter (78 to 25 ms an iteration on 11
    parameters). The same numbers to rounding, summed in another order."""
    segs = _segs(v)
    nb, m = b.size, fp.size - 1
    shift = np.r_[nk + np.arange(nb), 1 + np.arange(m)].astype(int)
    which = [0] * nb + [1] * m         # u or -y filtered
    p = nb + m
    a, g = np.zeros((p, p)), np.zeros(p)
    parts = zip(_split(_filt([1.0], fp, segs), segs),
                _split(-_filt([1.0], fp, _split(yhat, segs)), segs),
                _split(r, segs))
    for uf, yf, rr in parts:
        x, n = (uf, yf), uf.size
        lag = {}
        for i in range(p):
            for j in range(i, p):
                c1, c2 = (i, j) if shift[i] <= shift[j] else (j, i)
                s1, s2 = shift[c1], shift[c2]
                if s2 >= n:
                    continue
                x1, x2, d = x[which[c1]], x[which[c2]], s2 - s1
                key = (which[c1], which[c2], d)
                if key not in lag:
                    lag[key] = x1[d:] @ x2[:n - d]
                a[i, j] += lag[key] - x1[n - s1:] @ x2[n - s2:n - d]
            if shift[i] < n:
                g[i] += x[which[i]][:n - shift[i]] @ rr[shift[i]:]
        if offsets and n:
            mu = np.array([x[which[i]][:max(n - shift[i], 0)].sum() / n
                           for i in range(p)])
            a -= n * np.triu(np.outer(mu, mu))
            g -= mu * rr.sum()
    a = np.triu(a) + np.triu(a, 1).T
    return _scaled(a, g)


def _start(v, y, nb, m, nk, offsets=False):
    """ARX start, stabilised, B refitted, improved by Steiglitz-McBride
    (with `offsets`, a constant per experiment in every least-squares
    fit and in the cost; each experiment's output is taken from its
    first sample, which the zeros before it then continue: a large output
    offset otherwise makes a step there that the least squares chase)."""
    segs = _segs(y)
    if offsets:
        segs = [part - part[0] for part in segs]
        y = segs
    b, fp = _arx(v, y, nb, m, nk, offsets)
    if not np.all(np.isfinite(fp)):
        fp = np.concatenate([[1.0], np.zeros(m)])
    fp = _stabilise(fp)
    b = _b_given_f(v, y, fp, nb, nk, offsets)
    yc = np.concatenate(segs)

    def cost_of(b, fp):
        return _cost(_centred(yc - _simulate(b, fp, v, nk), segs, offsets),
                     0.0)

    cost = cost_of(b, fp)
    for _ in range(_SM_ITER if m else 0):
        b_t, fp_t = _arx(_split(_filt([1.0], fp, v), _segs(v)),
                         _split(_filt([1.0], fp, y), segs), nb, m, nk,
                         offsets)
        if not max_root(fp_t) < RADIUS:
            break
        cost_t = cost_of(b_t, fp_t)
        if not cost_t < cost:
            break
        b, fp, cost = b_t, fp_t, cost_t
    return b, fp


def fit_oe(u, y, shape, integrators, *, max_iter=100, tol=1e-10,
           offsets=False, start=None, stop=None):
    """Output-error fit on already scaled arrays (no checks, no scaling).

    Parameters
    ----------
    u, y : ndarray, shape (N,), or lists of them
        Input and output, of order one in size; lists are experiments,
        each from zero initial conditions, with the cost summed.
    shape : tuple of int
        (nb, nf, nk): orders and delay.
    integrators : int
        Number of poles fixed at z = 1.
    max_iter : int
        Maximum Levenberg-Marquardt iterations.
    tol : float
        Stop when the relative (predicted or actual) decrease of the cost
        falls below tol.
    offsets : bool
        Also fit a constant output offset per experiment. They enter
        linearly, so they are projected out (variable projection): each
        experiment's residual and Jacobian are centred.
    start : tuple of ndarray, optional
        (B, F') to start from instead of the ARX start (F' the free factor,
        monic, stable); an unstable or ill-sized one is not used.
    stop : threading.Event, optional
        Checked before each iteration: once set, the run stops there (not
        converged), for a fit on a thread whose result is no longer
        wanted.

    Returns
    -------
    dict
        ``B`` (nb,), ``F`` (nf + 1, monic, integrators included), ``Ff``
        (the free factor F'), ``theta`` ([b, f'] free parameters),
        ``std`` (their standard errors), ``cost``, ``yhat`` (offsets
        included), ``offsets`` (one per experiment, zeros unless fitted),
        ``nit``, ``converged`` and ``message``.
    """
    problem = _OutputError(u, y, shape, integrators, offsets)
    return problem.result(problem.run(max_iter, tol, start, stop))


def _precise(recent, predicted, share):
    """The message of a run converged to the data's precision
    (`PRECISION`), or None: `recent` the last steps' relative decreases,
    `predicted` the Gauss-Newton step's, `share` p / N."""
    if len(recent) == PRECISION_WINDOW and predicted <= share \
            and sum(recent) <= PRECISION * share:
        return (f"converged to the data's precision: the last "
                f"{PRECISION_WINDOW} steps lowered the cost by "
                f"{sum(recent):.1e} of it, the next is predicted to lower "
                f"it by {predicted:.1e} (one standard error of the "
                f"parameters is worth {share:.1e})")
    return None


class _OutputError:
    """The linear output-error cost of one `fit_oe` call and its
    Levenberg-Marquardt run."""

    def __init__(self, u, y, shape, integrators, offsets):
        self.nb, nf, self.nk = shape
        self.m = nf - integrators
        self.integrators, self.offsets = integrators, offsets
        v = _segs(u)
        for _ in range(integrators):
            v = [np.cumsum(part) for part in v]
        self.v, self.ys = v, _segs(y)
        self.y = np.concatenate(self.ys)
        # p / N: the relative cost of a standard error (`PRECISION`)
        self.share = (self.nb + self.m + (len(self.ys) if offsets else 0)) \
            / self.y.size

    def centre(self, x):
        return _centred(x, self.ys, self.offsets)

    def cost_of(self, yhat):
        return _cost(self.centre(self.y - yhat), 0.0)

    def normal(self, b, fp, yhat):
        # lagged correlations pay on long experiments; on many short ones
        # their loop over pairs of columns for each costs more
        if (self.y.size >= _predictor.SPECIALIZE_FROM
                and self.y.size >= LAGGED_FROM * len(self.ys)):
            return _lagged_normal(b, fp, self.v, yhat, self.y - yhat,
                                  self.nk, offsets=self.offsets)
        return _normal(self.centre(_jacobian(b, fp, self.v, yhat, self.nk)),
                       self.centre(self.y - yhat))

    def run(self, max_iter, tol, start=None, stop=None):
        """Levenberg-Marquardt from `start` (B, F') where it fits, else
        from the `_start`: a dict of the final iterate, its normal
        equations and the verdict."""
        nb = self.nb
        if (start is not None and np.size(start[0]) == nb
                and np.size(start[1]) == self.m + 1
                and np.all(np.isfinite(np.r_[start[0], start[1]]))
                and max_root(np.asarray(start[1], float)) < RADIUS):
            b, fp = (np.array(a, dtype=float) for a in start)
        else:
            b, fp = _start(self.v, self.ys, nb, self.m, self.nk,
                           self.offsets)
        s = dict(theta=np.concatenate([b, fp[1:]]), b=b, fp=fp)
        s['yhat'] = _simulate(b, fp, self.v, self.nk)
        s['cost'] = cost = self.cost_of(s['yhat'])
        floor = 1e-24 * (0.5 * (self.y @ self.y))   # rounding: an exact fit
        mu, nit, converged = 1e-4, 0, False
        message = f"reached max_iter = {max_iter}"
        recent = []                 # the last steps' relative decreases
        for nit in range(max_iter + 1):
            s['a'], g, s['d'] = self.normal(s['b'], s['fp'], s['yhat'])
            gn = np.linalg.lstsq(s['a'], g, rcond=None)[0]
            predicted = 0.5 * (g @ gn)   # decrease of the Gauss-Newton step
            if cost <= floor or predicted <= tol * cost:
                converged = True
                message = (f"converged: predicted relative decrease "
                           f"{predicted / max(cost, 1e-300):.1e} <= tol"
                           if cost > floor else "converged: exact fit")
                break
            done = _precise(recent, predicted / cost, self.share)
            if done:
                converged, message = True, done
                break
            if nit == max_iter:
                break
            if stop is not None and stop.is_set():
                message = "stopped: the fit is no longer wanted"
                break
            trial, mu = self._damped(s, g, gn, mu)
            if trial is None:
                converged = predicted <= np.sqrt(tol) * cost
                message = (f"{'converged' if converged else 'stalled'}: no "
                           f"decreasing step (predicted relative decrease "
                           f"{predicted / cost:.1e})")
                break
            decrease = (cost - trial['cost']) / cost
            recent = (recent + [decrease])[-PRECISION_WINDOW:]
            s.update(trial)
            cost = s['cost']
            mu = mu / 10 if mu > 1e-10 else 0.0
            if decrease <= tol:
                nit += 1
                s['a'], _, s['d'] = self.normal(s['b'], s['fp'], s['yhat'])
                converged = True
                message = (f"converged: relative decrease {decrease:.1e} "
                           f"<= tol")
                break
        return dict(s, nit=nit, converged=converged, message=message)

    def _damped(self, s, g, gn, mu):
        """The step of the smallest damping from `mu` up (tenfold) that
        keeps F' stable and lowers the cost: (the new iterate, mu), or
        (None, mu) when mu passes 1e12."""
        nb, theta, a, d = self.nb, s['theta'], s['a'], s['d']
        while True:
            try:
                step = (gn if mu == 0 else
                        np.linalg.solve(a + mu * np.eye(theta.size), g)) / d
            except np.linalg.LinAlgError:
                step = None
            if step is not None:
                trial = theta + step
                fp_t = np.concatenate([[1.0], trial[nb:]])
                if max_root(fp_t) < RADIUS:
                    yhat_t = _simulate(trial[:nb], fp_t, self.v, self.nk)
                    cost_t = self.cost_of(yhat_t)
                    if cost_t < s['cost']:
                        return dict(theta=trial, b=trial[:nb], fp=fp_t,
                                    yhat=yhat_t, cost=cost_t), mu
            mu = max(10 * mu, 1e-6)
            if mu > 1e12:
                return None, mu

    def result(self, s):
        """The `fit_oe` dict of the run `s`: a free pole pinned at the
        stability boundary is not converged, standard errors, F with the
        integrators, offsets."""
        converged, message = s['converged'], s['message']
        fp, yhat, cost = s['fp'], s['yhat'], s['cost']
        radius = max_root(fp)
        if converged and radius > PINNED:
            converged = False
            more = (f"an integrator (try integrators=1 or 'auto')"
                    if self.integrators == 0 else
                    f"one more integrator than the {self.integrators} "
                    f"fitted (try integrators={self.integrators + 1}), or "
                    f"a slow pole the record is too short to place")
            message = (f"pinned at the stability boundary: a free pole has "
                       f"|p| = {radius:.7f}; the data suggest {more}")
        dof = max(self.y.size - s['theta'].size
                  - (len(self.ys) if self.offsets else 0), 1)
        with np.errstate(all='ignore'):
            cov = np.linalg.pinv(s['a']) / np.outer(s['d'], s['d'])
            std = np.sqrt(2 * cost / dof * np.clip(np.diag(cov), 0, None))
        f = fp.copy()
        for _ in range(self.integrators):
            f = np.convolve(f, [1.0, -1.0])
        off = np.array([part.mean() for part in _split(self.y - yhat,
                                                       self.ys)]) \
            if self.offsets else np.zeros(len(self.ys))
        yhat = yhat + _offsets_signal(self.ys, off)
        return dict(B=s['b'].copy(), F=f, Ff=fp.copy(),
                    theta=s['theta'].copy(), std=std, cost=cost, yhat=yhat,
                    offsets=off, nit=s['nit'], converged=bool(converged),
                    message=message)


def fit_blocks(u, y, x0, sizes, *, nk, integrators=(0, 0), offsets=False,
               max_iter=100, radius=RADIUS):
    """Output-error fit of a linear model in the product form of two
    blocks, y = g q^-nk B1 B2 / (A1 A2) u (scaled data, as `fit_oe`).

    The model a sandwich with a closed backlash is: each block has its
    own orders, so a complex pair of roots fits only in a block of order
    two or more.

    Parameters
    ----------
    u, y : lists of ndarray
        Input and output experiments, each from zero initial conditions.
    x0 : ndarray
        The start, [c', a', g, b, d]: the free monic denominators of the
        second and first block without their leading 1, the gain, and the
        monic numerators of the first and second block without it.
    sizes : tuple of int
        (nc', na', nb, nd): the lengths of c', a', b and d.
    nk : int
        Delay.
    integrators : tuple of int
        Poles fixed at z = 1 in the first and second block.
    offsets : bool
        Also fit a constant output offset per experiment (projected out).
    max_iter : int
        Most Jacobian evaluations of the trust-region solver.
    radius : float
        The free poles stay inside it (default `RADIUS`).

    Returns
    -------
    dict
        ``x`` (as `x0`), ``B`` and ``F`` (the product model, as `fit_oe`
        gives them), ``cost`` and ``offsets`` (one per experiment).
    """
    nc, na, nb, nd = sizes
    cut = np.cumsum([nc, na, 1, nb])
    ys = _segs(y)
    y_all = np.concatenate(ys)
    far = np.full(y_all.size, 1e3 * (np.std(y_all) + 1.0))

    def model(x):
        c, a, g, b, d = np.split(x, cut)
        den = [np.convolve(np.r_[1.0, a], integrator_poly(integrators[0])),
               np.convolve(np.r_[1.0, c], integrator_poly(integrators[1]))]
        return (g[0] * np.convolve(np.r_[1.0, b], np.r_[1.0, d]),
                np.convolve(*den))

    def output(x):
        return _simulate(*model(x), u, nk)

    def residuals(x):
        c, a = x[:nc], x[nc:nc + na]
        if max(max_root(np.r_[1.0, c]), max_root(np.r_[1.0, a])) >= radius:
            return far
        with np.errstate(all='ignore'):
            r = _centred(y_all - output(x), ys, offsets)
        return r if np.all(np.isfinite(r)) else far

    with np.errstate(all='ignore'):
        x = least_squares(residuals, np.asarray(x0, float), method='trf',
                          x_scale='jac', max_nfev=max_iter * (x0.size + 1)).x
    r = y_all - output(x)
    off = np.array([part.mean() for part in _split(r, ys)]) if offsets \
        else np.zeros(len(ys))
    B, F = model(x)
    return dict(x=x, B=B, F=F, cost=_cost(_centred(r, ys, offsets), 0.0),
                offsets=off)


def wants_integrator(Ff):
    """The rule of ``integrators='auto'``: try one integrator when the
    free fit's denominator `Ff` has a real pole above 0.9."""
    poles = np.roots(Ff) if np.size(Ff) > 1 else np.zeros(0)
    return bool(np.any((poles.real > 0.9) & (np.abs(poles.imag) < 0.1)))


#: `cancelled_integrator`: a real zero closer to z = 1 than this
#: fraction of the distance from 1 to the model's slowest other pole
#: cancels its integrator over the model's own time scales; beyond 1
#: (where it also turns the low-frequency sign) the whole distance
DRIFT_RATIO = 0.1


def cancelled_integrator(fit):
    """The real zero of an integrating `fit_oe` result that cancels its
    pole at z = 1, or None.

    A zero z0 with |z0 - 1| < `DRIFT_RATIO` (1 - rho), rho the largest
    modulus of the other poles, leaves the integrator a ramp that emerges
    only long after the model's own dynamics have settled: a drift term
    that the fit uses to follow the record, not evidence of an
    integrator. Beyond 1 it also turns the model's low-frequency sign,
    and a loop designed on it runs away on the plant; there a zero
    closer to 1 than the slowest other pole (z0 - 1 < 1 - rho) is one.
    """
    zeros = np.roots(fit['B']) if np.size(fit['B']) > 1 else np.zeros(0)
    zeros = zeros[np.abs(zeros.imag) < 1e-9].real
    if not zeros.size:
        return None
    rho = max_root(fit['Ff']) if np.size(fit['Ff']) > 1 else 0.0
    near = zeros[np.argmin(np.abs(zeros - 1.0))]
    reach = (1.0 if near > 1.0 else DRIFT_RATIO) * (1.0 - rho)
    return float(near) if abs(near - 1.0) < reach else None


def fit_oe_auto(us, ys, shape, integrators, *, max_iter=100, tol=1e-10,
                offsets=False):
    """`fit_oe` with ``integrators`` an int or 'auto' (scaled data).

    'auto' fits 0 integrators, and 1 when `wants_integrator`, and keeps
    the lower AIC, unless a zero cancels the integrator
    (`cancelled_integrator`). Returns (out, used, aic, text): the chosen
    fit, its number of integrators, the AICs on the scaled data (None
    unless 'auto') and a sentence for the message.
    """
    kw = dict(max_iter=max_iter, tol=tol, offsets=offsets)
    if integrators != 'auto':
        return fit_oe(us, ys, shape, integrators, **kw), integrators, None, ''
    nb, nf, _ = shape
    n = sum(part.size for part in _segs(us))
    out = fit_oe(us, ys, shape, 0, **kw)
    p = nb + nf
    aic = {0: float(n * np.log(max(out['cost'], 1e-300)) + 2 * p), 1: None}
    if wants_integrator(out['Ff']):
        out1 = fit_oe(us, ys, shape, 1, **kw)
        aic[1] = float(n * np.log(max(out1['cost'], 1e-300)) + 2 * (p - 1))
    better = aic[1] is not None and aic[1] <= aic[0]
    drift = cancelled_integrator(out1) if better else None
    used = int(better and drift is None)
    if used:
        out = out1
    text = (f"; integrators='auto' chose {used} (AIC 0: {aic[0]:.6g}, 1: "
            + ('skipped, no real pole > 0.9' if aic[1] is None
               else f"{aic[1]:.6g}") + ")")
    if drift is not None:
        text += (f"; not 1, whose pole at z = 1 a zero at {drift:.6g} "
                 f"cancels (a drift term, not an integrator)")
    return out, used, aic, text
