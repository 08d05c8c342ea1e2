r"""Batch output-error refinement over a whole record.

`refine` minimises the paper's objective (2.6),

.. math:: Q(\theta) = \tfrac12 \sum_k \bigl(y(k) - \hat y(k, \theta)\bigr)^2,

with :math:`\hat y` *simulated* by the model from the input alone (output
error). Unlike a predictor that feeds measured past outputs into L2,
this is unbiased under white output noise.

Units, sign and integrators
---------------------------
The fit does not depend on the data's units: u and y are divided by their
standard deviations before the fit, and the model is mapped back (the
slopes scale by sy/su, the thresholds by su). The sign of the overall
gain is taken out of the output, so the backlash slopes stay positive and
a negative gain is carried by d0 = -1 (`SandwichSystem.normalized`).
Poles of the model at z = 1 (integrators) are fixed, and only the other
poles are kept stable.

Method, and why it copes with the nonsmoothness
-----------------------------------------------
Q is piecewise smooth in theta. Its pieces are the zone sequences of
eq. (2.2), and inside a piece the exact Jacobian J comes from the
recursive sensitivities (through L1, the backlash memory and L2). At a
kink, the zone that eq. (2.2) selects gives one of the limiting
Jacobians, which is an element of Clarke's generalised Jacobian.

Each iteration is a Levenberg-Marquardt step, solved as a
box-constrained QP (piqp when a bound binds),

.. math:: \min_d \tfrac12 d^T (J^T J + \mu\,\mathrm{diag}(J^T J)) d
          - (J^T r)^T d \quad\text{s.t.}\quad m_i + d \ge m_{min},\;
          D_i + d \ge 0,

and is accepted only if Q decreases and the free poles stay stable. A
step that crosses a kink without decreasing Q is refused, and mu grows,
so the next step is shorter and stays closer to the current piece. This
is the same safeguard a proximal bundle method gets from its proximity
term, and here it comes with the Gauss-Newton curvature, which on this
objective converges in tens of iterations, not thousands. Multi-start
guards against the local minima that a nonconvex output-error cost has.
"""

import time

import numpy as np

from ._oe import Structure, lm
from ._predictor import oe_signals
from .result import IdentificationResult, backlash_significance, whiteness
from ..model.sandwich import SandwichSystem
from ._data import prepare, scale as _scale, scaled
from .._checks import (check_int, check_positive, warn, progress_bar,
                       serial_blas,
                       IdentificationWarning)

__all__ = ['refine']

#: A fit must be at least this many percent to count as explaining the data.
MIN_FIT = 5.0


def _unit_poles(den, tol=1e-9):
    """How many roots of the monic denominator 1, a1, ... sit at z = 1."""
    poly = np.r_[1.0, den]
    count = 0
    while poly.size > 1 and abs(np.polyval(poly, 1.0)) <= tol * np.sum(
            np.abs(poly)):
        poly = np.polydiv(poly, [1.0, -1.0])[0]
        count += 1
    return count


