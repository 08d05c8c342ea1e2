"""The simulation study of Section 5, as reusable functions.

`section5_run` identifies the paper's plant from one data record with
several methods; `section5_table` and `plot_section5` turn the results
into the paper's table and Figs. 2 and 3. The command
``python -m sandwichctl demo``, the benchmark and the notebook use them.
"""

import numpy as np

from . import examples
from ..identification import identify

__all__ = ['section5_run', 'section5_table', 'plot_section5',
           'PAPER_SETTINGS']

#: Section 5 settings of the paper's bundle method and gradient baseline.
PAPER_SETTINGS = {
    'bundle': dict(eta0=0.015, k1=6, delta=1e-4),
    'gradient': dict(mu=0.009),
}


def section5_run(n_samples=20000, seed=0, snr=None, methods=None,
                 progress=False):
    """Identify the Section 5 plant with several methods on one record.

    Parameters
    ----------
    n_samples : int, optional
        Length of the record (default 20000).
    seed : int, optional
        Seed of the input; the noise uses ``seed + 1000``.
    snr : float or None, optional
        Output SNR as a variance ratio (46.5 in the paper), or None for
        noise-free data.
    methods : dict, optional
        ``{label: (method, options)}``; default the paper's bundle method
        and gradient baseline with the settings of Section 5.
    progress : bool, optional
        Show progress.

    Returns
    -------
    dict
        ``{'plant', 'u', 'y', 'theta_true', 'results': {label: result}}``.
    """
    if methods is None:
        methods = {name: (name, opts) for name, opts in
                   PAPER_SETTINGS.items()}
    plant = examples.paper_plant()
    u = examples.paper_input(n_samples, seed=seed)
    y = plant.simulate(u).outputs
    if snr is not None:
        y = examples.add_noise(y, snr, seed=seed + 1000)
    results = {}
    for label, (method, options) in methods.items():
        results[label] = identify(
            u, y, **plant.orders, method=method,
            theta0=examples.PAPER_THETA0, progress=progress, **options)
    return {'plant': plant, 'u': u, 'y': y, 'theta_true': plant.theta,
            'results': results}


def section5_table(run):
    """Text table of true against estimated parameters for each method."""
    labels = next(iter(run['results'].values())).theta_labels
    names = list(run['results'])
    head = f"{'param':>6} {'true':>9} " + ' '.join(f"{n:>12}" for n in names)
    lines = [head, '-' * len(head)]
    for i, lab in enumerate(labels):
        lines.append(f"{lab:>6} {run['theta_true'][i]:9.4f} " + ' '.join(
            f"{run['results'][n].theta[i]:12.4f}" for n in names))
    lines.append(f"{'error':>6} {'':>9} " + ' '.join(
        f"{run['results'][n].parameter_error(run['theta_true'])[-1]:11.2%}"
        f" " for n in names))
    return '\n'.join(lines)


def plot_section5(run, title=None, styles=None):
    """Figures 2/3 of the paper: every parameter's trajectory per method.

    Returns the matplotlib Figure.
    """
    styles = styles or {'bundle': dict(color='tab:blue', ls='-'),
                        'gradient': dict(color='tab:red', ls=':')}
    axes = None
    for label, res in run['results'].items():
        axes = res.plot_convergence(
            true_theta=run['theta_true'] if axes is None else None,
            axes=axes, label=label, lw=1, **styles.get(label, {}))
    fig = np.asarray(axes).flat[0].figure
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    return fig
