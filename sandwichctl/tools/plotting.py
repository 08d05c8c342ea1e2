"""Plots of the backlash: hysteresis loops and their slope lines.

`plot_hysteresis` draws the loop v against x of eq. (2.2) for an
identified backlash, optionally over the true one, with the increase line
v = m1 (x - D1) and the decrease line v = m2 (x + D2) of each. Only
matplotlib is used.
"""

import numpy as np

from ..model.backlash import Backlash
from ..model.sandwich import SandwichSystem
from .._checks import check_signal, check_axes, check_bool

__all__ = ['plot_hysteresis']


def plot_hysteresis(model_or_backlash, x=None, true=None, ax=None,
                    label=None, true_label='true', lines=True,
                    normalize=True):
    """Plot the hysteresis loop v(x) of a backlash, over the true one.

    The backlash output v is computed with eq. (2.2) along the input
    sequence `x` starting from zero memory (x(-1) = v(-1) = 0) and drawn
    against x. The loops of `model_or_backlash` (solid) and of `true`
    (dashed) share the axes; with ``lines=True`` each gets its two slope
    lines (thin), whose crossing point is marked when it lies in the
    plotted range (see `Backlash.crossing`).

    Parameters
    ----------
    model_or_backlash : SandwichSystem or Backlash
        The (identified) model. For a `SandwichSystem` its backlash is
        used; see `normalize`.
    x : array_like, shape (N,), optional
        Backlash input to sweep. Default: a triangle wave through 0, +A,
        -A, +A, then a smaller inner loop, with A three times the largest
        threshold D1, D2 of the backlashes drawn. To see the loop the data
        actually traced, pass the x of a simulation, e.g.
        ``model.simulate(u, internal=True).outputs[1]``.
    true : SandwichSystem or Backlash, optional
        The true backlash (or plant), drawn for comparison.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.
    label : str, optional
        Legend label of the model; default 'model' ('identified' when
        `true` is given).
    true_label : str, optional
        Legend label of `true`.
    lines : bool, optional
        Draw the increase and decrease lines (default True).
    normalize : bool, optional
        For a `SandwichSystem`, use the backlash of its normalised form
        (b0 = d0 = 1, the parametrisation of eq. (2.5) that identification
        returns), so that an identified model and the true plant are drawn
        in the same coordinates. Default True. Has no effect on a
        `Backlash`.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on.

    Raises
    ------
    TypeError
        If `model_or_backlash` or `true` is neither a `SandwichSystem` nor
        a `Backlash`.
    ValueError
        If `x` is not a finite 1-D signal, or a sandwich cannot be
        normalised (b0 and d0 of opposite signs; pass
        ``normalize=False``).

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use('Agg')
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> model = sw.SandwichSystem.from_theta(
    ...     [1.2, 0.32, 0.1, 0.2, 2.9, 3.5, 0.3, 0.45, -0.05],
    ...     na=2, nb=0, nc=2, nd=1, dt=1)
    >>> ax = sw.plot_hysteresis(model, true=plant)
    >>> ax.get_xlabel(), ax.get_ylabel()
    ('x', 'v')
    """
    normalize = check_bool('normalize', normalize)
    lines = check_bool('lines', lines)
    model = _as_backlash('model_or_backlash', model_or_backlash, normalize)
    reference = (None if true is None
                 else _as_backlash('true', true, normalize))
    drawn = [model] if reference is None else [model, reference]
    if x is None:
        x = _default_sweep(drawn)
    else:
        x = check_signal('x', x)
    if label is None:
        label = 'model' if reference is None else 'identified'

    if check_axes('ax', ax) is None:
        import matplotlib.pyplot as plt
        ax = plt.gca()
    curves = [(model, label, '-', 'C0')]
    if reference is not None:
        curves.append((reference, true_label, '--', 'k'))
    xs = np.array([x.min(), x.max()])
    span = xs[1] - xs[0]
    xs = xs + np.array([-0.05, 0.05]) * (span if span > 0 else 1.0)
    for bl, name, style, color in curves:
        v = bl.response(x)
        ax.plot(x, v, style, color=color, lw=1.6,
                label=(f"{name} (m1={bl.m1:.3g}, m2={bl.m2:.3g}, "
                       f"D1={bl.D1:.3g}, D2={bl.D2:.3g})"))
        if lines:
            ax.plot(xs, bl.m1 * (xs - bl.D1), ':', color=color, lw=0.8)
            ax.plot(xs, bl.m2 * (xs + bl.D2), '-.', color=color, lw=0.8)
            cross = bl.crossing
            if cross is not None and xs[0] <= cross <= xs[1]:
                ax.plot([cross], [bl.m1 * (cross - bl.D1)], 'x',
                        color=color)
    if lines:
        # one legend entry per line style, not per backlash
        ax.plot([], [], ':', color='grey', lw=0.8,
                label='increase line v = m1 (x - D1)')
        ax.plot([], [], '-.', color='grey', lw=0.8,
                label='decrease line v = m2 (x + D2)')
    ax.set_xlabel('x')
    ax.set_ylabel('v')
    ax.set_title('Backlash hysteresis loop (eq. 2.2)')
    ax.legend(fontsize='small')
    return ax


def _as_backlash(name, obj, normalize):
    """The Backlash of `obj` (a Backlash or a SandwichSystem)."""

    if isinstance(obj, Backlash):
        return obj
    if isinstance(obj, SandwichSystem):
        return obj.normalized().backlash if normalize else obj.backlash
    raise TypeError(f"{name} must be a sandwichctl.SandwichSystem or "
                    f"sandwichctl.Backlash; got {type(obj).__name__}")


def _default_sweep(backlashes, samples_per_segment=100):
    """Triangle wave: 0, A, -A, A, then an inner loop down to -A/3."""
    width = max(max(bl.D1, bl.D2) for bl in backlashes)
    amplitude = 3.0 * width if width > 0 else 1.0
    knots = amplitude * np.array([0.0, 1.0, -1.0, 1.0, -1.0 / 3, 2.0 / 3])
    segments = [np.linspace(a, b, samples_per_segment, endpoint=False)
                for a, b in zip(knots[:-1], knots[1:])]
    return np.concatenate(segments + [knots[-1:]])