class Problem:
    """A scaled output-error problem: data, structure, sign (private).

    Holds ``u / su`` and ``sign * y / sy`` and maps reduced parameters
    phi (see `_oe.Structure`) to models and results in the user's units.
    """

    def __init__(self, u, y, orders, i1=0, i2=0, sign=1, dt=True,
                 name=None, offsets=False, inits=False):
        us = list(u) if isinstance(u, list) else [u]
        ys = list(y) if isinstance(y, list) else [y]
        self.orders = {k: orders[k] for k in ('na', 'nb', 'nc', 'nd', 'q1',
                                               'q2')}
        self.st = Structure(*(self.orders[k] for k in
                              ('na', 'nb', 'nc', 'nd', 'q1', 'q2')), i1, i2,
                            n_offsets=len(us) if offsets else 0,
                            n_inits=len(us) if inits else 0)
        self.sign = 1 if sign >= 0 else -1
        self.su = _scale(np.concatenate(us))
        self.sy = _scale(np.concatenate(ys))
        self.u_user, self.y_user = us, ys
        self.u = [scaled(part, self.su) for part in us]
        self.y = [self.sign * scaled(part, self.sy) for part in ys]
        self.n_samples = sum(part.size for part in us)
        self.dt, self.name = dt, name
        # theta_user = theta_scaled * unit: slopes sy/su, thresholds su
        im = self.st.im_theta
        self.unit = np.ones(self.st.p)
        self.unit[im:im + 2] = self.sy / self.su
        self.unit[im + 2:im + 4] = self.su

    def phi_of_model(self, model):
        """Reduced scaled parameters of a model of this structure."""
        theta = model.normalized().theta / self.unit
        return self.st.phi(theta)

    def model(self, phi):
        """The model of phi in the user's units (signed normalisation)."""
        return SandwichSystem.from_theta(
            self.st.theta(phi) * self.unit, **self.orders, dt=self.dt,
            name=self.name, sign=self.sign)

    def result(self, out, method, linear=None, extra=None, min_fit=MIN_FIT):
        """The `IdentificationResult` of an `_oe.lm` output, with verdict."""
        phi = out['phi']
        theta = self.st.theta(phi) * self.unit
        n, q = self.n_samples, self.st.size
        # residuals in the user's units, on the data as given (the search
        # ran on their rounded scaled copy, see `_data.scaled`)
        y_all = np.concatenate(self.y_user)
        r = self.sign * self.sy * self.st.residuals(
            phi, [part / self.su for part in self.u_user],
            [self.sign * part / self.sy for part in self.y_user])
        cost = 0.5 * float(r @ r)
        denom = np.linalg.norm(y_all - y_all.mean())
        fit = 100 * (1 - np.linalg.norm(r) / denom) if denom > 0 \
            else -np.inf
        J = out['J']
        sigma2 = 2 * out['cost'] / max(n - q, 1)
        std = np.full(theta.size, np.inf)
        if np.all(np.isfinite(J)):
            with np.errstate(all='ignore'):
                cov_phi = sigma2 * np.linalg.pinv(J.T @ J)
                T = self.st.T * self.unit[:, None]
                cov_model = cov_phi[:self.st.q, :self.st.q]
                std = np.sqrt(np.clip(np.diag(T @ cov_model @ T.T), 0,
                                      None))
        stable = self.st.poles_stable(phi)
        integ = {'L1': self.st.i1, 'L2': self.st.i2}
        problems = []
        if not (np.all(np.isfinite(theta)) and np.isfinite(cost)):
            problems.append("the estimate is not finite")
        elif not stable:
            problems.append("the model is unstable (a free pole on or "
                            "outside the unit circle)")
        if not out['converged']:
            problems.append("the optimiser did not converge")
        bound = self.st.zeros_at_bound(phi) if stable else []
        if bound:
            problems.append(
                f"a zero of {' and '.join(bound)} ended on the search bound "
                f"|z| = {self.st.zero_radius:.3g}: a degenerate optimum, "
                f"where a zero far outside trades against a vanishing "
                f"slope and a growing width; other orders or delays may "
                f"suit these data")
        if not fit > min_fit:
            problems.append(f"the model does not explain the data (fit "
                            f"{fit:.3g} % <= {min_fit:g} %)")
        significance = None
        if linear is not None:
            if out['cost'] > linear['cost_scaled'] * (1 + 1e-9) + 1e-300:
                problems.append(f"the fit is worse than the linear "
                                f"baseline ({fit:.3g} % < "
                                f"{linear['fit']:.3g} %)")
            n_lin = linear['n_params']
            significance = backlash_significance(
                linear['cost'], cost, n_lin, q, n)
        success = not problems
        message = out['message']
        if problems:
            message = '; '.join(problems) + f" [{message}]"
        labels = SandwichSystem.from_theta(
            theta, **self.orders).theta_labels
        res = IdentificationResult(
            model=self.model(phi), theta=theta, history=np.zeros((0,
                                                                  theta.size)),
            errors=r, counts={'iterations': out['nit']},
            success=bool(success), message=message, method=method,
            options={}, orders=dict(self.orders), theta_labels=labels,
            nit=out['nit'], std=std, fit=float(fit), cost=cost,
            integrators=integ, linear=linear, significance=significance,
            whiteness=whiteness(r), converged=bool(out['converged']),
            n_experiments=len(self.u))
        if self.st.n_off:
            res.offsets = {'method': 'estimate', 'u': [0.0] * len(self.u),
                           'y': list(self.sign * self.sy * phi[
                               self.st.q:self.st.q + self.st.n_off])}
        if self.st.n_inits:
            res.initial_conditions = [
                {'x_past': self.su * x, 'v_past': self.sy * v,
                 'y_past': self.sign * self.sy * yy}
                for x, v, yy in (self.st.init(phi, e)
                                 for e in range(self.st.n_inits))]
        res.crossing = self._crossing(phi, res.model.backlash)
        if extra:
            res.update(extra)
        return res

    def _crossing(self, phi, backlash):
        """Where the model's slope lines cross (`Backlash.crossing`, in
        u's units; None if m1 == m2) and the share of the samples its x
        spends beyond: {'x': ..., 'share': ...}."""
        cross = backlash.crossing
        if cross is None:
            return {'x': None, 'share': 0.0}
        theta = self.st.theta(phi)
        with np.errstate(all='ignore'):
            x = self.su * np.concatenate([
                oe_signals(theta, self.st.o, uu, self.st.init(phi, e))[1]
                for e, uu in enumerate(self.u)])
            beyond = x < cross if backlash.m1 < backlash.m2 else x > cross
        return {'x': float(cross), 'share': float(np.mean(beyond))}


