"""The result of every identifier, recursive or batch.

`IdentificationResult` is a `scipy.optimize.OptimizeResult` with the
identified `SandwichSystem` in ``model``. The recursive estimators
(`RecursiveIdentifier`), the batch refinement (`refine`) and the
`identify` pipeline all return it, so they import it from here, and they
all judge it here: `verdict` lists the checks a model fails and `judge`
writes them into ``success``, ``message`` and warnings.
"""

from typing import NamedTuple

import numpy as np
from scipy import stats
from scipy.optimize import OptimizeResult

from .._checks import (_real_array, check_reference, check_vector, warn,
                       ExcitationWarning, IdentificationWarning)
from ..model._coefficients import signed_theta
from ..tools.validation import scaled_norm
from ._data import input_order_text

__all__ = ['IdentificationResult', 'parameter_error']

#: `print(res)` mentions the crossing of the slope lines when the model's
#: x spends at least this share of the samples beyond it.
CROSSING_NOTE = 0.1
#: A fit must be at least this many percent to count as explaining the data.
MIN_FIT = 5.0
#: Costs (on the scaled data: about half the samples' count for a model
#: that explains nothing) closer than this are equal: a model that fits
#: exactly is not worse than a linear one that does too.
EQUAL_COST = 1e-16
#: A parameter is poorly determined when its standard error exceeds this
#: share of its size (at least 1e-3).
POORLY_DETERMINED = 0.5
#: The data excite the backlash when the model's backlash is outside its
#: memory zone in at least this share of the samples.
MIN_EXCITATION = 0.01
#: An experiment whose input starts more than this many of its standard
#: deviations from zero starts the model (from rest at u = 0) with a step
#: far larger than the excitation, which the plant never had: the record
#: sits at an operating point.
INPUT_OFFSET = 20.0


class Failure(NamedTuple):
    """A failed check of `verdict`: its name, the sentence that says so,
    and whether it fails the identification (else it only warns)."""
    check: str
    text: str
    fatal: bool


