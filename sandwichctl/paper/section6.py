r"""The X-Y positioning-stage study of Section 6, as reusable functions.

`section6_run` simulates one axis of the stage (`examples.xy_stage`,
eqs. (6.1)-(6.3)) under the square-plus-sine excitation of Section 6,
measures its speed through the encoder model, identifies it with the
paper's bundle method (the Section 6 settings: b0 = d0 = 1,
:math:`\eta(0) = 0.00116`, :math:`\theta_0 = [0, 0, 0, 0, 1, 1, 0.001,
0.001, 0]^T`) and with the library's best method (``'oe'``), and
validates both models on a *fresh* record: a new input and new noise,
never seen by the estimators.

The figure of merit is the paper's maximum relative modelling error
("less than 11 %"),

.. math:: e_{\max} = \frac{\max_k |y(k) - \hat y(k)|}{\max_k |y(k)|},

computed by `sandwichctl.max_relative_error` between the measured
validation output y and a model output :math:`\hat y`. The paper does not
say which model output it scores, so both are reported:

- the *free-run* simulation, :math:`\hat y` from the input alone
  (``sw.compare(model, u, y)``), the strict test of a model; a model
  whose L1 or L2 is unstable has no bounded simulated output and is
  reported as unstable with :math:`e_{\max} = \infty`;
- the *one-step-ahead* prediction :math:`\hat y(k \mid k-1)`, which runs
  L2 from the measured past outputs (``sw.compare(model, u, y,
  horizon=1)``): the series-parallel predictor that the paper's
  identifier minimises in (2.6), and the likely meaning of the paper's
  11 %.

`section6_table` prints the numbers; `plot_section6` draws the paper's
Fig. 5 (parameter convergence), Fig. 6 (MSE over the steps) and Fig. 7
((a) validation, (b) input-output plot). The notebook
``notebooks/xy_stage.ipynb`` and ``benchmarks/bench_xy_stage.py`` use
them.
"""

import warnings

import numpy as np

from . import examples
from ..identification import identify
from ..tools.validation import compare

__all__ = ['section6_run', 'section6_table', 'validate', 'running_mse',
           'plot_section6', 'plot_parameters', 'plot_mse', 'plot_validation',
           'plot_input_output', 'PAPER_SETTINGS', 'METHODS']

#: Section 6 settings of the paper's bundle method: eta(0) = 0.00116
#: (theta0 is `examples.XY_STAGE_THETA0`; b0 = d0 = 1 by normalisation).
PAPER_SETTINGS = {'eta0': 0.00116}

#: Default methods of `section6_run`: ``{label: (method, options)}``.
METHODS = {'bundle': ('bundle', PAPER_SETTINGS), 'oe': ('oe', {})}


def running_mse(errors):
    r"""Running mean square error :math:`\frac1k \sum_{i=1}^k e(i)^2`.

    This is the MSE of the paper's Fig. 6, computed from the a-priori
    prediction errors e(k) of a recursive identification
    (``result.errors``).

    Parameters
    ----------
    errors : array_like, shape (N,)
        The errors e(1), ..., e(N).

    Returns
    -------
    ndarray, shape (N,)
        The running mean of e(k)^2.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.paper.section6.running_mse([1.0, -3.0, 2.0])
    array([1.    , 5.    , 4.6667])
    """
    e = np.asarray(errors, dtype=float)
    if e.ndim != 1:
        raise ValueError(f"errors must be a 1-D array; got shape {e.shape}")
    return np.cumsum(e ** 2) / np.arange(1, e.size + 1)


def _is_stable(model):
    return all(np.all(np.abs(sys.poles()) < 1) for sys in (model.L1,
                                                             model.L2))


