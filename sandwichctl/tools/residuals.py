r"""Residual analysis of a model on measured data (MATLAB's ``resid``).

A model that explains the data leaves residuals

.. math:: e(t) = y(t) - \hat y(t)

(here :math:`\hat y` is the free-run simulation from rest) that are white
and independent of past inputs. `residuals` computes, over N samples with
the means of e and u removed,

.. math::

    r_e(\tau) = \frac{R_e(\tau)}{R_e(0)}, \quad \tau = 0, \dots, L,
    \qquad
    r_{ue}(\tau) = \frac{R_{ue}(\tau)}{\sqrt{R_e(0)\,R_u(0)}},
    \quad \tau = -L, \dots, L,

with :math:`R_e(\tau) = \frac1N \sum_t e(t)\,e(t+\tau)` and
:math:`R_{ue}(\tau) = \frac1N \sum_t u(t)\,e(t+\tau)`. A positive lag
:math:`\tau` correlates the residual with the input :math:`\tau` samples
*earlier*: a large value there is input dynamics the model misses; a
large value at a negative lag means the residual feeds back into the
input (closed-loop data). If e is white and independent of u, each
normalised correlation is approximately normal with standard deviation
:math:`1/\sqrt N`, so 99 % of them fall inside the band
:math:`\pm 2.58/\sqrt N`: about one lag in a hundred outside is chance,
many are a model defect.

With several experiments, each is simulated from rest and the sums run
over the experiments (a lag never crosses from one experiment into the
next).
"""

import numbers

import numpy as np
import control as ct

from ..model.sandwich import SandwichSystem
from .experiments import as_experiments
from .._checks import check_bool, check_int, check_model_output

__all__ = ['residuals', 'ResidualResult']

#: Two-sided 99 % point of the standard normal distribution.
_Z99 = 2.58


class ResidualResult:
    """Residual correlations of a model on data, from `residuals`.

    Attributes
    ----------
    name : str
        Name of the model.
    residuals : list of ndarray
        The residuals y - yhat of each experiment (free-run simulation
        from rest), means not removed.
    lags : ndarray, shape (L + 1,)
        0, 1, ..., L.
    autocorrelation : ndarray, shape (L + 1,)
        Normalised autocorrelation of the residuals at `lags` (1 at 0).
    cross_lags : ndarray, shape (2 L + 1,)
        -L, ..., L.
    cross_correlation : ndarray, shape (2 L + 1,)
        Normalised correlation of the input with the residuals
        `cross_lags` samples later.
    bound : float
        Half-width of the 99 % confidence band, 2.58 / sqrt(N).
    n_samples : int
        N, the number of samples over all experiments.
    outside_auto : int
        How many of the autocorrelations at lags 1..L are outside the band.
    outside_cross : int
        How many of the cross-correlations at lags -L..L are outside it.
    axes : ndarray of matplotlib.axes.Axes or None
        The two axes plotted on, or None if nothing was plotted.
    """

    def __init__(self, name, errors, lags, auto, cross, n_samples):
        self.name = name
        self.residuals = errors
        self.lags = np.arange(lags + 1)
        self.autocorrelation = auto
        self.cross_lags = np.arange(-lags, lags + 1)
        self.cross_correlation = cross
        self.n_samples = int(n_samples)
        self.bound = _Z99 / np.sqrt(n_samples)
        self.outside_auto = int(np.sum(np.abs(auto[1:]) > self.bound))
        self.outside_cross = int(np.sum(np.abs(cross) > self.bound))
        self.axes = None

    @property
    def max_lag(self):
        """L, the largest lag."""
        return int(self.lags[-1])

    def plot(self, ax=None):
        """Plot both correlations with their 99 % band, in two panels.

        Parameters
        ----------
        ax : sequence of two matplotlib.axes.Axes, optional
            Axes for the autocorrelation and the cross-correlation;
            default a new figure.

        Returns
        -------
        ndarray of matplotlib.axes.Axes
            The two axes.
        """
        import matplotlib.pyplot as plt

        if ax is None:
            _, ax = plt.subplots(2, 1, figsize=(7, 5.5),
                                 constrained_layout=True)
        elif not (isinstance(ax, (list, tuple, np.ndarray))
                  and len(ax) == 2):
            raise TypeError(
                f"ax must be a sequence of two matplotlib Axes (the "
                f"autocorrelation and the cross-correlation panels); got "
                f"{type(ax).__name__}")
        axes = np.asarray(ax, dtype=object)
        if not all(hasattr(a, 'axhspan') for a in axes):
            raise TypeError(f"ax must hold two matplotlib Axes; got "
                            f"{[type(a).__name__ for a in axes]}")
        panels = [
            (axes[0], self.lags, self.autocorrelation, self.outside_auto,
             f"autocorrelation of the residuals of {self.name}", 'lag'),
            (axes[1], self.cross_lags, self.cross_correlation,
             self.outside_cross,
             f"cross-correlation of u and the residuals of {self.name}",
             'lag (u leads e by this many samples)')]
        for a, lag, r, outside, title, xlabel in panels:
            a.axhspan(-self.bound, self.bound, color='C0', alpha=0.15,
                      label=f"99 % band (±{self.bound:.3g})")
            a.vlines(lag, 0, r, color='C0', lw=1.5)
            inside = np.abs(r) <= self.bound
            if lag[0] == 0:
                inside[0] = True              # r_e(0) = 1 by definition
            a.plot(lag[inside], r[inside], 'o', color='C0', ms=3.5)
            a.plot(lag[~inside], r[~inside], 'o', color='C3', ms=4.5,
                   label=f"{outside} outside")
            a.axhline(0, color='k', lw=0.6)
            a.set_title(title, fontsize='medium')
            a.set_xlabel(xlabel)
            a.legend(fontsize='small', loc='upper right')
        self.axes = axes
        return axes

    def __repr__(self):
        n_auto, n_cross = self.max_lag, self.cross_lags.size
        return (
            f"ResidualResult of {self.name!r} on {self.n_samples} samples "
            f"(99 % band +-{self.bound:.3g})\n"
            f"  autocorrelation,    lags 1..{n_auto}: {self.outside_auto} "
            f"of {n_auto} outside the band\n"
            f"  cross-correlation u->e, lags -{n_auto}..{n_auto}: "
            f"{self.outside_cross} of {n_cross} outside the band\n"
            f"  (about 1 % outside is chance; many outside is a model "
            f"defect)")


