r"""Linear output-error (OE) identification, the baseline of sandwich fits.

`identify_linear` fits MATLAB ``oe``'s model

.. math:: y(t) = \frac{B(q)}{F(q)}\, u(t - n_k) + e(t),

with :math:`B(q) = b_1 + b_2 q^{-1} + \dots + b_{n_b} q^{-(n_b-1)}` and
:math:`F(q) = 1 + f_1 q^{-1} + \dots + f_{n_f} q^{-n_f}`, from zero
initial conditions, by minimising :math:`\tfrac12\sum_t (y - \hat y)^2`
with :math:`\hat y` simulated from the input alone.

Method
------
1. u and y are divided by their RMS values (units invariance); B is
   mapped back (B sy / su) at the end.
2. ``integrators`` of the poles can be fixed at z = 1,
   F = (1 - q^-1)^k F'(q). Since B / (F' (1 - q^-1)^k) u = B / F' v with
   v = cumsum^k(u), only B / F' is estimated, on the input v.
3. Start: ARX least squares of y on its past and on v, unstable roots of
   F' reflected into the unit circle (p -> 1 / conj(p)), B re-fitted by
   least squares for that F', then a few Steiglitz-McBride iterations,
   each kept only if F' stays stable and the OE cost decreases.
4. Levenberg-Marquardt on the OE cost with exact gradients from
   ``scipy.signal.lfilter`` (d yhat / d b_j = q^-(nk+j-1) / F' v,
   d yhat / d f_i = -q^-i / F' yhat). A step is accepted only if it
   lowers the cost and keeps max abs(root(F')) < 1 - 1e-6; otherwise the
   damping grows.

`_fit_oe` is the core on already scaled arrays; the sandwich pipeline
reuses it.
"""

import numbers
import time

import numpy as np
import control as ct
from scipy.optimize import OptimizeResult
from scipy.signal import lfilter

from ._data import prepare, scale, scaled
from .._checks import check_int, check_positive, check_dt, serial_blas
from .._checks import check_data_scale

__all__ = ['identify_linear', 'LinearIdentificationResult']

_RADIUS = 1 - 1e-6        # free poles must satisfy |p| < _RADIUS
_START_RADIUS = 0.999     # reflected start poles are kept inside this
_BOUNDARY = 1 - 1e-5      # a fit with a free pole beyond this is pinned
_SM_ITER = 5              # Steiglitz-McBride iterations of the start


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


def _delays(x, first, count):
    """Matrix whose column j is x delayed by first + j samples (zero ICs),
    experiment by experiment."""
    if isinstance(x, (list, tuple)):
        return np.vstack([_delays(part, first, count) for part in x])
    n = x.size
    out = np.zeros((n, count))
    for j in range(count):
        d = first + j
        if d < n:
            out[d:, j] = x[:n - d]
    return out


def _max_root(fp):
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
    """The output of a `_fit_oe` result `fit` (its B, F with the
    integrators, and offsets) on the inputs `u` (a list of experiments;
    zero initial conditions)."""
    u = _segs(u)
    return _simulate(fit['B'], fit['F'], u, nk) + _offsets_signal(
        u, fit['offsets'])