def verdict(*, finite=None, stable=None, estimate=None, converged=None,
            zeros_at_bound=(), zero_radius=None, fit=None, min_fit=MIN_FIT,
            linear=None, cost_scaled=None, method='oe', std=None, theta=None,
            labels=(), excitation=None, minimum_phase_bound=None,
            input_offset=None, input_order=None, backlash_moves=None):
    """The checks an identified model fails, in the order they are told.

    Every argument is one fact about the model; a fact left at None is
    not checked. An empty list is a success.

    Parameters
    ----------
    finite, stable : bool
        Batch methods: the estimate and its cost are finite; the free
        poles are strictly stable (checked only when finite).
    estimate : bool
        Recursive methods: the estimate is finite and stable.
    converged : bool
        The optimiser converged.
    zeros_at_bound : sequence of str, zero_radius : float
        Blocks with a zero on the search bound |z| = zero_radius.
    fit, min_fit : float
        The fit (percent) must exceed min_fit (None: checked already, the
        fit is only told).
    linear : dict, cost_scaled : float, method : str
        The linear baseline (``fit``, ``cost_scaled``); the model's cost on
        the same scaled data must not exceed its cost. A model of another
        method than ``'oe'`` that fails is told that 'oe' starts from the
        baseline. A baseline with ``'held'`` (the structure cannot hold
        it) adds its note to the failure.
    std, theta, labels
        Standard errors: above `POORLY_DETERMINED` of |theta| a parameter
        is poorly determined (not fatal).
    excitation : float
        Share of the samples the backlash is outside its memory zone:
        below `MIN_EXCITATION` the data hardly excite it (not fatal).
    minimum_phase_bound : float
        With a minimum-phase L1, the bound a zero of L1 ended on (not
        fatal: told in the message).
    input_offset : float
        The largest |u[0]| / std(u) of the experiments: above
        `INPUT_OFFSET` the record starts at an operating point.
    input_order : tuple
        (got, need, what): the input can determine `got` coefficients
        (`_data.excitation_order`: the taps of the shortest recurrence it
        satisfies) where the block `what` has `need`; fewer than need do
        not determine them.
    backlash_moves : tuple
        (count, need): the model's backlash is outside its memory zone in
        `count` samples, and only those tell the `need` parameters of L1
        and the backlash (m1, m2, D1, D2 and L1's free coefficients);
        fewer do not determine them, however well the model fits (an
        impulse through a sandwich: three samples).

    Returns
    -------
    list of Failure
    """
    failed = []

    def fail(check, text, fatal=True):
        failed.append(Failure(check, text, fatal))

    if finite is False:
        fail('finite', "the estimate is not finite")
    elif stable is False:
        fail('stable', "the model is unstable (a free pole on or outside "
                       "the unit circle)")
    if estimate is False:
        fail('estimate', "the estimate is unstable or not finite (a pole "
                         "of L1 or L2 on or outside the unit circle)")
    if converged is False:
        fail('converged', "the optimiser did not converge (a larger "
                          "max_iter lets it run on)")
    if zeros_at_bound:
        fail('zeros', f"a zero of {' and '.join(zeros_at_bound)} ended on "
                      f"the search bound |z| = {zero_radius:.3g}: a "
                      f"degenerate optimum, where a zero far outside trades "
                      f"against a vanishing slope and a growing width; "
                      f"other orders or delays may suit these data")
    if fit is not None and min_fit is not None and not fit > min_fit:
        fail('fit', f"the model does not explain the data (fit {fit:.3g} % "
                    f"<= {min_fit:g} %)")
    if linear is not None and \
            cost_scaled > linear['cost_scaled'] * (1 + 1e-9) + EQUAL_COST:
        fail('linear', f"the fit is worse than the linear baseline "
                       f"({fit:.3g} % < {linear['fit']:.3g} %)" + (
                           "" if method == 'oe' else
                           ": use method='oe', which starts from that "
                           "linear model (res.linear['model']) and is "
                           "never worse") + _held(linear))
    if input_offset is not None and input_offset > INPUT_OFFSET:
        fail('input_offset', input_offset_text(input_offset))
    if input_order is not None and input_order[0] < input_order[1]:
        fail('input_order', input_order_text(*input_order))
    if std is not None:
        ill = poorly_determined(std, theta)
        if np.any(ill):
            fail('std', [n for n, bad in zip(labels, ill) if bad], False)
    if backlash_moves is not None and backlash_moves[0] < backlash_moves[1]:
        fail('backlash_moves', f"the model's backlash moves in only "
                               f"{backlash_moves[0]} samples, and only they "
                               f"tell the {backlash_moves[1]} parameters of "
                               f"L1 and the backlash: the data do not "
                               f"determine them (excite the plant longer, "
                               f"across the dead band)")
    elif excitation is not None and excitation < MIN_EXCITATION:
        fail('excitation', excitation, False)
    if minimum_phase_bound is not None:
        fail('minimum_phase', f"a zero of L1 ended on the minimum-phase "
                              f"bound |z| = {minimum_phase_bound:.4g}: "
                              f"these data ask for a zero outside the unit "
                              f"circle (another delay q1, or "
                              f"minimum_phase=None, may suit them)", False)
    return failed


def input_offset_text(ratio):
    """The failure of an input at an operating point (`INPUT_OFFSET`)."""
    return (f"the input starts {ratio:.3g} of its standard deviations "
            f"from zero, and the model starts from rest at u = 0: the "
            f"record would begin with a step it never had (remove the "
            f"operating point: offsets='mean', or u - u0)")


