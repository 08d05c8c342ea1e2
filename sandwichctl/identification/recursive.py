r"""Recursive identification of sandwich systems (Section 3 of the paper).

`RecursiveIdentifier` is a streaming estimator of the normalised
parameter vector of eq. (2.5): ``update(u_k, y_k)`` takes one sample at a
time. `identify` runs it over a whole record.

Methods
-------
``'bundle'``
    The paper's nonsmooth recursive gradient identifier: Clarke
    subgradients (3.2)-(3.3), a bundle of at most ``k1`` subgradients with
    locality measures, the direction QP (3.4) solved with piqp, phi of
    (3.6), the line search (3.7)-(3.10) with long, short and null steps,
    and the stopping test ``phi >= -delta``.
``'gradient'``
    The traditional gradient method the paper compares against:
    theta(k+1) = theta(k) + mu e(k) w(k) with step ``mu`` (0.009 in
    Section 5). The paper "omits" the nonsmooth points; option
    ``nonsmooth`` chooses the reading: ``'skip'`` (default) skips the
    update at every sample whose predictor window switches zone, and
    ``'subgradient'`` updates there too, with the Clarke subgradient of
    the zone eq. (2.2) selects.

The interpretations of the places where the paper is loose are listed in
``docs/algorithm.md``; each is an option named after the paper's symbol.
"""

import dataclasses

import numpy as np

from ._predictor import padding, stable_and_finite, _idx
from ._recursive import (one_qp_warning, bundle_run, gradient_run,
                         rpem_run, LONG, SHORT, NULL, STOP, SKIP,
                         SUBGRADIENT, RPEM_OK, RPEM_LIMITED, RPEM_REJECTED,
                         RPEM_RESET)
from ._options import OPTIONS, RECURSIVE, method_options
from .result import IdentificationResult, judge, verdict
from ..model.sandwich import SandwichSystem, theta_labels
from .._checks import (warn, IdentificationWarning, check_dt, check_order,
                       check_bool, check_data_scale, check_signal,
                       check_vector, check_finite, check_nonnegative)

__all__ = ['RecursiveIdentifier']


_KIND_NAMES = {LONG: 'long', SHORT: 'short', NULL: 'null', STOP: 'stop',
               SKIP: 'skip', SUBGRADIENT: 'subgradient',
               RPEM_LIMITED: 'limited',
               RPEM_REJECTED: 'rejected', RPEM_RESET: 'reset', RPEM_OK: 'ok'}

_KINDS_OF = {'bundle': ('long', 'short', 'null', 'stop'),
             'gradient': ('long', 'skip'),
             'gradient/subgradient': ('long', 'subgradient'),
             'rpem': ('ok', 'limited', 'rejected', 'reset')}

#: Default options of each recursive method (paper symbols where defined;
#: `_options` checks and documents them).
DEFAULTS = {method: {f.name: f.default for f in
                     dataclasses.fields(OPTIONS[method])}
            for method in RECURSIVE}

_CHUNK = 4096


def _check_options(method, options):
    """The checked options of a recursive method, as a dict."""
    if method not in RECURSIVE:
        raise ValueError(f"method must be one of {sorted(DEFAULTS)}; got "
                         f"{method!r}")
    return method_options(method, options).as_dict()