def _cost(y, yhat):
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
    centred columns is least squares with a constant per experiment."""
    if not offsets:
        return x
    return np.concatenate([part - part.mean(axis=0)
                           for part in _split(x, segs)])


def _arx(v, y, nb, m, nk, offsets=False):
    """ARX least squares: F'(q) y = q^-nk B(q) v (+ a constant per
    experiment with `offsets`) + e; returns b, F'."""
    segs = _segs(y)
    theta = _lstsq(
        _centred(np.hstack([_delays(v, nk, nb), -_delays(y, 1, m)]), segs,
                 offsets),
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
    if fp.size <= 1 or _max_root(fp) < _START_RADIUS:
        return fp
    roots = np.roots(fp)
    mag = np.abs(roots)
    roots = np.where(mag > 1, roots / mag ** 2, roots)     # 1 / conj(p)
    mag = np.abs(roots)
    roots = np.where(mag > _START_RADIUS, roots * _START_RADIUS / mag, roots)
    return np.real(np.poly(roots))


def _jacobian(b, fp, v, yhat, nk):
    """d yhat / d [b, f'] by filtering through 1 / F'."""
    nb, m = b.size, fp.size - 1
    segs = _segs(v)
    cols = [_delays(_split(_filt([1.0], fp, segs), segs), nk, nb)]
    if m:
        cols.append(-_delays(_split(_filt([1.0], fp, _split(yhat, segs)),
                                    segs), 1, m))
    return np.hstack(cols)


def _normal(jac, r):
    """Column-scaled normal equations: J'J / dd', J'r / d and d = |J_:j|."""
    d = np.linalg.norm(jac, axis=0)
    d = np.maximum(d, 1e-12 * max(d.max(), 1e-300))
    return (jac.T @ jac) / np.outer(d, d), (jac.T @ r) / d, d


def _start(v, y, nb, m, nk, offsets=False):
    """ARX start, stabilised, B refitted, improved by Steiglitz-McBride
    (with `offsets`, a constant per experiment in every least-squares
    fit and in the cost)."""
    segs = _segs(y)
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
        if not _max_root(fp_t) < _RADIUS:
            break
        cost_t = cost_of(b_t, fp_t)
        if not cost_t < cost:
            break
        b, fp, cost = b_t, fp_t, cost_t
    return b, fp


def _fit_oe(u, y, nb, nf, nk, integrators, max_iter=100, tol=1e-10,
            offsets=False):
    """Output-error fit on already scaled arrays (no checks, no scaling).

    Parameters
    ----------
    u, y : ndarray, shape (N,), or lists of them
        Input and output, of order one in size; lists are experiments,
        each from zero initial conditions, with the cost summed.
    nb, nf, nk, integrators : int
        Orders, delay and number of poles fixed at z = 1.
    max_iter : int
        Maximum Levenberg-Marquardt iterations.
    tol : float
        Stop when the relative (predicted or actual) decrease of the cost
        falls below tol.
    offsets : bool
        Also fit a constant output offset per experiment. They enter
        linearly, so they are projected out (variable projection): each
        experiment's residual and Jacobian are centred.

    Returns
    -------
    dict
        ``B`` (nb,), ``F`` (nf + 1, monic, integrators included), ``Ff``
        (the free factor F'), ``theta`` ([b, f'] free parameters),
        ``std`` (their standard errors), ``cost``, ``yhat`` (offsets
        included), ``offsets`` (one per experiment, zeros unless fitted),
        ``nit``, ``converged`` and ``message``.
    """
    m = nf - integrators
    v = _segs(u)
    for _ in range(integrators):
        v = [np.cumsum(part) for part in v]
    ys = _segs(y)
    y = np.concatenate(ys)

    def centre(x):
        return _centred(x, ys, offsets)

    def cost_of(yhat):
        return _cost(centre(y - yhat), 0.0)

    b, fp = _start(v, ys, nb, m, nk, offsets)
    theta = np.concatenate([b, fp[1:]])
    yhat = _simulate(b, fp, v, nk)
    cost = cost_of(yhat)
    floor = 1e-24 * (0.5 * (y @ y))      # rounding level: an exact fit
    mu, nit, converged = 1e-4, 0, False
    message = f"reached max_iter = {max_iter}"
    for nit in range(max_iter + 1):
        a, g, d = _normal(centre(_jacobian(b, fp, v, yhat, nk)),
                          centre(y - yhat))
        gn = np.linalg.lstsq(a, g, rcond=None)[0]
        predicted = 0.5 * (g @ gn)       # decrease of the Gauss-Newton step
        if cost <= floor or predicted <= tol * cost:
            converged = True
            message = (f"converged: predicted relative decrease "
                       f"{predicted / max(cost, 1e-300):.1e} <= tol"
                       if cost > floor else "converged: exact fit")
            break
        if nit == max_iter:
            break
        while True:
            try:
                step = (gn if mu == 0 else
                        np.linalg.solve(a + mu * np.eye(theta.size), g)) / d
            except np.linalg.LinAlgError:
                step = None
            if step is not None:
                trial = theta + step
                fp_t = np.concatenate([[1.0], trial[nb:]])
                if _max_root(fp_t) < _RADIUS:
                    yhat_t = _simulate(trial[:nb], fp_t, v, nk)
                    cost_t = cost_of(yhat_t)
                    if cost_t < cost:
                        break
            mu = max(10 * mu, 1e-6)
            if mu > 1e12:
                cost_t = None
                break
        if cost_t is None:
            converged = predicted <= np.sqrt(tol) * cost
            message = (f"{'converged' if converged else 'stalled'}: no "
                       f"decreasing step (predicted relative decrease "
                       f"{predicted / cost:.1e})")
            break
        decrease = (cost - cost_t) / cost
        theta, b, fp, yhat, cost = trial, trial[:nb], fp_t, yhat_t, cost_t
        mu = mu / 10 if mu > 1e-10 else 0.0
        if decrease <= tol:
            nit += 1
            a, g, d = _normal(centre(_jacobian(b, fp, v, yhat, nk)),
                              centre(y - yhat))
            converged = True
            message = f"converged: relative decrease {decrease:.1e} <= tol"
            break
    radius = _max_root(fp)
    if converged and radius > _BOUNDARY:
        converged = False
        message = (f"pinned at the stability boundary: a free pole has "
                   f"|p| = {radius:.7f}; the data suggest an integrator "
                   f"(try integrators=1 or 'auto')")
    dof = max(y.size - theta.size - (len(ys) if offsets else 0), 1)
    with np.errstate(all='ignore'):
        cov = np.linalg.pinv(a) / np.outer(d, d)
        std = np.sqrt(2 * cost / dof * np.clip(np.diag(cov), 0, None))
    f = fp.copy()
    for _ in range(integrators):
        f = np.convolve(f, [1.0, -1.0])
    off = np.array([part.mean() for part in _split(y - yhat, ys)]) \
        if offsets else np.zeros(len(ys))
    yhat = yhat + _offsets_signal(ys, off)
    return dict(B=b.copy(), F=f, Ff=fp.copy(), theta=theta.copy(), std=std,
                cost=cost, yhat=yhat, offsets=off, nit=nit,
                converged=bool(converged), message=message)


def _fit_oe_auto(us, ys, nb, nf, nk, integrators, max_iter=100, tol=1e-10,
                 offsets=False):
    """`_fit_oe` with ``integrators`` an int or 'auto' (scaled data).

    'auto' fits 0 integrators, and 1 when the free model has a real pole
    above 0.9, and keeps the lower AIC. Returns (out, used, aic, text):
    the chosen fit, its number of integrators, the AICs on the scaled data
    (None unless 'auto') and a sentence for the message.
    """
    if integrators != 'auto':
        return (_fit_oe(us, ys, nb, nf, nk, integrators, max_iter, tol,
                        offsets),
                integrators, None, '')
    n = sum(part.size for part in _segs(us))
    out = _fit_oe(us, ys, nb, nf, nk, 0, max_iter, tol, offsets)
    p = nb + nf
    aic = {0: float(n * np.log(max(out['cost'], 1e-300)) + 2 * p), 1: None}
    poles = np.roots(out['Ff']) if nf else np.zeros(0)
    if np.any((poles.real > 0.9) & (np.abs(poles.imag) < 0.1)):
        out1 = _fit_oe(us, ys, nb, nf, nk, 1, max_iter, tol, offsets)
        aic[1] = float(n * np.log(max(out1['cost'], 1e-300)) + 2 * (p - 1))
    used = int(aic[1] is not None and aic[1] <= aic[0])
    if used:
        out = out1
    text = (f"; integrators='auto' chose {used} (AIC 0: {aic[0]:.6g}, 1: "
            + ('skipped, no real pole > 0.9' if aic[1] is None
               else f"{aic[1]:.6g}") + ")")
    return out, used, aic, text


def oe_transfer_function(b, f, nk, dt, name=None):
    """B(q) q^-nk / F(q) as a ct.TransferFunction in descending powers of z.

    Examples
    --------
    >>> from sandwichctl.identification.linear import oe_transfer_function
    >>> G = oe_transfer_function([1.5], [1, 0.1, 0.2], 1, 1)
    >>> G.num[0][0], G.den[0][0]
    (array([1.5, 0. ]), array([1. , 0.1, 0.2]))
    """
    b, f = np.asarray(b, float), np.asarray(f, float)
    nb, nf = b.size, f.size - 1
    deg = max(nb - 1 + nk, nf)
    num = np.concatenate([np.zeros(nk), b, np.zeros(deg - nk - nb + 1)])
    den = np.concatenate([f, np.zeros(deg - nf)])
    num = np.trim_zeros(num, 'f')
    if num.size == 0:
        num = np.zeros(1)
    kw = {} if name is None else {'name': name}
    return ct.tf(num, den, dt, **kw)


def _poly_str(c):
    """'1.5 z^2 - 0.2 z + 3' from coefficients in descending powers."""
    n = c.size - 1
    s = ''.join(f" {'-' if a < 0 else '+'} " + (
        ('' if abs(a) == 1 else f"{abs(a):.6g} ")
        + (f"z^{n - i}" if n - i > 1 else 'z') if i < n else f"{abs(a):.6g}")
        for i, a in enumerate(c) if a != 0)
    return s[3:] if s.startswith(' + ') else ('-' + s[3:] if s else '0')


class LinearIdentificationResult(OptimizeResult):
    """Result of `identify_linear` (a `scipy.optimize.OptimizeResult`).

    Attributes
    ----------
    model : control.TransferFunction
        The identified B(z) z^-nk / F(z) in the user's units, discrete with
        the given dt, in descending powers of z.
    B, F : ndarray
        The polynomials in q^-1: B (nb), F (nf + 1, monic, integrator
        factors (1 - q^-1) included).
    nb, nf, nk, integrators : int
        Orders, delay and the number of poles fixed at z = 1 (the one
        chosen when ``integrators='auto'``).
    fit : float
        100 (1 - ||y - yhat|| / ||y - mean(y)||), percent, as MATLAB's
        ``compare``, on the estimation data.
    cost : float
        0.5 sum (y - yhat)^2 in the user's units.
    yhat, residuals : ndarray
        Simulated output and y - yhat.
    theta, std, theta_labels : ndarray, ndarray, list
        The free parameters [b_1..b_nb, f'_1..f'_(nf-integrators)] (f' are
        the coefficients of the free factor F'), their standard errors
        from sigma^2 (J'J)^-1, and their names.
    aic : dict
        With ``integrators='auto'``: AIC of each fitted number of
        integrators (None if that fit was skipped).
    nit, elapsed, success, message
        Iterations, wall time (s), whether the fit is finite, strictly
        stable in its free poles, converged and has fit > 0, and what
        happened.
    """

    def __repr__(self):
        num = np.trim_zeros(self.model.num[0][0], 'f')
        den = self.model.den[0][0]
        return '\n'.join([
            f"LinearIdentificationResult: "
            f"{'success' if self.success else 'FAILED'}",
            f"  {self.message}",
            f"  model (nb={self.nb}, nf={self.nf}, nk={self.nk}, "
            f"integrators={self.integrators}, dt={self.model.dt}):",
            f"    ({_poly_str(num)}) / ({_poly_str(den)})",
            f"  fit: {self.fit:.4f} %, cost: {self.cost:.6g}, "
            f"nit: {self.nit}, elapsed: {1e3 * self.elapsed:.1f} ms"])

    __str__ = __repr__


def _check_orders(n, nb, nf, nk, integrators):
    nb = check_int('nb', nb, minimum=1)
    nf = check_int('nf', nf, minimum=0)
    nk = check_int('nk', nk, minimum=0)
    if isinstance(integrators, str):
        if integrators != 'auto':
            raise ValueError(f"integrators must be an integer in [0, nf] or "
                             f"'auto'; got {integrators!r}")
    elif not isinstance(integrators, numbers.Integral) or isinstance(
            integrators, bool):
        raise TypeError(f"integrators must be an integer in [0, nf] or "
                        f"'auto'; got {type(integrators).__name__} "
                        f"{integrators!r}")
    elif not 0 <= integrators <= nf:
        raise ValueError(f"integrators must be an integer in [0, nf={nf}] "
                         f"or 'auto'; got {integrators}")
    need = 10 * (nb + nf) + nk
    if n < need:
        raise ValueError(
            f"u and y have N = {n} samples, too few for nb + nf = {nb + nf} "
            f"parameters and nk = {nk}: need N >= 10 (nb + nf) + nk = {need}")
    return nb, nf, nk, integrators


@serial_blas
def identify_linear(u, y=None, nb=None, nf=None, nk=1, dt=True,
                    integrators=0, max_iter=100, tol=1e-10, name=None,
                    offsets='none'):
    """Fit a linear output-error model B(q) / F(q) q^-nk (MATLAB ``oe``).

    The model is y(t) = B(q) / F(q) u(t - nk) + e(t), with
    B(q) = b1 + b2 q^-1 + ... + b_nb q^-(nb-1) and
    F(q) = 1 + f1 q^-1 + ... + f_nf q^-nf, simulated from zero initial
    conditions. The free poles are kept strictly inside the unit circle.
    The result does not depend on the units of u and y.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Input and measured output (finite, real, same length), from rest;
        or, in `u` alone, a ``control.TimeResponseData`` or a list of
        experiments, each from rest, with the cost summed (see
        `sandwichctl.tools.experiments`; give the orders by keyword).
    nb : int
        Number of B coefficients (>= 1).
    nf : int
        Number of poles (>= 0), integrators included.
    nk : int, optional
        Input delay in samples (default 1).
    dt : float or True, optional
        Sampling time of the returned model (default True: unspecified).
    integrators : int or 'auto', optional
        Number of the nf poles fixed at z = 1 (default 0). ``'auto'`` fits
        0 and 1 integrator and keeps the one with the lower AIC (the
        integrator fit is skipped when the free model has no real pole
        above 0.9).
    max_iter : int, optional
        Maximum Levenberg-Marquardt iterations (default 100).
    tol : float, optional
        Stop when the relative decrease of the cost, actual or predicted
        by the Gauss-Newton model, falls below tol (default 1e-10).
    name : str, optional
        Name of the returned TransferFunction.
    offsets : {'none', 'mean', 'estimate'}, optional
        ``'none'`` (default) uses the data as given; ``'mean'`` removes
        the means of u and y first; ``'estimate'`` fits a constant output
        offset per experiment (the model simulated from rest plus
        ``res.offsets['y']`` reproduces the fit). See `identify`.

    Returns
    -------
    LinearIdentificationResult
        ``model`` (a discrete ``control.TransferFunction`` in the user's
        units), ``B``, ``F``, ``fit``, ``cost``, ``yhat``, ``residuals``,
        ``std``, ``nit``, ``elapsed``, ``success``, ``message``, ...
        Simulate the model with ``ct.forced_response``.

    Raises
    ------
    ValueError, TypeError
        On bad arguments (the message names the argument), a constant u
        or y, too few samples (N < 10 (nb + nf) + nk), or data whose peak
        magnitude is outside 1e-100 .. 1e100 (rescale them).

    Examples
    --------
    >>> import numpy as np, control as ct
    >>> from sandwichctl.identification.linear import identify_linear
    >>> plant = ct.tf([1.5, 0], [1, 0.1, 0.2], 1)   # B = 1.5, nk = 1
    >>> u = np.random.default_rng(0).standard_normal(500)
    >>> y = ct.forced_response(plant, inputs=u).outputs
    >>> res = identify_linear(u, y, nb=1, nf=2, nk=1, dt=1)
    >>> bool(res.success), round(res.fit, 6)
    (True, 100.0)
    >>> res.model.num[0][0].round(6), res.model.den[0][0].round(6)
    (array([1.5, 0. ]), array([1. , 0.1, 0.2]))
    """
    start = time.perf_counter()
    us, ys, dt, offset_info, estimate = prepare(u, y, dt, offsets)
    check_data_scale('u', us), check_data_scale('y', ys)
    dt = check_dt('dt', dt)
    n = sum(part.size for part in us)
    nb, nf, nk, integrators = _check_orders(n, nb, nf, nk, integrators)
    max_iter = check_int('max_iter', max_iter, minimum=1)
    tol = check_positive('tol', tol)
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string or None; got "
                        f"{type(name).__name__} {name!r}")
    y = np.concatenate(ys)
    su = scale(np.concatenate(us))
    sy = scale(y)
    exact = [part / su for part in us]
    us = [scaled(part, su) for part in us]
    ys = [scaled(part, sy) for part in ys]

    out, used, aic, choice = _fit_oe_auto(us, ys, nb, nf, nk, integrators,
                                          max_iter, tol, estimate)
    if aic is not None:                 # AIC in the user's units
        aic = {k: None if v is None else v + n * np.log(sy ** 2)
               for k, v in aic.items()}

    gain = sy / su
    b = out['B'] * gain
    f = out['F']
    m = nf - used
    theta = np.concatenate([b, out['theta'][nb:]])
    std = out['std'].copy()
    std[:nb] *= gain
    # the model's output on the data as given (the fit ran on their
    # rounded scaled copy, see `_data.scaled`)
    yhat = fit_output(out, exact, nk) * sy
    resid = y - yhat
    cost = 0.5 * (resid @ resid)
    denom = np.linalg.norm(y - y.mean())
    fit = 100 * (1 - np.linalg.norm(resid) / denom)

    model = oe_transfer_function(b, f, nk, dt, name)

    finite = bool(np.all(np.isfinite(b)) and np.all(np.isfinite(f)))
    stable = _max_root(out['Ff']) < _RADIUS
    success = finite and stable and out['converged'] and fit > 0
    message = out['message'] + choice
    if out['converged'] and not fit > 0:
        message += f"; fit {fit:.3g} % <= 0"
    labels = ([f"b{j}" for j in range(1, nb + 1)]
              + [f"f'{i}" for i in range(1, m + 1)])
    return LinearIdentificationResult(
        model=model, B=b, F=f, nb=nb, nf=nf, nk=nk, integrators=used,
        fit=float(fit), cost=float(cost), yhat=yhat, residuals=resid,
        theta=theta, std=std, theta_labels=labels, aic=aic, nit=out['nit'],
        elapsed=time.perf_counter() - start, success=bool(success),
        message=message, dt=dt, scales=(float(su), float(sy)),
        offsets=dict(offset_info, y=list(out['offsets'] * sy)
                     if estimate else offset_info['y']),
        n_experiments=len(us))
