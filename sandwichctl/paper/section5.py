"""The simulation study of Section 5, as reusable functions.

`section5_run` identifies the paper's plant from one data record with
several methods: by default the paper's bundle method and the traditional
gradient baseline under both readings of "the nonsmooth points are
omitted" (`METHODS`). `section5_table` and `plot_section5` turn the
results into the paper's table and Figs. 2 and 3. The command
``python -m sandwichctl demo``, the benchmark and the notebook use them.

The paper's "SNR equal to 46.5" has three readings (variance ratio,
amplitude ratio, dB; see `sandwichctl.examples.add_noise`);
`section5_run` takes the reading as ``snr_kind`` and `snr_label` names
it. Which reading reproduces Fig. 3 is measured in
``docs/reproduction.md``.
"""

import warnings

import numpy as np

from . import examples
from ..identification import identify

__all__ = ['section5_run', 'section5_table', 'plot_section5', 'snr_label',
           'PAPER_SETTINGS', 'METHODS']

#: Section 5 settings of the paper's bundle method and gradient baseline.
PAPER_SETTINGS = {
    'bundle': dict(eta0=0.015, k1=6, delta=1e-4),
    'gradient': dict(mu=0.009),
}

#: Default methods of `section5_run`, ``{label: (method, options)}``: the
#: bundle method and the gradient baseline under its two readings,
#: ``nonsmooth='skip'`` (the default reading: no update at a sample whose
#: predictor window switches backlash zone) and ``nonsmooth='subgradient'``
#: (update there with the Clarke subgradient of the zone eq. (2.2)
#: selects).
METHODS = {
    'bundle': ('bundle', PAPER_SETTINGS['bundle']),
    'gradient/skip': ('gradient', dict(PAPER_SETTINGS['gradient'],
                                       nonsmooth='skip')),
    'gradient/subgradient': ('gradient', dict(PAPER_SETTINGS['gradient'],
                                              nonsmooth='subgradient')),
}

_STYLES = {'bundle': dict(color='tab:blue', ls='-'),
           'gradient/skip': dict(color='tab:red', ls=':'),
           'gradient/subgradient': dict(color='tab:orange', ls='-.')}


def snr_label(snr, kind='variance'):
    """How the study names a noise level: ``'SNR 46.5 (variance ratio)'``.

    Parameters
    ----------
    snr : float or None
        The signal-to-noise ratio, or None for noise-free data.
    kind : {'variance', 'amplitude', 'db'}, optional
        Its reading, see `sandwichctl.examples.add_noise`.

    Returns
    -------
    str

    Examples
    --------
    >>> import sandwichctl as sw
    >>> [sw.paper.section5.snr_label(46.5, kind)
    ...  for kind in ('variance', 'amplitude', 'db')]
    ['SNR 46.5 (variance ratio)', 'SNR 46.5 (amplitude ratio)', 'SNR 46.5 dB']
    >>> sw.paper.section5.snr_label(None)
    'noise-free'
    """
    if snr is None:
        return 'noise-free'
    if kind not in examples.SNR_KINDS:
        raise ValueError(f"kind must be one of {sorted(examples.SNR_KINDS)}; "
                         f"got {kind!r}")
    if kind == 'db':
        return f"SNR {snr:g} dB"
    return f"SNR {snr:g} ({examples.SNR_KINDS[kind]})"


def section5_run(n_samples=20000, seed=0, snr=None, methods=None,
                 progress=False, snr_kind='variance'):
    """Identify the Section 5 plant with several methods on one record.

    Parameters
    ----------
    n_samples : int, optional
        Length of the record (default 20000).
    seed : int, optional
        Seed of the input; the noise uses ``seed + 1000``.
    snr : float or None, optional
        Output signal-to-noise ratio (46.5 in the paper) in the reading
        `snr_kind`, or None for noise-free data.
    methods : dict, optional
        ``{label: (method, options)}``; default `METHODS`, the paper's
        bundle method and the gradient baseline under both readings, with
        the settings of Section 5.
    progress : bool, optional
        Show progress.
    snr_kind : {'variance', 'amplitude', 'db'}, optional
        How `snr` is read (default 'variance'), see
        `sandwichctl.examples.add_noise`.

    Returns
    -------
    dict
        ``plant``, ``u``, ``y``, ``theta_true``, ``snr``, ``snr_kind``,
        ``results`` (label -> `IdentificationResult`) and ``warnings``
        (label -> the messages of the warnings the identification issued,
        e.g. that a gradient run diverged).

    Examples
    --------
    >>> import sandwichctl as sw
    >>> run = sw.paper.section5.section5_run(3000, snr=46.5,
    ...                                      snr_kind='amplitude')
    >>> list(run['results'])
    ['bundle', 'gradient/skip', 'gradient/subgradient']
    >>> run['results']['gradient/skip'].options['nonsmooth']
    'skip'
    """
    if methods is None:
        methods = METHODS
    plant = examples.paper_plant()
    u = examples.paper_input(n_samples, seed=seed)
    y = plant.simulate(u).outputs
    if snr is not None:
        y = examples.add_noise(y, snr, seed=seed + 1000, kind=snr_kind)
    results, issued = {}, {}
    for label, (method, options) in methods.items():
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter('always')
            results[label] = identify(
                u, y, **plant.orders, method=method,
                theta0=examples.PAPER_THETA0, progress=progress, **options)
        issued[label] = [str(w.message) for w in caught]
    return {'plant': plant, 'u': u, 'y': y, 'theta_true': plant.theta,
            'snr': snr, 'snr_kind': snr_kind, 'results': results,
            'warnings': issued}