def validate(model, u, y):
    """Score a model on (fresh) data, free run and one step ahead.

    Parameters
    ----------
    model : SandwichSystem
        The identified model.
    u, y : array_like, shape (N,)
        Validation input and measured output.

    Returns
    -------
    dict
        ``stable`` (L1 and L2 of the model are stable), ``max_relative_error``
        (`sandwichctl.max_relative_error` of the simulated output, a
        fraction; inf if unstable), ``fit`` (percent, see
        `sandwichctl.fit_percent`; -inf if unstable) and ``yhat`` (the
        simulated output, or None if unstable); and the same for the
        one-step-ahead prediction (`sandwichctl.compare` with
        ``horizon=1``): ``one_step_max_relative_error``, ``one_step_fit``
        and ``one_step_yhat``. The prediction needs only a stable L1 (L2
        runs from measured outputs); if it is not finite, its error is inf,
        its fit -inf and its output None.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.xy_stage()
    >>> u = sw.examples.xy_stage_input(2000, seed=1)
    >>> y = plant.simulate(u).outputs
    >>> out = sw.paper.section6.validate(plant, u, y)
    >>> out['stable'], out['max_relative_error'], out['fit']
    (True, 0.0, 100.0)
    >>> out['one_step_max_relative_error'] < 1e-12
    True
    """
    out = {'stable': False, 'max_relative_error': np.inf, 'fit': -np.inf,
           'yhat': None}
    if _is_stable(model):
        res = compare(model, u, y, plot=False)
        out = {'stable': True, 'max_relative_error': res.max_relative_error,
               'fit': res.fit, 'yhat': res.yhat}
    try:
        one = compare(model, u, y, plot=False, horizon=1)
    except ValueError:                   # L1 unstable: v is not finite
        out.update(one_step_max_relative_error=np.inf, one_step_fit=-np.inf,
                   one_step_yhat=None)
    else:
        out.update(one_step_max_relative_error=one.max_relative_error,
                   one_step_fit=one.fit, one_step_yhat=one.yhat)
    return out


def section6_run(n_samples=6700, n_validation=4000, seed=0, methods=None,
                 noise_std=0.2, resolution=1e-4, progress=False,
                 **plant_params):
    """Identify the X-Y stage axis and validate on fresh data (Section 6).

    Parameters
    ----------
    n_samples : int, optional
        Length of the identification record (default 6700, the number of
        steps after which Section 6 reports convergence; 3.35 s of data).
    n_validation : int, optional
        Length of the fresh validation record (default 4000, 2 s).
    seed : int, optional
        Seeds four independent streams (`numpy.random.SeedSequence`):
        identification input and noise, validation input and noise.
    methods : dict, optional
        ``{label: (method, options)}`` passed to `sandwichctl.identify`;
        default `METHODS`: the paper's bundle method with the Section 6
        settings and the library's ``'oe'``. Every method starts from
        `examples.XY_STAGE_THETA0`.
    noise_std, resolution : float, optional
        Measurement noise (mm/s) and encoder resolution (mm), see
        `examples.xy_stage_measurement`.
    progress : bool, optional
        Show progress of the identifications.
    **plant_params : float
        Overrides of the physical parameters of `examples.xy_stage`.

    Returns
    -------
    dict
        ``plant``, ``theta_true`` (normalised, eq. (2.5)), ``u``, ``y``
        (measured) and ``y_true`` for identification; ``u_val``, ``y_val``
        and ``y_val_true`` for validation; ``results`` (label ->
        `IdentificationResult`), ``validation`` (label -> the dict of
        `validate`) and ``warnings`` (label -> list of the warning
        messages the identification issued).

    Examples
    --------
    >>> import sandwichctl as sw
    >>> run = sw.paper.section6.section6_run(
    ...     n_samples=2000, n_validation=1000,
    ...     methods={'bundle': ('bundle', sw.paper.section6.PAPER_SETTINGS)})
    >>> run['results']['bundle'].history.shape
    (2000, 9)
    >>> sorted(run['validation']['bundle'])    # doctest: +NORMALIZE_WHITESPACE
    ['fit', 'max_relative_error', 'one_step_fit',
     'one_step_max_relative_error', 'one_step_yhat', 'stable', 'yhat']
    """
    if methods is None:
        methods = METHODS
    plant = examples.xy_stage(**plant_params)
    dt = plant.dt
    streams = [np.random.default_rng(s)
               for s in np.random.SeedSequence(seed).spawn(4)]
    u = examples.xy_stage_input(n_samples, dt, seed=streams[0])
    y_true = plant.simulate(u).outputs
    y = examples.xy_stage_measurement(y_true, dt, resolution, noise_std,
                                      seed=streams[1])
    u_val = examples.xy_stage_input(n_validation, dt, seed=streams[2])
    y_val_true = plant.simulate(u_val).outputs
    y_val = examples.xy_stage_measurement(y_val_true, dt, resolution,
                                          noise_std, seed=streams[3])
    results, validation, issued = {}, {}, {}
    for label, (method, options) in methods.items():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            start = ({} if method == 'oe'
                     else {'theta0': examples.XY_STAGE_THETA0})
            res = identify(u, y, **plant.orders, method=method, dt=dt,
                           progress=progress, **start, **options)
        results[label] = res
        issued[label] = [str(w.message) for w in caught]
        validation[label] = validate(res.model, u_val, y_val)
    return {'plant': plant, 'theta_true': plant.theta, 'u': u, 'y': y,
            'y_true': y_true, 'u_val': u_val, 'y_val': y_val,
            'y_val_true': y_val_true, 'results': results,
            'validation': validation, 'warnings': issued}