def _held_out_lines(held):
    """The lines of `IdentificationResult`'s repr on step 13's check."""
    if held and 'fit' in held:
        return [f"  held-out tails ({held['samples']} samples): sandwich "
                f"{held['fit']:.2f} %, linear {held['linear_fit']:.2f} % "
                f"(fitted without them)" + (
                    "" if held['open'] else
                    ": the open backlash did not generalise")]
    return [f"  {held['note']}"] if held else []


def _held(linear):
    """'; ' and the note of a baseline whose structure cannot hold the
    linear fit (``linear['held']``, see `_search.held_note`); '' when it
    holds it."""
    held = linear.get('held')
    return "; " + held['note'] if held else ""


def poorly_determined(std, theta):
    """Which parameters of theta the standard errors `std` leave poorly
    determined: a standard error that is not finite or above
    `POORLY_DETERMINED` of |theta| (at least 1e-3)."""
    return ~np.isfinite(std) | (std > POORLY_DETERMINED * np.maximum(
        np.abs(theta), 1e-3))


def judge(res, failed):
    """Write the `verdict` `failed` into `res`: a fatal failure sets
    ``success`` to False and is told in front of ``message``; a poorly
    determined parameter is told after it and warns, as does too little
    excitation."""
    fatal = [f.text for f in failed if f.fatal]
    if fatal:
        res.success = False
        res.message = '; '.join(fatal) + f" [{res.message}]"
    for f in failed:
        if f.check == 'std':
            res.message += (f"; parameters poorly determined by these data "
                            f"(standard error > 50%): {f.text}")
            warn(f"{f.text} are poorly determined by the data (excitation "
                 f"too small or orders too high?)", IdentificationWarning)
        elif f.check == 'minimum_phase':
            res.message += f"; {f.text}"
        elif f.check == 'excitation':
            warn(f"the backlash of the identified model is outside its "
                 f"memory zone in only {f.text:.1%} of the samples: the "
                 f"data hardly excite it, so m1, m2, D1, D2 are unreliable "
                 f"(is the input amplitude smaller than the dead band?)",
                 ExcitationWarning)
    return res


def parameter_error(theta_hat, theta_true):
    """Normalised parameter error ||theta_hat - theta|| / ||theta||.

    Parameters
    ----------
    theta_hat : array_like, shape (p,) or (N, p)
        One estimate or a history of estimates (one per row).
    theta_true : array_like, shape (p,)
        The true parameter vector.

    Returns
    -------
    float or ndarray of shape (N,)
        An estimate that is not finite (a diverged one) gives nan or inf;
        one too far off for a float gives inf.

    Raises
    ------
    ValueError
        If `theta_true` is not finite, or is zero (the relative error is
        then undefined: use ``np.linalg.norm(theta_hat - theta_true)``).

    Examples
    --------
    >>> import sandwichctl as sw
    >>> float(sw.parameter_error([1.1, 2.0], [1.0, 2.0]))  # doctest: +ELLIPSIS
    0.0447...
    """
    theta_true = check_reference('theta_true', theta_true)
    theta_hat = np.asarray(_real_array(
        'theta_hat', theta_hat, 'an array of numbers, shape (p,) or (N, p)'),
        dtype=float)
    if theta_hat.ndim not in (1, 2):
        raise ValueError(f"theta_hat must have shape (p,) or (N, p); got "
                         f"shape {theta_hat.shape}")
    if theta_hat.shape[-1] != theta_true.size:
        raise ValueError(
            f"theta_hat has {theta_hat.shape[-1]} parameters per estimate "
            f"but theta_true has {theta_true.size}")
    with np.errstate(over='ignore'):
        return (scaled_norm(theta_hat - theta_true)
                / scaled_norm(theta_true))