def _simulate(model, u, dt):
    """Free-run output of `model` from rest on the input u (one
    experiment)."""
    name = getattr(model, 'name', None) or 'model'
    if isinstance(model, SandwichSystem):
        with np.errstate(over='ignore', invalid='ignore'):
            yhat = model.simulate(u).outputs
    else:
        t = (float(model.dt) if isinstance(model.dt, numbers.Real)
             and not isinstance(model.dt, bool) else 1.0) * np.arange(u.size)
        with np.errstate(over='ignore', invalid='ignore'):
            yhat = ct.forced_response(model, t, u).outputs
    yhat = np.asarray(yhat, dtype=float).reshape(-1)
    check_model_output(yhat, f"the simulated output of model {name!r}")
    return yhat


def _check_model(model, dt):
    """The system to simulate: a SandwichSystem or a discrete SISO LTI
    model (an identification result gives its ``model``)."""
    inner = getattr(model, 'model', None)
    if not isinstance(model, ct.InputOutputSystem) and \
            isinstance(inner, ct.InputOutputSystem):
        model = inner
    if isinstance(model, SandwichSystem):
        pass
    elif isinstance(model, (ct.TransferFunction, ct.StateSpace)):
        if model.ninputs != 1 or model.noutputs != 1:
            raise ValueError(
                f"model must be single-input single-output; {model.name!r} "
                f"has {model.ninputs} inputs and {model.noutputs} outputs")
        if not model.isdtime():
            raise ValueError(
                f"model must be discrete-time (the residuals are those of "
                f"the sampled data); {model.name!r} has dt={model.dt!r}: "
                f"discretise it first, e.g. with ct.c2d(model, dt)")
    else:
        raise TypeError(
            f"model must be a SandwichSystem or a discrete-time linear "
            f"system (ct.tf, ct.ss), or an identification result; got "
            f"{type(model).__name__}")
    m_dt = model.dt
    if (isinstance(dt, numbers.Real) and not isinstance(dt, bool)
            and isinstance(m_dt, numbers.Real)
            and not isinstance(m_dt, bool)
            and abs(float(m_dt) - dt) > 1e-9 * dt):
        raise ValueError(f"the data are sampled at dt = {dt:g} but model "
                         f"{model.name!r} has dt = {float(m_dt):g}")
    return model