def _errors(res):
    """Per-sample a-priori errors of a result (its recursive pass if any)."""
    rec = getattr(res, 'recursive', None)
    return (rec if rec is not None else res).errors


def section6_table(run):
    """Text table: validation errors per method, then the parameters.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.

    Returns
    -------
    str
        For each method the maximum relative error and the fit on the
        fresh validation record, of the free-run simulation and of the
        one-step-ahead prediction, whether the model is stable, the final
        running MSE of its (recursive) a-priori errors and the wall time;
        then the true normalised parameters against the estimates.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> run = sw.paper.section6.section6_run(
    ...     n_samples=2000, n_validation=1000,
    ...     methods={'bundle': ('bundle', sw.paper.section6.PAPER_SETTINGS)})
    >>> head = sw.paper.section6.section6_table(run).splitlines()[:2]
    >>> print(head[0])
            max rel err  max rel err     fit %     fit %
    >>> print(head[1][:52])
    method     free run     one step  free run  one step
    """
    names = list(run['results'])
    width = max([6] + [len(n) for n in names])
    lines = [f"{'':<{width}}  {'max rel err':>11}  {'max rel err':>11}  "
             f"{'fit %':>8}  {'fit %':>8}",
             f"{'method':<{width}}  {'free run':>11}  {'one step':>11}  "
             f"{'free run':>8}  {'one step':>8}  {'stable':>6}  "
             f"{'final MSE':>9}  {'time s':>6}"]
    for name in names:
        res, val = run['results'][name], run['validation'][name]
        mse = running_mse(_errors(res))
        err, fit = ((f"{val['max_relative_error']:.2%}",
                     f"{val['fit']:.2f}") if val['stable'] else ('inf', '-'))
        one = val['one_step_max_relative_error']
        err1, fit1 = ((f"{one:.2%}", f"{val['one_step_fit']:.2f}")
                      if np.isfinite(one) else ('inf', '-'))
        lines.append(
            f"{name:<{width}}  {err:>11}  {err1:>11}  {fit:>8}  {fit1:>8}  "
            f"{'yes' if val['stable'] else 'NO':>6}  "
            f"{mse[-1] if mse.size else np.nan:9.4g}  {res.elapsed:6.2f}")
    labels = next(iter(run['results'].values())).theta_labels
    lines += ['', f"{'param':>6} {'true':>9} "
              + ' '.join(f"{n:>{max(len(n), 9)}}" for n in names)]
    for i, lab in enumerate(labels):
        lines.append(f"{lab:>6} {run['theta_true'][i]:9.4f} " + ' '.join(
            f"{run['results'][n].theta[i]:{max(len(n), 9)}.4f}"
            for n in names))
    return '\n'.join(lines)


def _labels(run, labels):
    if labels is None:
        return list(run['results'])
    if isinstance(labels, str):
        labels = [labels]
    missing = [lab for lab in labels if lab not in run['results']]
    if missing:
        raise ValueError(f"labels {missing} are not methods of this run; "
                         f"it has {list(run['results'])}")
    return list(labels)


def plot_parameters(run, labels='bundle'):
    """Fig. 5: every parameter's estimate against the step k.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.
    labels : str or list of str, optional
        Methods to draw (default 'bundle', the paper's figure). For
        ``'oe'`` the trajectory is that of its recursive pass; the
        batch refinement that follows is not a trajectory over k.

    Returns
    -------
    matplotlib.figure.Figure
    """
    axes = None
    for label in _labels(run, labels):
        axes = run['results'][label].plot_convergence(
            true_theta=run['theta_true'] if axes is None else None,
            axes=axes, label=label, lw=1)
    fig = np.asarray(axes).flat[0].figure
    fig.suptitle('Fig. 5: parameter estimates of the X-Y stage axis '
                 '(dashed: true normalised values)')
    fig.tight_layout()
    return fig