def backlash_significance(cost_linear, cost_sandwich, n_linear, n_sandwich,
                          n_samples):
    """F-test of the sandwich against the linear model it nests.

    With D1 = D2 = 0 and m1 = m2 the sandwich is the linear model, so the
    extra ``n_sandwich - n_linear`` parameters (the backlash) can be
    tested: ``F = ((C_lin - C_sw) / extra) / (C_sw / (N - n_sandwich))``,
    with C the sums of squared residuals.

    Returns
    -------
    dict
        ``F``, ``p_value`` (small: the backlash explains the data
        significantly better than the linear model) and ``extra``.

    Examples
    --------
    >>> from sandwichctl.identification.result import backlash_significance
    >>> out = backlash_significance(2.0, 1.0, 5, 8, 1000)
    >>> round(out['F'], 1), out['p_value'] < 1e-6
    (330.7, True)
    """
    extra = max(int(n_sandwich) - int(n_linear), 1)
    dof = max(int(n_samples) - int(n_sandwich), 1)
    if not cost_sandwich > 0:
        return {'F': np.inf, 'p_value': 0.0, 'extra': extra}
    F = max(cost_linear - cost_sandwich, 0.0) / extra / (cost_sandwich / dof)
    return {'F': float(F), 'p_value': float(stats.f.sf(F, extra, dof)),
            'extra': extra}


def whiteness(residuals, lags=20):
    """Residual whiteness summary: autocorrelation against its 99% band.

    Returns
    -------
    dict
        ``lags``, ``outside`` (how many of lags 1..lags fall outside
        +-2.58/sqrt(N)), ``Q`` (Ljung-Box statistic) and ``p_value``
        (small: the residuals are not white, so the model leaves dynamics
        unexplained or the noise is coloured).

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.identification.result import whiteness
    >>> w = whiteness(np.random.default_rng(0).standard_normal(2000))
    >>> w['outside'] <= 1, w['p_value'] > 0.01
    (True, True)
    """
    r = np.asarray(residuals, dtype=float)
    r = r - r.mean()
    n = r.size
    lags = int(min(lags, n - 1))
    denom = float(r @ r)
    if lags < 1 or not denom > 0:
        return {'lags': 0, 'outside': 0, 'Q': 0.0, 'p_value': 1.0}
    rho = np.array([r[:-k] @ r[k:] for k in range(1, lags + 1)]) / denom
    Q = float(n * (n + 2) * np.sum(rho ** 2 / (n - np.arange(1, lags + 1))))
    return {'lags': lags,
            'outside': int(np.sum(np.abs(rho) > 2.58 / np.sqrt(n))),
            'Q': Q, 'p_value': float(stats.chi2.sf(Q, lags))}


