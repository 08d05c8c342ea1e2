r"""Model validation: fit measures and measured-versus-simulated plots.

All measures compare a measured output y(0), ..., y(N-1) with a simulated
(or predicted) output :math:`\hat y(0), \dots, \hat y(N-1)`; single-output
signals only. With :math:`\|\cdot\|` the Euclidean norm over the samples
and :math:`\bar y` the mean of y,

.. math::

    \mathrm{NRMSE} = \frac{\|y - \hat y\|}{\|y - \bar y\|}, \qquad
    \mathrm{fit} = 100\,(1 - \mathrm{NRMSE})\ \%, \qquad
    e_{\max} = \frac{\max_k |y(k) - \hat y(k)|}{\max_k |y(k)|}.

``fit`` is the "fit" of MATLAB's ``compare``: 100 % is a perfect match,
0 % is no better than the constant :math:`\bar y`, and it can be negative.
:math:`e_{\max}` is the *maximum relative modelling error* that Section 6
of the paper reports ("less than 11 %"): the largest absolute error,
relative to the peak magnitude of the measured output (a fraction, not a
percentage); `max_relative_error` can also scale by the output range.

`compare` simulates one or several models on the same input, plots them
over the measurement and returns these numbers. With ``horizon=k`` it
scores k-step-ahead *predictions* instead of the free-run simulation:
the model runs from the measured past, so its errors cannot accumulate
over more than k samples (see `compare`).
"""

import contextlib
import numbers
import warnings

import numpy as np
import control as ct

from ..model.sandwich import SandwichSystem
from .experiments import as_experiments
from .._checks import (check_signal, check_int, check_axes, check_bool,
                       check_data_scale, check_model_output,
                       SimulationWarning)

__all__ = ['fit_percent', 'nrmse', 'max_relative_error', 'compare',
           'CompareResult', 'CompareResultList']


def nrmse(y, yhat):
    r"""Normalised root-mean-square error :math:`\|y-\hat y\|/\|y-\bar y\|`.

    The error norm is divided by the norm of the measured output's
    deviation from its mean, so 0 is a perfect match and 1 is as good as
    predicting the constant mean.

    Parameters
    ----------
    y : array_like, shape (N,)
        Measured output.
    yhat : array_like, shape (N,)
        Simulated or predicted output.

    Returns
    -------
    float
        The NRMSE, >= 0.

    Raises
    ------
    ValueError
        If the signals have different lengths or non-finite samples, or
        samples above 1e100 in magnitude (whose squares overflow: rescale
        both alike), or if y is constant (the normalisation is then zero).

    See Also
    --------
    fit_percent : the same measure as MATLAB's percentage fit.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.nrmse([1.0, 2.0, 3.0], [1.0, 2.0, 4.0])
    0.7071
    """
    y, yhat = _check_pair(y, yhat)
    for name, other, values in (('y', 'yhat', y), ('yhat', 'y', yhat)):
        check_data_scale(name, values, 'the error norms', low=False,
                         back=f"{other} alike (the fit does not change)")
    # each norm in units of its own largest entry, so that neither a y
    # of 1e-200 nor its error against a yhat of 1 underflows or overflows
    spread = float(scaled_norm(y - y.mean()))
    if spread == 0:
        raise ValueError(
            f"y is constant (every sample is {float(y[0])!r}), so its "
            f"deviation from the mean is zero and the normalised error is "
            f"undefined; compare on data that excites the output")
    with np.errstate(over='ignore'):
        return float(scaled_norm(y - yhat) / spread)


def fit_percent(y, yhat):
    r"""Percentage fit :math:`100\,(1 - \|y-\hat y\|/\|y-\bar y\|)`.

    This is the "fit" of MATLAB's ``compare`` (System Identification
    Toolbox): 100 for a perfect match, 0 for a model no better than the
    mean of y, negative for a worse one.

    Parameters
    ----------
    y : array_like, shape (N,)
        Measured output.
    yhat : array_like, shape (N,)
        Simulated or predicted output.

    Returns
    -------
    float
        The fit in percent, <= 100.

    Raises
    ------
    ValueError
        If the signals have different lengths or non-finite samples, or
        samples above 1e100 in magnitude (rescale both alike), or if y is
        constant.

    See Also
    --------
    nrmse : the normalised error, ``fit = 100 * (1 - nrmse)``.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.fit_percent([0.0, 1.0, 0.0, -1.0], [0.0, 0.5, 0.0, -0.5])
    50.0
    """
    return 100.0 * (1.0 - nrmse(y, yhat))