class RecursiveIdentifier:
    r"""Streaming estimator of a sandwich system, one sample at a time.

    Parameters
    ----------
    na, nb, nc, nd : int
        Orders of eq. (2.1) (nb and nd count the coefficients after
        b0 = d0 = 1).
    q1, q2 : int, optional
        Known delays of L1 and L2 (default 1).
    method : {'bundle', 'gradient', 'rpem'}, optional
        The paper's bundle method (default), the traditional gradient
        method, or the recursive prediction-error method; see the module
        documentation.
    theta0 : array_like, optional
        Starting point in the order of eq. (2.5). Default: zeros for the
        linear coefficients and 0.1 for m1, m2, D1, D2 (as in Section 5).
    dt : float or True, optional
        Sampling time of the identified model.
    keep_history : bool, optional
        Keep theta(k), e(k) and the step kind of every sample (default
        True; turn off for unbounded online use).
    **options
        Method options. ``'bundle'``: eta0 (0.015), k1 (6), delta (1e-4),
        q (0.1), q_star (0.5), gamma (0.5), eta_max (None: = eta0), rho
        (0.5), n_ls (10), step_bound (False: True caps eta by Theorem
        4.1's bound (4.1)-(4.2)), full_step_test (False: True makes a
        long step also require eq. (3.9) read literally, f(k, theta + t)
        < f(k, theta)), predictor ('series-parallel'), m_min (1e-6),
        divergence_limit (1e6).
        ``'gradient'``: mu (0.009), nonsmooth ('skip' or 'subgradient',
        default 'skip'; the older ``skip_nonsmooth=True/False`` means the
        same), predictor, m_min, divergence_limit. See
        ``docs/algorithm.md`` and ``docs/reproduction.md``.
        ``'rpem'``: lam0 (0.99), lam_start (0.95), P0 (10), p_max (1e6),
        max_step (0.5), warmup (0), m_min, err_limit (1e6),
        divergence_limit.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(500, seed=0)
    >>> y = plant.simulate(u).outputs
    >>> est = sw.RecursiveIdentifier(**plant.orders)
    >>> for uk, yk in zip(u, y):
    ...     e = est.update(uk, yk)
    >>> est.theta.shape
    (9,)

    The gradient baseline under its two readings of "the nonsmooth points
    are omitted": ``'skip'`` leaves the estimate unchanged at a nonsmooth
    sample, ``'subgradient'`` updates there with a Clarke subgradient; the
    counts say how often each happened.

    >>> skip = sw.RecursiveIdentifier(**plant.orders, method='gradient')
    >>> sub = sw.RecursiveIdentifier(**plant.orders, method='gradient',
    ...                              nonsmooth='subgradient')
    >>> _ = skip.update_many(u, y), sub.update_many(u, y)
    >>> sorted(skip.result().counts), sorted(sub.result().counts)
    (['long', 'skip'], ['long', 'subgradient'])
    >>> skipped = skip.result().counts['skip']
    >>> subgradient = sub.result().counts['subgradient']
    >>> skipped > 0, subgradient > 0
    (True, True)
    """

    def __init__(self, na, nb, nc, nd, q1=1, q2=1, method='bundle',
                 theta0=None, dt=True, keep_history=True, **options):
        self.orders = {k: check_order(k, v) for k, v in
                       zip(('na', 'nb', 'nc', 'nd', 'q1', 'q2'),
                           (na, nb, nc, nd, q1, q2))}
        self._o = tuple(self.orders[k] for k in
                        ('na', 'nb', 'nc', 'nd', 'q1', 'q2'))
        self.method = method
        self.options = _check_options(method, options)
        self.dt = check_dt('dt', dt)
        self.labels = theta_labels(na, nb, nc, nd)
        theta0 = self._checked_start(theta0)
        self.keep_history = check_bool('keep_history', keep_history)
        self._pad = padding(self._o)
        self._theta0_construction = theta0.copy()
        self._start(theta0)

    def reset(self, theta0=None):
        """Start again, with no sample seen.

        The orders, method, options, `dt` and `keep_history` stay; the
        estimate, its history, the step counts and the method's own state
        (the bundle, the covariance) start afresh, as in a new estimator
        of the same arguments. A diverged estimate is restarted this way.

        Parameters
        ----------
        theta0 : array_like, optional
            The start of this run, in the order of eq. (2.5). Default: the
            start given at construction, also after an earlier
            ``reset(theta0=...)``.

        Raises
        ------
        TypeError, ValueError
            If `theta0` is not a finite vector of the parameters' length
            with m1, m2 > 0 and D1, D2 >= 0; the estimator is then left as
            it was.

        Examples
        --------
        >>> import sandwichctl as sw
        >>> est = sw.RecursiveIdentifier(na=1, nb=0, nc=1, nd=0)
        >>> _ = est.update(1.0, 0.5)
        >>> est.reset(theta0=[0.5, -0.5, 1.0, 1.0, 0.0, 0.0])
        >>> est.n_samples, est.theta
        (0, array([ 0.5, -0.5,  1. ,  1. ,  0. ,  0. ]))
        >>> est.reset()                     # the start given at construction
        >>> est.n_samples, est.theta
        (0, array([0. , 0. , 0.1, 0.1, 0.1, 0.1]))
        """
        if theta0 is None:
            # one pickled by an older version has no _theta0_construction:
            # its theta0, the start it was made with (unless an older
            # reset(theta0=...) moved it)
            theta0 = getattr(self, '_theta0_construction', self.theta0)
        self._start(self._checked_start(theta0))

    def _checked_start(self, theta0):
        """`theta0` checked (a new array), or the default start for None:
        zeros for the linear coefficients and 0.1 for m1, m2, D1, D2."""
        na, nc = self.orders['na'], self.orders['nc']
        im = nc + na
        if theta0 is None:
            theta0 = np.zeros(len(self.labels))
            theta0[im:im + 4] = 0.1
        if getattr(theta0, 'sign', 1) < 0:
            raise ValueError(
                "theta0 is the theta of a negative-gain model (sign=-1), "
                "which the recursive methods cannot carry (b0 = d0 = 1 "
                "and m1, m2 > 0): identify -y from the theta of the model "
                "with L2 negated, or use sw.identify, which fits signed "
                "gains")
        theta0 = check_vector('theta0', theta0, len(self.labels))
        if np.any(theta0[im:im + 2] <= 0) or np.any(theta0[im + 2:im + 4] < 0):
            raise ValueError(
                f"theta0 must have m1, m2 > 0 and D1, D2 >= 0 (entries "
                f"{im}..{im + 3}); got {theta0[im:im + 4]}")
        return theta0

    def _start(self, theta0):
        """The state of a run from the checked `theta0`, no sample seen:
        buffers, counts, history and the method's own state."""
        p = theta0.size
        self.theta0 = theta0
        self._theta = theta0.copy()
        cap = self._pad + _CHUNK
        self._u, self._y = np.zeros(cap), np.zeros(cap)
        self._xs, self._vs, self._ys = np.zeros(cap), np.zeros(cap), \
            np.zeros(cap)
        self._zs = np.zeros(cap, dtype=np.int64)
        self._pos = self._pad
        self._grad = np.zeros(p)
        self.n_samples = 0
        self.counts = {name: 0 for name in _KIND_NAMES.values()}
        self.diverged_at = None
        self._hist, self._err, self._kind = [], [], []
        # per-chunk outputs of the compiled recursions (gradient, rpem)
        self._buf = (np.zeros((cap, p)), np.zeros(cap),
                     np.zeros(cap, dtype=np.int64))
        if self.method == 'rpem':
            self._S = [np.zeros((cap, p)) for _ in range(3)]
            self._P = self.options['P0'] * np.eye(p)
            self._lam = np.array([self.options['lam_start']])
            self._rwork = [np.zeros(p) for _ in range(4)]
        if self.method == 'bundle':
            k1 = self.options['k1']
            self._trials = np.zeros((max(k1 - 1, 1), p))
            self._s = np.zeros(max(k1 - 1, 1))
            self._ntrial = 0
            self._H = np.zeros((k1, p))
            self._beta = np.zeros(k1)
            self._weights = np.zeros(k1)
            self._work = [np.zeros(p) for _ in range(3)]

    @property
    def _kinds_key(self):
        if (self.method == 'gradient'
                and self.options['nonsmooth'] == 'subgradient'):
            return 'gradient/subgradient'
        return self.method

    @property
    def theta(self):
        """Current estimate (copy), in the order of eq. (2.5)."""
        return self._theta.copy()

    @property
    def model(self):
        """Current estimate as a normalised `SandwichSystem`."""
        return SandwichSystem.from_theta(self._theta, **self.orders,
                                         dt=self.dt)

    # ------------------------------------------------------------------
    def update(self, u_k, y_k):
        """Process one sample; return the a-priori prediction error e(k).

        Raises
        ------
        RuntimeError
            If the estimate has diverged earlier (see `diverged_at`).
        """
        u_k = check_finite('u_k', u_k)
        y_k = check_finite('y_k', y_k)
        # one sample tells no scale: only a value that overflows is refused
        # (the record's lower bound refused 1e-150 but took 0)
        check_data_scale('u_k', u_k, low=False)
        check_data_scale('y_k', y_k, low=False)
        return float(self._process(np.array([u_k]), np.array([y_k]))[0])

    def update_many(self, u, y):
        """Process a block of samples; return their prediction errors."""
        u = check_signal('u', u)
        y = check_signal('y', y, length=u.size)
        check_data_scale('u', u)
        check_data_scale('y', y)
        return self._process(u, y)

    def _process(self, u, y):
        """`update_many` on checked samples."""
        if self.diverged_at is not None:
            raise RuntimeError(
                f"the estimate diverged at sample {self.diverged_at}; "
                f"reset() it, or create a new estimator (smaller eta0/mu, "
                f"or another theta0)")
        errors = np.empty(u.size)
        done = 0
        with one_qp_warning():
            while done < u.size:
                room = self._u.size - self._pos
                if room == 0:
                    self._shift()
                    room = self._u.size - self._pos
                m = min(room, u.size - done)
                sl = slice(self._pos, self._pos + m)
                self._u[sl] = u[done:done + m]
                self._y[sl] = y[done:done + m]
                got = self._run(self._pos, self._pos + m,
                                errors[done:done + m])
                self._pos += got
                self.n_samples += got
                done += got
                if got < m:
                    errors[done:] = np.nan
                    break
        return errors

    def _shift(self):
        pad = self._pad
        arrays = [self._u, self._y, self._xs, self._vs, self._ys, self._zs]
        if self.method == 'rpem':
            arrays += self._S
        for arr in arrays:
            arr[:pad] = arr[self._pos - pad:self._pos]
        self._pos = pad

    def _record_block(self, hist, err, kinds):
        """Count the step kinds of consecutive samples and, with
        `keep_history`, keep their estimates (rows of `hist`), errors and
        kinds."""
        for kind, count in zip(*np.unique(kinds, return_counts=True)):
            self.counts[_KIND_NAMES[kind]] += int(count)
        if self.keep_history:
            self._hist.extend(hist.copy())
            self._err.extend(err.tolist())
            self._kind.extend(kinds.tolist())

    def _flag_divergence(self, k_abs):
        self.diverged_at = k_abs
        warn(f"{self.method} estimate diverged at sample {k_abs} (non-finite "
             f"or |theta| > {self.options['divergence_limit']:g}); stopped "
             f"and kept the last finite estimate", IdentificationWarning)

    def _run(self, k0, k1, errors):
        """Process buffer positions k0..k1-1; return how many were done."""
        if self.method == 'gradient':
            return self._run_gradient(k0, k1, errors)
        if self.method == 'rpem':
            return self._run_rpem(k0, k1, errors)
        return self._run_bundle(k0, k1, errors)

    def _run_rpem(self, k0, k1, errors):
        opt = self.options
        hist, err, kinds = self._buf
        theta = self._theta.copy()
        rpem_run(theta, self._P, self._o, self._u, self._y, self._xs,
                 self._vs, self._zs, self._ys, *self._S, k0, k1,
                 self.n_samples, opt['warmup'], self._lam, opt['lam0'],
                 opt['P0'], opt['p_max'], opt['max_step'], opt['m_min'],
                 opt['err_limit'], hist, err, kinds, *self._rwork)
        self._record_block(hist[k0:k1], err[k0:k1], kinds[k0:k1])
        errors[:] = err[k0:k1]
        self._theta = theta
        return k1 - k0

    def _run_gradient(self, k0, k1, errors):
        opt = self.options
        hist, err, kinds = self._buf
        theta = self._theta.copy()
        bad = gradient_run(
            theta, self._o, self._u, self._y,
            opt['predictor'] == 'series-parallel', self._xs, self._vs,
            self._zs, self._ys, k0, k1, opt['mu'], opt['skip_nonsmooth'],
            opt['m_min'], hist, err, kinds, self._grad)
        too_big = np.flatnonzero(
            np.max(np.abs(hist[k0:k1]), axis=1) > opt['divergence_limit'])
        stop = k1 if bad < 0 else bad
        if too_big.size and k0 + too_big[0] < stop:
            stop = k0 + too_big[0]
        done = stop - k0
        self._record_block(hist[k0:stop], err[k0:stop], kinds[k0:stop])
        errors[:done] = err[k0:stop]
        if stop < k1:
            self._theta = hist[stop - 1].copy() if stop > k0 else self._theta
            self._flag_divergence(self.n_samples + done)
        else:
            self._theta = theta
        return done

    def _run_bundle(self, k0, k1, errors):
        opt = self.options
        ystar = self._y if opt['predictor'] == 'series-parallel' else self._ys
        hist, err, kinds = self._buf
        stop, self._ntrial = bundle_run(
            self._theta, self._trials, self._ntrial, self._s, self._o,
            self._u, ystar, self._y, self._xs, self._vs, self._zs, self._ys,
            k0, k1, self.n_samples, opt['eta0'], opt['eta_max'], opt['rho'],
            opt['n_ls'], opt['q'], opt['q_star'], opt['gamma'],
            opt['delta'], opt['step_bound'], opt['m_min'],
            opt['full_step_test'], opt['divergence_limit'], self._H,
            self._beta, self._weights, self._grad, *self._work, hist, err,
            kinds)
        done = stop - k0
        self._record_block(hist[k0:stop], err[k0:stop], kinds[k0:stop])
        errors[:done] = err[k0:stop]
        if stop < k1:
            self._flag_divergence(self.n_samples + done)
        return done

    # ------------------------------------------------------------------
    def result(self, elapsed=None):
        """The `IdentificationResult` for the samples processed so far.

        ``success`` says that samples were processed without divergence,
        learning (not most of them covariance resets or null steps), with
        neither slope on its bound m_min (a degenerate estimate, as of
        data with a negative gain), and the estimate is finite with both
        blocks stable; it cannot
        compare the model with a linear baseline, as ``sw.identify(...,
        method=...)`` does on a whole record.

        Parameters
        ----------
        elapsed : float or None, optional
            Seconds the identification took, stored as the result's
            ``elapsed`` (default None: not measured).

        Returns
        -------
        IdentificationResult

        Raises
        ------
        TypeError
            If `elapsed` is neither None nor a real number.
        ValueError
            If `elapsed` is negative, NaN or infinite.
        """
        if elapsed is not None:
            elapsed = check_nonnegative('elapsed', elapsed)
        p = self._theta.size
        hist = (np.array(self._hist) if self._hist else np.zeros((0, p)))
        success = self.diverged_at is None and self.n_samples > 0
        resets = self.counts.get('reset', 0)
        if self.diverged_at is not None:
            message = (f"diverged at sample {self.diverged_at}; the model "
                       f"is the last finite estimate")
        elif self.n_samples == 0:
            message = "no samples processed yet: the model is theta0"
        elif success and resets > self.n_samples / 2:
            success = False         # the covariance never held: no learning
            message = (f"processed {self.n_samples} samples, {resets} of "
                       f"them resets of the covariance (its trace "
                       f"overflowed): the estimate did not learn; scale u "
                       f"and y towards order 1 (other units)")
        elif success and self.counts.get('null', 0) > self.n_samples / 2:
            success = False         # the line search found no descent
            message = (f"processed {self.n_samples} samples, "
                       f"{self.counts['null']} of them null steps (the "
                       f"line search found no descent): the estimate "
                       f"hardly left theta0; scale u and y towards order 1 "
                       f"(other units), or try another eta0 or theta0")
        elif success and np.any(self._theta[_idx(self._o)[1]:][:2]
                                <= self.options['m_min']):
            success = False         # a slope pressed on its bound
            message = (f"processed {self.n_samples} samples, and a slope "
                       f"ended on its bound m_min = "
                       f"{self.options['m_min']:g}: a degenerate estimate; "
                       f"the data's gain may be negative, which b0 = d0 = "
                       f"1 with m1, m2 > 0 cannot carry (identify -y, or "
                       f"use sw.identify, which fits signed gains)")
        elif success:
            message = f"processed {self.n_samples} samples"
        res = IdentificationResult(
            model=self.model, theta=self.theta, history=hist,
            errors=np.array(self._err), kinds=np.array(self._kind, int),
            counts={k: v for k, v in self.counts.items()
                    if k in _KINDS_OF[self._kinds_key]},
            success=success, message=message,
            method=self.method, options=dict(self.options),
            orders=dict(self.orders), theta_labels=list(self.labels),
            theta0=self.theta0.copy(), nit=self.n_samples, elapsed=elapsed)
        if self.n_samples:
            judge(res, verdict(estimate=stable_and_finite(self._theta,
                                                          self._o)))
        return res