def _diverged_at(res, n_samples):
    """Sample at which a recursive run stopped early, or None."""
    done = res.history.shape[0]
    return done if 0 < done < n_samples else None


def section5_table(run):
    """Text table of true against estimated parameters for each method.

    The line ``error`` is the normalised parameter error
    ||theta_hat - theta|| / ||theta|| of the final estimate, marked with
    ``*`` if that model is unstable or otherwise failed its checks
    (``result.success`` is False; a note under the table says why). A run
    that diverged shows the sample where it stopped instead, and its
    column holds the last finite estimate.

    Parameters
    ----------
    run : dict
        The output of `section5_run`.

    Returns
    -------
    str

    Examples
    --------
    >>> import sandwichctl as sw
    >>> run = sw.paper.section5.section5_run(
    ...     2000, methods={'bundle': sw.paper.section5.METHODS['bundle']})
    >>> print(sw.paper.section5.section5_table(run))
     param      true       bundle
    -----------------------------
        c1    1.2000       1.0698
        c2    0.3200       0.2256
        a1    0.1000       0.0711
        a2    0.2000       0.1906
        m1    3.0000       2.6199
        m2    3.6000       3.0639
        D1    0.3333       0.2525
        D2    0.4000       0.3163
        d1   -0.0500      -0.1393
     error                 14.20%
    """
    labels = next(iter(run['results'].values())).theta_labels
    names = list(run['results'])
    width = max([12] + [len(n) + 1 for n in names])
    head = f"{'param':>6} {'true':>9} " + ' '.join(
        f"{n:>{width}}" for n in names)
    lines = [head, '-' * len(head)]
    for i, lab in enumerate(labels):
        lines.append(f"{lab:>6} {run['theta_true'][i]:9.4f} " + ' '.join(
            f"{run['results'][n].theta[i]:{width}.4f}" for n in names))
    cells, notes = [], []
    for n in names:
        res = run['results'][n]
        stop = _diverged_at(res, run['u'].size)
        if stop is not None:
            cells.append(f"{'diverged @' + str(stop):>{width}}")
            continue
        err = f"{res.parameter_error(run['theta_true'])[-1]:.2%}"
        if not res.success:
            err += '*'
            notes.append(f"* {n}: {res.message}")
        cells.append(f"{err:>{width}}")
    lines.append(f"{'error':>6} {'':>9} " + ' '.join(cells))
    return '\n'.join(lines + notes)


def plot_section5(run, title=None, styles=None):
    """Figures 2/3 of the paper: every parameter's trajectory per method.

    A run that diverged is drawn up to its last finite estimate; the
    vertical range of each panel is that of the true value and the runs
    that did not diverge, so a diverging trajectory leaves the panel
    instead of flattening the others.

    Parameters
    ----------
    run : dict
        The output of `section5_run`.
    title : str, optional
        Figure title.
    styles : dict, optional
        ``{label: line keywords}``; default blue for the bundle method,
        red dotted and orange dash-dotted for the gradient readings.

    Returns
    -------
    matplotlib.figure.Figure
    """
    styles = styles or _STYLES
    axes = None
    finite = [run['theta_true'][None, :]]
    for label, res in run['results'].items():
        axes = res.plot_convergence(
            true_theta=run['theta_true'] if axes is None else None,
            axes=axes, label=label, lw=1, **styles.get(label, {}))
        if (_diverged_at(res, run['u'].size) is None
                and res.history.size):
            finite.append(res.history)
    lows = np.min([np.min(h, axis=0) for h in finite], axis=0)
    highs = np.max([np.max(h, axis=0) for h in finite], axis=0)
    pad = 0.1 * np.maximum(highs - lows, 0.05)
    for i, ax in enumerate(np.asarray(axes).flat[:lows.size]):
        ax.set_ylim(lows[i] - pad[i], highs[i] + pad[i])
    fig = np.asarray(axes).flat[0].figure
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