def max_relative_error(y, yhat, scale='peak'):
    r"""Maximum relative modelling error (the measure of Section 6).

    With ``scale='peak'`` (default)

    .. math:: e_{\max} = \frac{\max_k |y(k) - \hat y(k)|}{\max_k |y(k)|},

    the largest absolute error relative to the peak magnitude of the
    measured output. With ``scale='range'`` the denominator is the output
    range :math:`\max_k y(k) - \min_k y(k)` instead, which does not depend
    on an offset in y. The result is a fraction: the paper's "less than
    11 %" is ``max_relative_error(y, yhat) < 0.11``.

    Parameters
    ----------
    y : array_like, shape (N,)
        Measured output.
    yhat : array_like, shape (N,)
        Simulated or predicted output.
    scale : {'peak', 'range'}, optional
        What the largest error is divided by (see above).

    Returns
    -------
    float
        The maximum relative error, >= 0.

    Raises
    ------
    ValueError
        If the signals have different lengths or non-finite samples, if
        `scale` is not 'peak' or 'range', or if the denominator is zero
        (y identically zero, or constant for ``scale='range'``).

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.max_relative_error([1.0, -2.0, 4.0], [1.5, -2.0, 3.0])
    0.25
    >>> sw.max_relative_error([1.0, -2.0, 4.0], [1.5, -2.0, 3.0],
    ...                       scale='range')
    0.1667
    """
    y, yhat = _check_pair(y, yhat)
    if not isinstance(scale, str) or scale not in ('peak', 'range'):
        raise ValueError(f"scale must be 'peak' or 'range'; got {scale!r}")
    if scale == 'peak':
        denominator = np.max(np.abs(y))
        what = 'the peak magnitude max|y|'
    elif scale == 'range':
        denominator = np.max(y) - np.min(y)
        what = 'the range max(y) - min(y)'
    else:
        raise ValueError(f"scale must be 'peak' or 'range'; got {scale!r}")
    if denominator == 0:
        raise ValueError(
            f"{what} of y is zero, so the relative error is undefined; "
            f"compare on data that excites the output")
    return float(np.max(np.abs(y - yhat)) / denominator)


class CompareResult:
    """Outcome of `compare` for one model.

    Attributes
    ----------
    name : str
        Label of the model (its system name unless `compare` was given
        labels).
    fit : float
        Percentage fit, see `fit_percent`.
    nrmse : float
        Normalised error, see `nrmse`.
    max_relative_error : float
        Maximum relative error (fraction of max|y|), see
        `max_relative_error`.
    yhat : ndarray, shape (N,)
        Simulated output.
    y : ndarray, shape (N,)
        Measured output.
    timepts : ndarray, shape (N,)
        Time points of the samples.
    model : object
        The model that was simulated.
    ax : matplotlib.axes.Axes or None
        The axes plotted on, or None if `compare` did not plot.
    horizon : int or None
        None if `yhat` is the free-run simulation, k if it is the k-step-
        ahead prediction (see `compare`).
    """

    def __init__(self, name, y, yhat, timepts, model, ax=None,
                 horizon=None):
        self.name = name
        self.horizon = horizon
        self.y = y
        self.yhat = yhat
        self.timepts = timepts
        self.model = model
        self.ax = ax
        self.fit = fit_percent(y, yhat)
        self.nrmse = nrmse(y, yhat)
        self.max_relative_error = max_relative_error(y, yhat)

    @property
    def error(self):
        """Output error ``y - yhat``, shape (N,)."""
        return self.y - self.yhat

    def as_dict(self):
        """The numbers as a plain dict (fit, nrmse, max_relative_error).

        Returns
        -------
        dict
            Keys 'name', 'fit', 'nrmse' and 'max_relative_error'.
        """
        return {'name': self.name, 'fit': self.fit, 'nrmse': self.nrmse,
                'max_relative_error': self.max_relative_error}

    def plot(self, ax=None):
        """Plot the measured and simulated outputs.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; default the current axes.

        Returns
        -------
        matplotlib.axes.Axes
        """
        return _plot_compare([self], ax)

    def __repr__(self):
        horizon = ('' if self.horizon is None
                   else f", horizon={self.horizon}")
        return (f"CompareResult(name={self.name!r}, fit={self.fit:.4g}, "
                f"nrmse={self.nrmse:.4g}, "
                f"max_relative_error={self.max_relative_error:.4g}"
                f"{horizon})")