def residuals(model, data, lags=25, ax=None, plot=True):
    r"""Residual autocorrelation and input-residual cross-correlation.

    Like MATLAB's ``resid``: the model is simulated from rest on the
    measured input, and the correlations of the residuals e = y - yhat
    with themselves (lags 0 to `lags`) and with the input (lags -`lags`
    to `lags`) are computed with their 99 % confidence band
    :math:`\pm 2.58/\sqrt N` (module documentation). A model that
    explains the data leaves almost every lag inside the band.

    Parameters
    ----------
    model : SandwichSystem, control.TransferFunction or control.StateSpace
        The model: a sandwich (simulated with its fast kernel) or a
        discrete-time single-input single-output linear model (simulated
        with ``ct.forced_response``). An identification result is also
        accepted (its ``model`` is used).
    data : tuple, control.TimeResponseData or list
        The measured data as the model sees them (offsets removed as for
        the identification): a ``(u, y)`` pair of arrays, a record, or a
        list of experiments (see `as_experiments`).
    lags : int, optional
        Largest lag L (default 25), at least 1 and below the length of
        the shortest experiment.
    ax : sequence of two matplotlib.axes.Axes, optional
        Axes of the two panels; default a new figure.
    plot : bool, optional
        Plot the two panels (default True); False only computes.

    Returns
    -------
    ResidualResult
        The residuals, ``autocorrelation`` at ``lags``,
        ``cross_correlation`` at ``cross_lags``, the ``bound`` of the band
        and how many lags fall outside it (``outside_auto``,
        ``outside_cross``); it prints as a summary.

    Raises
    ------
    TypeError
        If `model` is not a supported system, or `data` is not one of the
        accepted forms.
    ValueError
        If `lags` is out of range, the data are not finite, the model is
        not SISO, is continuous-time, has another sampling time than the
        data, or its simulation is not finite or above 1e100 in magnitude
        (unstable), or the residuals or the input are constant.

    See Also
    --------
    compare : the simulated output over the measured one.

    Examples
    --------
    >>> import numpy as np
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(4000, seed=1)
    >>> y = plant.simulate(u).outputs
    >>> y = y + 0.05 * np.random.default_rng(2).standard_normal(u.size)
    >>> good = sw.residuals(plant, (u, y), plot=False)
    >>> good.outside_auto <= 2, good.outside_cross <= 2
    (True, True)
    >>> linear = sw.identify_linear(u, y, nb=3, nf=4, nk=2).model
    >>> bad = sw.residuals(linear, (u, y), plot=False)
    >>> bad.outside_auto > 10
    True
    """
    exps = as_experiments(data)
    model = _check_model(model, exps.dt)
    shortest = min(u.size for u in exps.u)
    lags = check_int('lags', lags, minimum=1)
    plot = check_bool('plot', plot)
    if lags >= shortest:
        raise ValueError(f"lags must be below the length of the shortest "
                         f"experiment ({shortest} samples); got {lags}")
    errors, r_e, r_ue = [], np.zeros(lags + 1), np.zeros(2 * lags + 1)
    s_e = s_u = 0.0
    for u, y in exps:
        e = y - _simulate(model, u, exps.dt)
        errors.append(e)
        ec, uc = e - e.mean(), u - u.mean()
        n = e.size
        r_e += [ec[:n - k] @ ec[k:] for k in range(lags + 1)]
        # R_ue(k) = sum_t u(t) e(t + k), for k = -L..L
        r_ue += [uc[:n - k] @ ec[k:] if k >= 0 else uc[-k:] @ ec[:n + k]
                 for k in range(-lags, lags + 1)]
        s_e += ec @ ec
        s_u += uc @ uc
    name = getattr(model, 'name', None) or 'model'
    if not s_e > 0:
        raise ValueError(f"the residuals of model {name!r} are constant (a "
                         f"perfect fit up to an offset); their correlation "
                         f"is undefined")
    if not s_u > 0:
        raise ValueError("the input u is constant, so its correlation with "
                         "the residuals is undefined")
    result = ResidualResult(name, errors, lags, r_e / s_e,
                            r_ue / np.sqrt(s_e * s_u), exps.n_samples)
    if plot:
        result.plot(ax)
    return result


#: bands per decade of `error_bands`
BANDS_PER_DECADE = 5


def _band_sums(residuals, yhat):
    """(centres, sum |E|^2, sum E conj(Yhat), sum |Yhat|^2, bins) per
    band of `error_bands`; None for a record of fewer than 64 samples."""
    e = np.asarray(residuals, dtype=float).reshape(-1)
    yh = np.asarray(yhat, dtype=float).reshape(-1)
    n = min(e.size, yh.size)
    if n < 64:
        return None
    win = np.hanning(n)
    E = np.fft.rfft((e[:n] - e[:n].mean()) * win)
    Y = np.fft.rfft((yh[:n] - yh[:n].mean()) * win)
    w = 2 * np.pi * np.arange(E.size) / n
    lo = 2 * np.pi * 4 / n
    edges = np.logspace(np.log10(lo), np.log10(np.pi),
                        int(BANDS_PER_DECADE * np.log10(np.pi / lo)) + 1)
    which = np.digitize(w, edges)
    sums = []
    for k in range(1, edges.size):
        inside = which == k
        if inside.any():
            sums.append((np.sqrt(edges[k - 1] * edges[k]),
                         np.sum(np.abs(E[inside]) ** 2),
                         np.sum(E[inside] * np.conj(Y[inside])),
                         max(np.sum(np.abs(Y[inside]) ** 2), 1e-300),
                         inside.sum()))
    return tuple(np.array(col) for col in zip(*sums))