def plot_mse(run, labels='bundle', ax=None):
    """Fig. 6: running MSE of the a-priori errors e(k) over the steps.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.
    labels : str or list of str, optional
        Methods to draw (default 'bundle'); for ``'oe'`` the errors of its
        recursive pass are used.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt
    if ax is None:
        ax = plt.gca()
    for label in _labels(run, labels):
        mse = running_mse(_errors(run['results'][label]))
        ax.semilogy(np.arange(1, mse.size + 1), mse, lw=1,
                    label=f"{label}: final {mse[-1]:.3g}")
    ax.set_xlabel('step k')
    ax.set_ylabel(r'MSE $\frac{1}{k}\sum e(i)^2$  [(mm/s)$^2$]')
    ax.set_title('Fig. 6: mean square error')
    ax.legend()
    return ax


def _model_label(label, val):
    if not val['stable']:
        return f"{label}: unstable model, not drawn"
    return f"{label}: max rel. error {val['max_relative_error']:.1%}"


def _plot_models(ax, run, labels, x, **style):
    """Each model's validation output against x; an unstable model gets
    only its legend entry."""
    for label in _labels(run, labels):
        val = run['validation'][label]
        if val['stable']:
            ax.plot(x, val['yhat'], label=_model_label(label, val), **style)
        else:
            ax.plot([], [], lw=1, label=_model_label(label, val))


def plot_validation(run, labels=None, ax=None):
    """Fig. 7(a): measured and simulated speed on the fresh record.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.
    labels : str or list of str, optional
        Methods to draw (default all).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt
    if ax is None:
        ax = plt.gca()
    t = run['plant'].dt * np.arange(run['y_val'].size)
    ax.plot(t, run['y_val'], color='k', lw=1.2, label='measured')
    _plot_models(ax, run, labels, t, lw=1)
    ax.set_xlabel('time [s]')
    ax.set_ylabel('platform speed y [mm/s]')
    ax.set_title('Fig. 7(a): validation on fresh data')
    ax.legend(fontsize=8)
    return ax


def plot_input_output(run, labels=None, ax=None):
    """Fig. 7(b): output against input, measured and simulated.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.
    labels : str or list of str, optional
        Methods to draw (default all).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.

    Returns
    -------
    matplotlib.axes.Axes
    """
    import matplotlib.pyplot as plt
    if ax is None:
        ax = plt.gca()
    ax.plot(run['u_val'], run['y_val'], color='k', lw=0.8, label='measured')
    _plot_models(ax, run, labels, run['u_val'], lw=0.8, ls='--')
    ax.set_xlabel('input u [V]')
    ax.set_ylabel('platform speed y [mm/s]')
    ax.set_title('Fig. 7(b): input-output plot')
    ax.legend(fontsize=8)
    return ax


def plot_section6(run, labels=None):
    """The paper's Figs. 5, 6 and 7 for one run.

    Parameters
    ----------
    run : dict
        The output of `section6_run`.
    labels : list of str, optional
        Methods for Figs. 5 and 6 (default 'bundle' if the run has it,
        else all); Fig. 7 shows every method.

    Returns
    -------
    dict
        ``{'fig5': Figure, 'fig6': Figure, 'fig7': Figure}``.
    """
    import matplotlib.pyplot as plt
    if labels is None:
        labels = ['bundle'] if 'bundle' in run['results'] else None
    fig5 = plot_parameters(run, labels)
    fig6, ax6 = plt.subplots(figsize=(7, 3.5))
    plot_mse(run, labels, ax=ax6)
    fig6.tight_layout()
    fig7, (ax_a, ax_b) = plt.subplots(1, 2, figsize=(12, 4))
    plot_validation(run, ax=ax_a)
    plot_input_output(run, ax=ax_b)
    fig7.tight_layout()
    return {'fig5': fig5, 'fig6': fig6, 'fig7': fig7}