class CompareResultList(list):
    """A list of `CompareResult`, one per model, from `compare`.

    It prints as a table and can plot all models over the measurement.
    """

    @property
    def fit(self):
        """Percentage fits of the models, ndarray of shape (n_models,)."""
        return np.array([r.fit for r in self])

    @property
    def nrmse(self):
        """Normalised errors of the models, ndarray."""
        return np.array([r.nrmse for r in self])

    @property
    def max_relative_error(self):
        """Maximum relative errors of the models, ndarray."""
        return np.array([r.max_relative_error for r in self])

    def plot(self, ax=None):
        """Plot the measurement and every model's output on one axes.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            Axes to draw on; default the current axes.

        Returns
        -------
        matplotlib.axes.Axes
        """
        return _plot_compare(list(self), ax)

    def __str__(self):
        width = max([5] + [len(r.name) for r in self])
        lines = [f"{'model':<{width}}  {'fit %':>8}  {'nrmse':>8}  "
                 f"{'max rel err':>11}"]
        for r in self:
            lines.append(f"{r.name:<{width}}  {r.fit:8.2f}  {r.nrmse:8.4f}"
                         f"  {r.max_relative_error:11.4f}")
        return '\n'.join(lines)


def compare(model, u, y=None, ax=None, initial_state=None, timepts=None,
            labels=None, plot=True, horizon=None):
    r"""Simulate (or predict) model(s) on measured data and compare.

    Like MATLAB's ``compare``: by default each model is simulated from
    `initial_state` with input `u` (free run), its output is plotted over
    the measured `y` with the percentage fit in the legend, and the
    numbers are returned.

    With ``horizon=k`` the model output is the *k-step-ahead prediction*
    :math:`\hat y(t \mid t-k)`: the model runs from the measured past, so
    only the last k samples are its own. For a `SandwichSystem`, L1 and
    the backlash do not depend on y, so x and v are simulated from u as in
    the free run; L2's recursion (2.1),

    .. math:: \hat y(s) = -\sum_{i=1}^{n_c} c_i\, y^*(s-i)
              + \sum_{j=0}^{n_d} d_j\, v(s-q_2-j),

    is then run for s = t-k+1, ..., t with :math:`y^*(s-i)` the measured
    output y(s-i) if :math:`s-i \le t-k` and the prediction
    :math:`\hat y(s-i)` otherwise. ``horizon=1`` is the one-step-ahead
    predictor, which is the paper's series-parallel predictor of (2.6);
    a horizon of N or more is the free run. For a discrete-time linear
    system (``ct.tf`` or ``ct.ss``) the same is done with its own
    difference equation, its input u in the place of v. Samples before
    t = 0 are zero (the free run's zero initial state), so the first k
    predictions are those of the free run.

    This is the equation-error (ARX-type) predictor: measured outputs
    enter the model's autoregressive part. MATLAB's ``compare(data, sys,
    k)`` predicts with the model's noise model instead, and for an
    output-error model, whose noise model is 1, its k-step prediction is
    the simulation.

    Parameters
    ----------
    model : SandwichSystem, control system, or list of them
        Model(s) to simulate. A `SandwichSystem` runs its fast
        `SandwichSystem.simulate`; other python-control systems (e.g. a
        linear ``ct.tf`` model for reference) run through
        ``ct.input_output_response`` (or ``ct.forced_response`` for
        transfer functions). Every model must be single-input,
        single-output.
    u : array_like, shape (N,)
        Measured input; or, without `y`, a ``control.TimeResponseData``
        (its time vector labels the plot) or a list of experiments, each
        compared in turn (a list of results is returned).
    y : array_like, shape (N,)
        Measured output.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.
    initial_state : array_like, optional
        Initial state of the model(s), default zero. With several models it
        is passed to each, so it is only useful when they share a state
        layout.
    timepts : array_like, shape (N,), optional
        Time points of the samples; default ``dt * arange(N)`` (or
        ``arange(N)`` when dt is True). Needed for continuous-time models.
    labels : str or list of str, optional
        Legend labels, one per model; default the system names.
    plot : bool, optional
        If False, only compute the numbers (no matplotlib calls).
    horizon : int or None, optional
        None (default) for the free-run simulation, or the prediction
        horizon k >= 1 (see above). Needs a `SandwichSystem` or a
        discrete-time linear system, and no `initial_state`.

    Returns
    -------
    CompareResult or CompareResultList
        A `CompareResult` (fit, nrmse, max_relative_error, yhat, ...) for a
        single model; a `CompareResultList` if `model` is a list or tuple.

    Raises
    ------
    ValueError
        If u and y differ in length or contain NaN/inf or samples above
        1e100 in magnitude (rescale them, and the model to match), if y is
        constant, if a model is not SISO or its output is not finite or
        above 1e100 in magnitude (unstable), or
        if `horizon` is given with `initial_state` or a continuous-time
        model.
    TypeError
        If a model is not a python-control system, if `horizon` is not an
        integer, or if `horizon` is given for a nonlinear system other
        than a `SandwichSystem`.

    See Also
    --------
    fit_percent, nrmse, max_relative_error : the measures.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(500, seed=1)
    >>> y = plant.simulate(u).outputs
    >>> result = sw.compare(plant, u, y, plot=False)
    >>> result.fit, result.max_relative_error
    (100.0, 0.0)

    A model with a wrong L2 drifts in free run; its one-step-ahead
    prediction, restarted from the measured output at every sample,
    stays closer:

    >>> theta = plant.theta.copy()
    >>> theta[0] *= 1.05                          # c1 of L2 off by 5 %
    >>> model = sw.SandwichSystem.from_theta(theta, **plant.orders)
    >>> free = sw.compare(model, u, y, plot=False)
    >>> one = sw.compare(model, u, y, plot=False, horizon=1)
    >>> bool(one.max_relative_error < free.max_relative_error)
    True
    >>> one.horizon
    1
    """
    ax = check_axes('ax', ax)
    plot = check_bool('plot', plot)
    if y is None:
        data = as_experiments(u)
        if len(data) > 1:
            return [compare(model, uu, yy, ax=None,
                            initial_state=initial_state, labels=labels,
                            plot=plot, horizon=horizon,
                            timepts=None if data.dt is True else
                            data.dt * np.arange(uu.size))
                    for uu, yy in data]
        (u, y), = data
        if timepts is None and data.dt is not True:
            timepts = data.dt * np.arange(u.size)
    many = isinstance(model, (list, tuple))
    models = list(model) if many else [model]
    if not models:
        raise ValueError("model must be a system or a non-empty list of "
                         "systems; got an empty list")
    u = check_signal('u', u)
    y = check_signal('y', y)
    if u.size != y.size:
        raise ValueError(f"u and y must have the same number of samples; "
                         f"got {u.size} and {y.size}")
    for name, values in (('u', u), ('y', y)):
        check_data_scale(name, values, "the fit's error norms", low=False,
                         back='the model to match')
    if labels is None:
        labels = [getattr(m, 'name', None) or f"model {i}"
                  for i, m in enumerate(models)]
    elif isinstance(labels, str):
        labels = [labels]
    if not (isinstance(labels, (list, tuple))
            and all(isinstance(label, str) for label in labels)):
        raise TypeError(f"labels must be a string or a list of strings, one "
                        f"per model; got {labels!r}")
    if len(labels) != len(models):
        raise ValueError(f"labels must have one entry per model "
                         f"({len(models)}); got {len(labels)}")
    if timepts is not None:
        timepts = check_signal('timepts', timepts, length=u.size)
    if horizon is not None:
        horizon = check_int('horizon', horizon, minimum=1)
        if initial_state is not None:
            raise ValueError(
                "initial_state applies to the free-run simulation "
                "(horizon=None); a k-step predictor starts from the "
                f"measured past; got horizon={horizon} and an "
                "initial_state, pass only one of them")

    results = CompareResultList()
    for label, m in zip(labels, models):
        _check_spacing(m, timepts)
        if horizon is None:
            yhat, t = _simulate(m, u, initial_state, timepts)
        else:
            yhat, t = _predict(m, u, y, horizon, timepts)
        results.append(CompareResult(str(label), y, yhat, t, m,
                                     horizon=horizon))
    if plot:
        ax = _plot_compare(results, ax)
        for r in results:
            r.ax = ax
    return results if many else results[0]