class IdentificationResult(OptimizeResult):
    """Result of `identify` (a `scipy.optimize.OptimizeResult`).

    Attributes
    ----------
    model : SandwichSystem
        The identified model in the data's units, normalised with b0 = 1
        and d0 = +1 or -1 (the sign of its gain, `SandwichSystem.gain_sign`).
    theta : ndarray
        Final estimate, order of eq. (2.5); names in `theta_labels`. For
        a model with a negative gain it carries ``sign = -1`` (see
        `SandwichSystem.theta`), so that ``SandwichSystem.from_theta(
        res.theta, **orders)`` rebuilds ``res.model``.
    history : ndarray, shape (N, p)
        theta(k) after every sample (empty for batch methods).
    errors : ndarray, shape (N,)
        A-priori prediction errors e(k) (recursive methods) or final
        residuals (batch methods).
    counts : dict
        Numbers of long, short, null and stop steps (and skipped samples
        of the gradient method).
    success : bool
        True only if the model is finite and stable (poles on the unit
        circle only where integrators were declared or identified), the
        optimiser converged, and the model explains the data: a fit
        clearly above 0 and, for every method of `identify` (recursive
        ones too), not below the linear baseline. ``message`` says which
        test failed.
    message : str
        What happened.
    method, options, orders, theta0, nit, elapsed
        The method, its options, the orders, the start, the number of
        samples or iterations, and the wall time in seconds (of a
        recursive method: the recursion and its refinement, not the
        baseline).
    fit, cost, linear
        The fit (percent, as MATLAB's ``compare``) and output-error cost
        on the estimation data, and, from `identify`, the linear
        output-error baseline of the same total orders (a dict with
        ``fit``, ``cost``, ``model``, ``integrators``; for the recursive
        methods, which fit no integrators, fitted without).
    minimum_phase
        From ``identify(method='oe')``: the block kept minimum-phase
        ('L1') or None.
    std, significance, whiteness, crossing
        Batch methods only: the parameters' standard errors, the
        backlash's F-test against the baseline (`backlash_significance`),
        the residual whiteness summary (`whiteness`), and where the
        model's slope lines cross with the share of samples its x spends
        beyond (``{'x': ..., 'share': ...}``; printed from 10%).
    held_out
        From `identify` (``'oe'``): the cross-check of an open backlash
        (step 13 of docs/algorithm.md), None when the model's backlash is
        closed anyway. A dict: ``samples`` (held out at the end of each
        experiment), ``fit`` and ``linear_fit`` (percent, on those samples,
        of the sandwich and of the linear model fitted without them) and
        ``open`` (False: the open backlash did not generalise and the
        model is the closed-backlash floor of step 12); or ``samples`` and
        ``note`` when the tails were too short to judge.
    long_record
        From `identify` (``'oe'``): None, or for a record of more than
        200,000 samples ``{'samples': ..., 'head': ...}``: the search ran
        on the leading ``head`` samples and the final refinement on all of
        them (the message says so too; docs/algorithm.md, long records).
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        model, theta = self.get('model'), self.get('theta')
        if model is not None and theta is not None:   # theta carries d0
            self['theta'] = signed_theta(theta, model.gain_sign)

    def copy(self):
        """A shallow copy of this result, of its own class (dict's own
        copy gave a plain dict, without the summary and methods)."""
        return type(self)(self)

    def __repr__(self):
        if 'theta' not in self:
            return f"IdentificationResult({dict.__repr__(self)})"
        lines = [f"IdentificationResult ({self.get('method')}): "
                 f"{'success' if self.get('success') else 'FAILED'}",
                 f"  {self.get('message')}"]
        if getattr(self, 'counts', None):
            lines.append('  steps: ' + ', '.join(
                f"{k} {v}" for k, v in self.counts.items() if v))
        if getattr(self, 'fit', None) is not None:
            text = f"  fit on the estimation data: {self.fit:.2f} %"
            lin = getattr(self, 'linear', None)
            if lin is not None:
                text += (f"; linear output-error baseline (same total "
                         f"orders): {lin['fit']:.2f} %")
            lines.append(text)
        lines += _held_out_lines(getattr(self, 'held_out', None))
        sig = getattr(self, 'significance', None)
        if sig:
            lines.append(f"  backlash significance: F = {sig['F']:.4g} on "
                         f"{sig['extra']} extra parameters, p = "
                         f"{sig['p_value']:.2g}"
                         + (" (significant)" if sig['p_value'] < 0.01
                            else " (not significant: a linear model "
                                 "explains these data as well)"))
        white = getattr(self, 'whiteness', None)
        if white and white['lags']:
            lines.append(f"  residuals: {white['outside']} of "
                         f"{white['lags']} autocorrelation lags outside the "
                         f"99% band (Ljung-Box p = {white['p_value']:.2g})")
        if getattr(self, 'minimum_phase', None):
            lines.append(f"  {self.minimum_phase} kept minimum-phase (its "
                         f"zeros inside the unit circle)")
        cross = getattr(self, 'crossing', None)
        if cross and cross['share'] >= CROSSING_NOTE:
            lines.append(
                f"  x is beyond the crossing of the slope lines (x = "
                f"{cross['x']:.4g}) in {cross['share']:.0%} of the samples: "
                f"eq. (2.2) switches lines with the direction of x there, "
                f"the output-error cost jumps and the search is least "
                f"certain (see the algorithm page)")
        std = getattr(self, 'std', None)
        if std is None:
            lines.append('  theta: ' + ', '.join(
                f"{name}={val:.4g}" for name, val in
                zip(self.theta_labels, self.theta)))
        else:
            lines.append('  parameters (estimate +- standard error; * poorly '
                         'determined):')
            for name, val, sd in zip(self.theta_labels, self.theta, std):
                flag = ' *' if not (sd <= 0.5 * max(abs(val), 1e-12)) \
                    else ''
                lines.append(f"    {name:>4} = {val: .6g} +- {sd:.2g}{flag}")
        return '\n'.join(lines)

    __str__ = __repr__

    def parameter_error(self, true_theta):
        """Normalised error ||theta(k) - theta|| / ||theta|| for every k
        of the recursive estimate's history (`parameter_error` of
        ``res.theta`` for the final estimate)."""
        return parameter_error(self._history(), true_theta)

    def _history(self):
        """The history theta(k), refused when empty: only the recursive
        methods keep one (followed by `refine`, it ends at the recursive
        estimate)."""
        history = getattr(self, 'history', None)
        if history is None or np.size(history) == 0:
            method = self.get('method')
            why = ("only the recursive methods ('bundle', 'gradient', "
                   "'rpem') keep one" if method not in (
                       'bundle', 'gradient', 'rpem') else
                   "its RecursiveIdentifier saw no sample" if not
                   self.get('nit') else
                   "its RecursiveIdentifier ran with keep_history=False")
            raise ValueError(
                f"this result ({method!r}) has no history of estimates: "
                f"{why}; for the final estimate use "
                f"sw.parameter_error(res.theta, theta_true)")
        return history

    def plot_convergence(self, true_theta=None, axes=None, label=None,
                         **line_kw):
        """Plot every parameter's trajectory theta(k).

        Parameters
        ----------
        true_theta : array_like, optional
            True (equivalent) parameters, drawn as dashed lines.
        axes : array of matplotlib Axes, optional
            One axes per parameter, e.g. from an earlier call, to overlay
            several methods.
        label : str, optional
            Legend label of these trajectories (default: the method).
        **line_kw
            Passed to ``Axes.plot`` (e.g. color, ls).

        Returns
        -------
        ndarray of matplotlib Axes
        """
        import matplotlib.pyplot as plt
        history = self._history()
        p = len(self.theta_labels)
        if true_theta is not None:
            true_theta = check_vector('true_theta', true_theta)
            if true_theta.size != p:
                raise ValueError(f"true_theta must have the {p} parameters "
                                 f"{list(self.theta_labels)}; got "
                                 f"{true_theta.size}")
        if axes is not None:
            axes = np.asarray(axes, dtype=object)
            if axes.size < p or not all(hasattr(ax, 'plot')
                                        for ax in axes.flat):
                raise ValueError(f"axes must hold {p} matplotlib Axes, one "
                                 f"per parameter (as an earlier call "
                                 f"returns them); got {axes.size} "
                                 f"item{'s' if axes.size != 1 else ''}")
        if axes is None:
            ncol = 3
            nrow = -(-p // ncol)
            fig, axes = plt.subplots(nrow, ncol, figsize=(11, 2.2 * nrow),
                                     sharex=True, squeeze=False)
            for ax in axes.flat[p:]:
                ax.set_visible(False)
        axes = np.asarray(axes)
        k = np.arange(1, history.shape[0] + 1)
        for i, ax in enumerate(axes.flat[:p]):
            ax.plot(k, history[:, i], label=label or self.method,
                    **line_kw)
            if true_theta is not None:
                ax.axhline(true_theta[i], color='k', ls='--', lw=0.8)
            ax.set_title(self.theta_labels[i], fontsize=9)
        axes.flat[0].legend(fontsize=8)
        for ax in axes[-1] if axes.ndim == 2 else axes[-1:]:
            ax.set_xlabel('k')
        return axes