def _perturb(st, phi, rng, spread, m_min):
    """A random admissible start near phi (multi-start)."""
    im = st.im
    for _ in range(100):
        trial = phi.copy()
        lin = np.r_[0:im, im + 4:phi.size]
        trial[lin] += spread * rng.standard_normal(lin.size) * (
            np.abs(phi[lin]) + 0.1)
        trial[im:im + 4] *= np.exp(spread * rng.standard_normal(4))
        trial[im + 2:im + 4] += 1e-3
        trial = st.clip(trial, m_min)
        if st.stable(trial):
            return trial
    return phi.copy()


def _admissible_start(st, phi, m_min):
    """Move a start into the domain: slopes >= m_min, D >= 0, and unstable
    free denominators pulled inside the unit circle (roots scaled by 0.9
    until stable)."""
    phi = phi.copy()
    phi[~np.isfinite(phi)] = 0.0
    phi = st.clip(phi, max(m_min, 1e-3 * max(phi[st.im], phi[st.im + 1],
                                             1e-300)))
    for start, n in ((0, st.nc_free), (st.nc_free, st.na_free)):
        powers = 0.9 ** np.arange(1, n + 1)
        for _ in range(200):
            if st.poles_stable(phi):
                break
            phi[start:start + n] *= powers
    return phi