def scaled_norm(x):
    """The Euclidean norm along the last axis, in units of the largest
    entry (no overflow or underflow of the squares at the float's ends):
    inf where an entry is, nan where one is nan."""
    top = np.max(np.abs(x), axis=-1)
    with np.errstate(invalid='ignore', divide='ignore'):
        unit = np.where(np.isfinite(top) & (top > 0), top, 1.0)
        got = np.linalg.norm(x / unit[..., None], axis=-1) * unit
    return np.where(np.isinf(top), np.inf, got)


def _check_pair(y, yhat):
    y = check_signal('y', y)
    yhat = check_signal('yhat', yhat)
    if y.size != yhat.size:
        raise ValueError(f"y and yhat must have the same number of "
                         f"samples; got {y.size} and {yhat.size}")
    return y, yhat


def _check_spacing(sys, t):
    """Refuse time points `t` spaced other than a discrete model's dt
    (python-control would run a transfer function over them at the
    data's rate, silently)."""
    dt = getattr(sys, 'dt', None)
    if (t is None or t.size < 2 or isinstance(dt, bool)
            or not isinstance(dt, numbers.Real) or not dt > 0):
        return
    step = float(t[-1] - t[0]) / (t.size - 1)
    if abs(step - float(dt)) > 1e-6 * float(dt):
        raise ValueError(
            f"the data's time points (timepts) are {step:g} apart on "
            f"average but model {getattr(sys, 'name', sys)!r} has dt = "
            f"{float(dt):g}; resample the data or use a model at the "
            f"data's rate")


