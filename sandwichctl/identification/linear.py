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
   damping grows. It stops at ``tol``, or once it has converged to the
   data's precision: its last 10 steps lowered the cost by at most a
   tenth of p / N of it and the Gauss-Newton step predicts at most p / N
   more (p parameters, N samples; p / N of the cost is what one standard
   error of the parameters is worth), where an integrated input made it
   crawl along a curved valley for hundreds of iterations at a fit equal
   to four decimals.

The core on already scaled arrays is ``_linear.fit_oe``; the sandwich
pipeline reuses it.
"""

import numbers
import time

import numpy as np
import control as ct
from scipy.optimize import OptimizeResult

from ._data import (excitation_order, input_offset, input_order_text,
                    prepare, scale, scaled, with_shift)
from ._linear import fit_oe_auto, fit_output, max_root, RADIUS
from .result import (INPUT_OFFSET, MIN_FIT, IdentificationResult,
                     input_offset_text)
from .._checks import (check_int, check_positive, check_tolerance, check_dt,
                       serial_blas)
from .._checks import MOST_ROUNDS, check_data_scale

__all__ = ['identify_linear', 'LinearIdentificationResult']


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
        stable in its free poles, converged and has a fit above
        ``MIN_FIT`` (5 %, the bar of `identify`), and what happened.
    """

    copy = IdentificationResult.copy

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


def _verdict(out, b, f, fit, choice, us, *, free):
    """(success, message) of a linear fit `out` with coefficients b, f in
    the user's units, its `fit`, the sentence of the integrator `choice`,
    the input experiments `us` (their `input_offset`, and how many
    coefficients they can determine, `excitation_order`, against the
    model's `free` ones)."""
    finite = bool(np.all(np.isfinite(b)) and np.all(np.isfinite(f)))
    stable = max_root(out['Ff']) < RADIUS
    offset = input_offset(us)
    got = excitation_order(us, free)
    success = (finite and stable and out['converged'] and fit > MIN_FIT
               and not offset > INPUT_OFFSET and got >= free)
    message = out['message'] + choice
    if out['converged'] and not fit > MIN_FIT:
        message += (f"; fit {fit:.3g} % <= {MIN_FIT:g} %: the model "
                    f"explains next to nothing of y")
    if got < free:
        message = (input_order_text(got, free, 'the model') +
                   f" [{message}]")
    if offset > INPUT_OFFSET:
        message = input_offset_text(offset) + f" [{message}]"
    return success, message


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
        above 0.9), except an integrator that a real zero of the fit
        nearly cancels (closer to z = 1 than a tenth of the distance from
        1 to the slowest other pole; beyond 1, where it turns the
        low-frequency sign, than that whole distance): a drift term, not
        an integrator, and the message says so.
    max_iter : int, optional
        Maximum Levenberg-Marquardt iterations (default 100).
    tol : float, optional
        Stop when the relative decrease of the cost, actual or predicted
        by the Gauss-Newton model, falls below tol (0 < tol < 1, default
        1e-10), or once the fit has converged to the data's precision
        (step 4 above; the message says which).
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
    max_iter = check_int('max_iter', max_iter, 1, MOST_ROUNDS)
    tol = check_tolerance('tol', tol)
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string or None; got "
                        f"{type(name).__name__} {name!r}")
    y = np.concatenate(ys)
    su = scale(np.concatenate(us))
    sy = scale(y)
    exact = [part / su for part in us]
    us = [scaled(part, su) for part in us]
    ys = [scaled(part, sy) for part in ys]

    out, used, aic, choice = fit_oe_auto(us, ys, (nb, nf, nk), integrators,
                                         max_iter=max_iter, tol=tol,
                                         offsets=estimate)
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
    if estimate:            # back to the user's output (`prepare`)
        yhat = yhat + np.concatenate([np.full(part.size, c) for part, c
                                      in zip(ys, offset_info['y'])])
    cost = 0.5 * (resid @ resid)
    denom = np.linalg.norm(y - y.mean())
    fit = 100 * (1 - np.linalg.norm(resid) / denom)

    model = oe_transfer_function(b, f, nk, dt, name)

    success, message = _verdict(out, b, f, fit, choice, exact, free=nb + m)
    labels = ([f"b{j}" for j in range(1, nb + 1)]
              + [f"f'{i}" for i in range(1, m + 1)])
    return LinearIdentificationResult(
        model=model, B=b, F=f, nb=nb, nf=nf, nk=nk, integrators=used,
        fit=float(fit), cost=float(cost), yhat=yhat, residuals=resid,
        theta=theta, std=std, theta_labels=labels, aic=aic, nit=out['nit'],
        elapsed=time.perf_counter() - start, success=bool(success),
        message=message, dt=dt, scales=(float(su), float(sy)),
        offsets=with_shift(offset_info, out['offsets'] * sy),
        n_experiments=len(us))