def error_bands(residuals, yhat):
    r"""The model's relative error by frequency band, from its residuals:
    (w, delta), with w the bands' centres in rad/sample (log-spaced,
    `BANDS_PER_DECADE` per decade, from 4 periods per record to the
    Nyquist frequency) and

    .. math:: \delta_k = \sqrt{\textstyle\sum_{\omega \in k} |E(\omega)|^2
              \big/ \sum_{\omega \in k} |\hat Y(\omega)|^2},

    the residual's amplitude over the model output's in each band
    (Hann-windowed periodograms, means removed). Where the data excited
    the plant, this bounds the relative error :math:`|P - \hat P| /
    |\hat P|` that matters for robust stability (noise and unmodelled
    nonlinearity, play above all, count as error too: the estimate is
    conservative). Empty arrays for a record of fewer than 64 samples.

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.tools.residuals import error_bands
    >>> rng = np.random.default_rng(0)
    >>> yhat = np.cumsum(rng.standard_normal(4000))
    >>> w, delta = error_bands(0.01 * rng.standard_normal(4000), yhat)
    >>> bool(delta[0] < 0.01 < delta[-1])
    True
    """
    return band_errors(residuals, yhat)[0]


def relative_error(residuals, yhat):
    r"""The model's complex relative error by frequency band, from its
    residuals: (w, Delta, sigma), on the bands of `error_bands`, with

    .. math:: \Delta_k = \textstyle\sum_{\omega \in k} E(\omega)
              \overline{\hat Y(\omega)} \big/ \sum_{\omega \in k}
              |\hat Y(\omega)|^2 .

    For an output-error model fitted to open-loop data, :math:`e = (P -
    \hat P) u + v` and :math:`\hat y = \hat P u`, so Delta estimates
    :math:`(P - \hat P) / \hat P` with the noise v averaged out (it is
    uncorrelated with yhat): :math:`\hat P (1 + \Delta)` is the plant's
    frequency response as the data measured it, gain and phase, where
    `error_bands` only bounds the error's size. sigma is the standard
    error of each Delta: what of the residual Delta does not explain,
    averaged over the band's periodogram bins (counted as half as many
    independent ones, for the Hann window). Empty arrays for a record of
    fewer than 64 samples.

    Examples
    --------
    A model 10 % short of the plant's gain:

    >>> import numpy as np
    >>> from sandwichctl.tools.residuals import relative_error
    >>> rng = np.random.default_rng(0)
    >>> yhat = np.cumsum(rng.standard_normal(4000))
    >>> e = 0.1 * yhat + 0.01 * rng.standard_normal(4000)
    >>> w, d, sigma = relative_error(e, yhat)
    >>> bool(np.all(np.abs(d - 0.1) < np.maximum(3 * sigma, 1e-3)))
    True
    """
    return band_errors(residuals, yhat)[1]


def noise_level(residuals):
    """The standard deviation of the noise on a record, read from a fit's
    residuals: 1.4826 times the median absolute deviation of their
    increments, over sqrt(2). Differencing removes the slow model error
    (what play or a missed mode leaves) and the median ignores outliers,
    so for white noise this is its standard deviation, and for an encoder
    reading quantised to q about 0.3 q. A list holds one array per
    experiment. None for fewer than 3 samples.

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.tools.residuals import noise_level
    >>> rng = np.random.default_rng(1)
    >>> slow = np.sin(np.linspace(0, 20, 20000))
    >>> e = slow + 0.01 * rng.standard_normal(20000)
    >>> round(noise_level(e), 3)
    0.01
    """
    parts = (residuals if isinstance(residuals, (list, tuple))
             else [residuals])
    d = np.concatenate([np.diff(np.asarray(part, dtype=float).reshape(-1))
                        for part in parts])
    if d.size < 2:
        return None
    return float(1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2))


def band_errors(residuals, yhat):
    """(`error_bands`, `relative_error`) of the same residuals, from one
    pass over their spectra."""
    sums = _band_sums(residuals, yhat)
    if sums is None:
        return ((np.zeros(0), np.zeros(0)),
                (np.zeros(0), np.zeros(0, complex), np.zeros(0)))
    w, ee, ey, yy, bins = sums
    delta = ey / yy
    rest = np.maximum(ee / yy - np.abs(delta) ** 2, 0.0)
    return ((w, np.sqrt(ee / yy)),
            (w, delta, np.sqrt(rest / np.maximum(bins / 2, 1))))