def _default_timepts(sys, n):
    dt = getattr(sys, 'dt', None)
    if dt is True:
        return np.arange(n, dtype=float)
    if isinstance(dt, numbers.Real) and dt > 0:
        return float(dt) * np.arange(n)
    raise ValueError(
        f"timepts is required for a continuous-time model "
        f"({getattr(sys, 'name', sys)!r} has dt={dt!r}); pass the sample "
        f"times of u and y")


def _simulate(sys, u, initial_state, timepts):
    """Simulated output of one model and its time points."""

    _check_siso(sys)
    t = _default_timepts(sys, u.size) if timepts is None else timepts
    x0 = 0.0 if initial_state is None else initial_state
    if initial_state is not None and not isinstance(sys, SandwichSystem):
        n = (ct.ss(sys).nstates if isinstance(sys, ct.TransferFunction)
             else sys.nstates)
        size = np.size(initial_state)
        if size not in (1, n):
            raise ValueError(
                f"initial_state has {size} entries, and model {sys.name!r} "
                f"has {n} state{'' if n == 1 else 's'} (one initial state "
                f"serves several models only when they share a state "
                f"layout: compare them one by one)")
    # An unstable model overflows; that is reported below, not warned.
    with _overflow_reported():
        if isinstance(sys, SandwichSystem):
            resp = sys.simulate(u, initial_state=initial_state, timepts=t)
        elif isinstance(sys, ct.NonlinearIOSystem):
            resp = ct.input_output_response(sys, t, u, initial_state=x0)
        else:
            resp = ct.forced_response(sys, t, u, initial_state=x0)
    yhat = np.asarray(resp.outputs, dtype=float).reshape(-1)
    check_model_output(yhat, f"the simulated output of model {sys.name!r}")
    return yhat, t


@contextlib.contextmanager
def _overflow_reported():
    """No overflow warnings: the caller reports a non-finite result."""
    with np.errstate(over='ignore', invalid='ignore'), \
            warnings.catch_warnings():
        warnings.simplefilter('ignore', SimulationWarning)
        yield


def _check_siso(sys):
    if not isinstance(sys, ct.InputOutputSystem):
        raise TypeError(
            f"model must be a SandwichSystem or a python-control system "
            f"(e.g. ct.tf(...)); got {type(sys).__name__}")
    if sys.ninputs != 1 or sys.noutputs != 1:
        raise ValueError(
            f"model {sys.name!r} must be single-input single-output; got "
            f"{sys.ninputs} inputs and {sys.noutputs} outputs")


