"""The result of every identifier, recursive or batch.

`IdentificationResult` is a `scipy.optimize.OptimizeResult` with the
identified `SandwichSystem` in ``model``. The recursive estimators
(`RecursiveIdentifier`), the batch refinement (`refine`) and the
`identify` pipeline all return it, so they import it from here.
"""

import numpy as np
from scipy.optimize import OptimizeResult

__all__ = ['IdentificationResult', 'parameter_error']


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

    Examples
    --------
    >>> import sandwichctl as sw
    >>> float(sw.parameter_error([1.1, 2.0], [1.0, 2.0]))  # doctest: +ELLIPSIS
    0.0447...
    """
    theta_true = np.asarray(theta_true, dtype=float)
    theta_hat = np.asarray(theta_hat, dtype=float)
    if theta_hat.shape[-1] != theta_true.size:
        raise ValueError(
            f"theta_hat has {theta_hat.shape[-1]} parameters per estimate "
            f"but theta_true has {theta_true.size}")
    return (np.linalg.norm(theta_hat - theta_true, axis=-1)
            / np.linalg.norm(theta_true))



class IdentificationResult(OptimizeResult):
    """Result of `identify` (a `scipy.optimize.OptimizeResult`).

    Attributes
    ----------
    model : SandwichSystem
        The identified, normalised model (b0 = d0 = 1).
    theta : ndarray
        Final estimate, order of eq. (2.5); names in `theta_labels`.
    history : ndarray, shape (N, p)
        theta(k) after every sample (empty for batch methods).
    errors : ndarray, shape (N,)
        A-priori prediction errors e(k) (recursive methods) or final
        residuals (batch methods).
    counts : dict
        Numbers of long, short, null and stop steps (and skipped samples
        of the gradient method).
    success : bool
        False if the estimate diverged or the method failed.
    message : str
        What happened.
    method, options, orders, theta0, nit, elapsed
        The method, its options, the orders, the start, the number of
        samples or iterations, and the wall time in seconds.
    """

    def __repr__(self):
        lines = [f"IdentificationResult ({self.method}): "
                 f"{'success' if self.success else 'FAILED'}",
                 f"  {self.message}"]
        if getattr(self, 'counts', None):
            lines.append('  steps: ' + ', '.join(
                f"{k} {v}" for k, v in self.counts.items() if v))
        lines.append('  theta: ' + ', '.join(
            f"{name}={val:.4g}" for name, val in
            zip(self.theta_labels, self.theta)))
        return '\n'.join(lines)

    __str__ = __repr__

    def parameter_error(self, true_theta):
        """Normalised error ||theta(k) - theta|| / ||theta|| for every k."""
        return parameter_error(self.history, true_theta)

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
        p = len(self.theta_labels)
        if axes is None:
            ncol = 3
            nrow = -(-p // ncol)
            fig, axes = plt.subplots(nrow, ncol, figsize=(11, 2.2 * nrow),
                                     sharex=True, squeeze=False)
            for ax in axes.flat[p:]:
                ax.set_visible(False)
        axes = np.asarray(axes)
        k = np.arange(1, self.history.shape[0] + 1)
        for i, ax in enumerate(axes.flat[:p]):
            ax.plot(k, self.history[:, i], label=label or self.method,
                    **line_kw)
            if true_theta is not None:
                ax.axhline(np.asarray(true_theta)[i], color='k', ls='--',
                           lw=0.8)
            ax.set_title(self.theta_labels[i], fontsize=9)
        axes.flat[0].legend(fontsize=8)
        for ax in axes[-1] if axes.ndim == 2 else axes[-1:]:
            ax.set_xlabel('k')
        return axes