@serial_blas
def refine(model, u, y=None, max_iter=100, tol=1e-10, n_starts=1,
           spread=0.3, seed=None, m_min=1e-9, progress=False,
           offsets='none'):
    r"""Refine a sandwich model on a whole record by output-error LM.

    Parameters
    ----------
    model : SandwichSystem
        Initial model (e.g. ``identify(...).model``); its orders, delays,
        integrators (poles exactly at z = 1) and the sign of its gain are
        kept.
    u, y : array_like, shape (N,)
        Input and measured output, from zero initial state; or, in `u`
        alone, a ``control.TimeResponseData`` or a list of experiments
        (see `identify`).
    max_iter : int, optional
        Maximum Levenberg-Marquardt iterations per start (default 100).
    tol : float, optional
        Stop when the relative decrease of the cost, or the relative
        step, falls below tol.
    n_starts : int, optional
        Number of starts: the model itself plus ``n_starts - 1`` random
        perturbations of it (default 1). The best final cost wins.
    spread : float, optional
        Relative size of the multi-start perturbations (default 0.3).
    seed : int or numpy.random.Generator, optional
        Seed of the perturbations.
    m_min : float, optional
        Lower bound on the slopes m1, m2, relative to the scaled data.
    progress : bool, optional
        Show a progress bar over the starts.
    offsets : {'none', 'mean', 'estimate'}, optional
        As in `identify` (default 'none').

    Returns
    -------
    IdentificationResult
        ``model`` (in the data's units), ``theta``, ``errors`` (final
        residuals), ``std`` (standard errors from sigma^2 (J'J)^-1),
        ``fit`` (percent, as MATLAB's ``compare``), ``cost``, ``success``
        and ``message``.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(3000, seed=0)
    >>> y = plant.simulate(u).outputs
    >>> start = sw.SandwichSystem.from_theta(plant.theta * 1.05,
    ...                                      **plant.orders)
    >>> res = sw.refine(start, u, y)
    >>> bool(sw.parameter_error(res.theta, plant.theta) < 1e-6)
    True
    """
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"model must be a SandwichSystem; got "
                        f"{type(model).__name__}")
    us, ys, _, offset_info, estimate = prepare(u, y, model.dt, offsets)
    max_iter = check_int('max_iter', max_iter, minimum=1)
    n_starts = check_int('n_starts', n_starts, minimum=1)
    tol = check_positive('tol', tol)
    spread = check_positive('spread', spread)
    m_min = check_positive('m_min', m_min)
    norm = model.normalized()
    co = norm.coefficients
    prob = Problem(us, ys, norm.orders, _unit_poles(co['a']),
                   _unit_poles(co['c']), norm.gain_sign, dt=model.dt,
                   name=model.name, offsets=estimate)
    st = prob.st
    if prob.n_samples <= 2 * st.size:
        raise ValueError(f"the data have {prob.n_samples} samples, too few "
                         f"for {st.size} parameters")
    phi0 = _admissible_start(st, prob.phi_of_model(norm), m_min)
    st.widen_zero_radius(phi0)
    rng = np.random.default_rng(seed)
    start = time.perf_counter()
    best = None
    for i in _progress_range(n_starts, progress, 'refine'):
        phi = phi0 if i == 0 else _perturb(st, phi0, rng, spread, m_min)
        out = lm(st, phi, prob.u, prob.y, max_iter, tol, m_min)
        if best is None or out['cost'] < best['cost']:
            best = out
    res = prob.result(best, 'refine', extra={
        'theta0': st.theta(phi0) * prob.unit,
        'elapsed': time.perf_counter() - start,
        'options': dict(max_iter=max_iter, tol=tol, n_starts=n_starts,
                        spread=spread, m_min=m_min)})
    res.counts['starts'] = n_starts
    res.offsets = dict(offset_info, **(res.get('offsets') or {}))
    _warn_poorly_determined(res)
    return res


def _warn_poorly_determined(res):
    """Warn (and say in the message) when standard errors exceed 50%."""
    ill = ~np.isfinite(res.std) | (res.std > 0.5 * np.maximum(
        np.abs(res.theta), 1e-3))
    if np.any(ill):
        names = [n for n, bad in zip(res.theta_labels, ill) if bad]
        res.message += (f"; parameters poorly determined by these data "
                        f"(standard error > 50%): {names}")
        warn(f"{names} are poorly determined by the data (excitation too "
             f"small or orders too high?)", IdentificationWarning)


def _progress_range(n, progress, desc, step=1):
    """range(0, n, step), with a tqdm bar (notebook widget in Jupyter,
    text in a terminal) when asked for."""
    steps = range(0, n, step)
    if not progress:
        return steps
    return progress_bar(True, iterable=steps, desc=desc, leave=False)