def _recursion(sys, u):
    """AR coefficients c and forced part f of the output recursion.

    y(s) = -sum_i c[i-1] y(s-i) + f(s) is the model's output equation, with
    f computed from u (zero before sample 0).
    """
    if isinstance(sys, SandwichSystem):
        with _overflow_reported():        # only v is used; y may diverge
            v = sys.simulate(u, internal=True).outputs[2]
        if not np.all(np.isfinite(v)):
            raise ValueError(
                f"the backlash output v of model {sys.name!r} is not finite "
                f"(first bad sample {int(np.flatnonzero(~np.isfinite(v))[0])}"
                f"); its L1 is probably unstable")
        co = sys.coefficients
        fir = np.concatenate([np.zeros(co['q2']), co['d']])
        f = np.convolve(v, fir)[:u.size]
        return co['c'], f
    if not isinstance(sys, (ct.TransferFunction, ct.StateSpace)):
        raise TypeError(
            f"horizon (k-step prediction) needs a SandwichSystem or a "
            f"discrete-time linear system (ct.tf, ct.ss); model "
            f"{sys.name!r} is a {type(sys).__name__}")
    if not sys.isdtime():
        raise ValueError(
            f"horizon (k-step prediction) needs a discrete-time model; "
            f"{sys.name!r} has dt={sys.dt!r}")
    tf = sys if isinstance(sys, ct.TransferFunction) else ct.tf(sys)
    num = np.atleast_1d(np.asarray(tf.num[0][0], dtype=float))
    den = np.trim_zeros(np.atleast_1d(np.asarray(tf.den[0][0],
                                                 dtype=float)), 'f')
    num = np.trim_zeros(num, 'f') if np.any(num) else np.zeros(1)
    if num.size > den.size:
        raise ValueError(
            f"model {sys.name!r} is improper (numerator degree "
            f"{num.size - 1} > denominator degree {den.size - 1}), so it has "
            f"no causal difference equation to predict with")
    fir = np.concatenate([np.zeros(den.size - num.size), num]) / den[0]
    return den[1:] / den[0], np.convolve(u, fir)[:u.size]


def _predict(sys, u, y, horizon, timepts):
    """k-step-ahead prediction of one model and its time points."""
    _check_siso(sys)
    t = _default_timepts(sys, u.size) if timepts is None else timepts
    c, f = _recursion(sys, u)
    yhat = _k_step(c, f, y, horizon)
    check_model_output(yhat, f"the {horizon}-step prediction of model "
                        f"{sys.name!r}")
    return yhat, t


def _k_step(c, f, y, k):
    """yhat(t | t-k) of y(s) = -sum c_i y(s-i) + f(s), for every t.

    Vectorised over the origins r = t - k: step j predicts sample r + j
    from the measured samples up to r (zero before 0) and the predictions
    of steps 1..j-1.
    """
    if c.size == 0:                     # no past output: the free run
        return np.array(f, dtype=float)
    n = y.size
    k = min(k, n)                       # a longer horizon is the free run
    origin = np.arange(n) - k
    padded_y = np.concatenate([np.zeros(k + c.size), y])
    padded_f = np.concatenate([np.zeros(k), f])
    shift = k + c.size                  # padded_y[shift + s] is y(s)
    steps = []                          # steps[-i]: prediction of r + j - i
    for j in range(1, k + 1):
        pred = padded_f[k + origin + j].copy()
        for i, ci in enumerate(c, 1):
            if ci == 0:
                continue
            past = (steps[j - i - 1] if j - i >= 1
                    else padded_y[shift + origin + j - i])
            pred -= ci * past
        steps.append(pred)
        if len(steps) > c.size:
            steps[j - c.size - 1] = None          # no longer needed
    return steps[-1]


def _plot_compare(results, ax):
    import matplotlib.pyplot as plt

    check_axes('ax', ax)
    if ax is None:
        ax = plt.gca()
    first = results[0]
    ax.plot(first.timepts, first.y, color='k', lw=1.2, label='measured')
    for r in results:
        what = '' if r.horizon is None else f"{r.horizon}-step "
        ax.plot(r.timepts, r.yhat, lw=1.0,
                label=f"{r.name}: {what}fit {r.fit:.1f} %")
    dt = getattr(first.model, 'dt', None)
    ax.set_xlabel('k' if dt is True else 'time')
    ax.set_ylabel('y')
    ax.set_title('Measured and simulated output' if first.horizon is None
                 else f"Measured and {first.horizon}-step-ahead predicted "
                      f"output")
    ax.legend()
    return ax
