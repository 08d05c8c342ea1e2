r"""The same plant tracked with and without compensation.

`closed_loop_demo` builds a compensator and two `tracking_controller`
designs from a model and runs both loops around a plant;
`CompensationDemo` holds the result, its figures of merit and a plot.
"""

import numpy as np

from .compensator import sandwich_compensator, linearized_plant, _check_model
from .tracking import tracking_controller
from .closedloop import closed_loop_response
from .references import steps_and_sines
from .._checks import check_signal, common_dt

__all__ = ['CompensationDemo', 'closed_loop_demo']


class CompensationDemo:
    r"""Result of `closed_loop_demo`: the same plant with and without
    compensation.

    Attributes
    ----------
    reference : ndarray
        The reference r.
    with_compensation, without_compensation : control.TimeResponseData
        Closed-loop responses (outputs y, u, x, v).
    rms_with, rms_without : float
        RMS tracking error :math:`\sqrt{\mathrm{mean}(r - y)^2}`.
    ratio : float
        ``rms_with / rms_without``.
    activity_ratio : float
        Total variation of u, :math:`\sum_k |u(k) - u(k-1)|`, with
        compensation over that without: about 1 when the compensator only
        adds the necessary jumps across the band, several times more when
        it chatters (see `sandwich_compensator`'s ``band_fraction``).
    compensator : SandwichCompensator
        The compensator, built from the model given.
    controller_with, controller_without : TrackingController
        The controllers, designed for ``compensator.design_plant`` and for
        ``linearized_plant(model)``.
    """

    def __init__(self, reference, with_compensation, without_compensation,
                 compensator, controller_with, controller_without):
        self.reference = reference
        self.with_compensation = with_compensation
        self.without_compensation = without_compensation
        self.compensator = compensator
        self.controller_with = controller_with
        self.controller_without = controller_without
        self.rms_with = _rms(reference - with_compensation.outputs[0])
        self.rms_without = _rms(reference - without_compensation.outputs[0])
        with np.errstate(all='ignore'):   # a loop that tracks exactly
            self.ratio = float(np.float64(self.rms_with) / self.rms_without)
            self.activity_ratio = (
                np.sum(np.abs(np.diff(with_compensation.outputs[1])))
                / np.sum(np.abs(np.diff(without_compensation.outputs[1]))))

    def plot(self, axs=None):
        """Plot r and y, the tracking errors, and u of both loops.

        Parameters
        ----------
        axs : array of 3 matplotlib axes, optional
            Where to draw; a new figure with three rows by default.

        Returns
        -------
        ndarray of matplotlib.axes.Axes
        """
        import matplotlib.pyplot as plt
        if axs is None:
            _, axs = plt.subplots(3, 1, sharex=True, figsize=(9, 7))
        flat = np.ravel(np.asarray(axs, dtype=object))
        if flat.size != 3 or not all(hasattr(ax, 'plot') for ax in flat):
            raise ValueError(f"axs must be 3 matplotlib Axes (rows for the "
                             f"output, the error and the input); got "
                             f"{axs!r:.60}")
        axs = flat
        t = self.with_compensation.time
        yw, uw = self.with_compensation.outputs[:2]
        yo, uo = self.without_compensation.outputs[:2]
        axs[0].plot(t, self.reference, 'k--', lw=1, label='reference r')
        axs[0].plot(t, yo, color='tab:red', lw=1, label='y, uncompensated')
        axs[0].plot(t, yw, color='tab:blue', lw=1, label='y, compensated')
        axs[0].set_ylabel('output')
        axs[0].legend(loc='upper right', fontsize='small')
        axs[1].plot(t, self.reference - yo, color='tab:red', lw=1,
                    label=f'uncompensated, RMS {self.rms_without:.3g}')
        axs[1].plot(t, self.reference - yw, color='tab:blue', lw=1,
                    label=f'compensated, RMS {self.rms_with:.3g}')
        axs[1].set_ylabel('error r - y')
        axs[1].legend(loc='upper right', fontsize='small')
        axs[2].plot(t, uo, color='tab:red', lw=1, label='uncompensated')
        axs[2].plot(t, uw, color='tab:blue', lw=1, label='compensated')
        axs[2].set_ylabel('plant input u')
        axs[2].set_xlabel('time')
        axs[2].legend(loc='upper right', fontsize='small')
        axs[0].set_title(f'Tracking with and without compensation: RMS '
                         f'ratio {self.ratio:.2f}')
        return axs

    def __repr__(self):
        return (f"CompensationDemo(rms_with={self.rms_with:.4g}, "
                f"rms_without={self.rms_without:.4g}, "
                f"ratio={self.ratio:.3f}, "
                f"activity_ratio={self.activity_ratio:.2f})")


def closed_loop_demo(plant, model, reference=None, smoothing=0.0,
                     band_fraction=1.0, feedforward=True, modulus_margin=0.6,
                     approximate=False):
    r"""Track a reference with and without a compensator built from `model`.

    Two loops around the same (true) `plant`, each with a linear controller
    from `tracking_controller` (same method, same margin):

    * with compensation: ``sandwich_compensator(model)`` in front of the
      plant and a controller designed for its ``design_plant``
      (:math:`z^{-q_1} L_2`);
    * without: a controller designed for ``linearized_plant(model)``
      (backlash replaced by its mean slope), driving the plant directly.

    Both use the model only through the compensator and the designs, so an
    identified model can be judged by how well it compensates the true plant.

    Parameters
    ----------
    plant : SandwichSystem
        The true plant that is simulated.
    model : SandwichSystem
        The model the compensator and the controllers are built from (the
        true plant, an identified model, or a perturbed one).
    reference : array_like, optional
        Reference r; default ``steps_and_sines()``.
    smoothing, band_fraction : float, optional
        Options of the compensator (see `sandwich_compensator`); defaults
        0 and 1, the exact inverse.
    feedforward : bool, optional
        Use model-inverse feedforward with reference preview in both loops
        (default True); False gives pure PI feedback.
    modulus_margin : float, optional
        Robustness requirement of both PI designs (default 0.6; see
        `tracking_controller`).
    approximate : bool, optional
        Allow approximate inverses of a non-minimum-phase model.

    Returns
    -------
    CompensationDemo

    Raises
    ------
    ValueError
        If plant and model have different sampling times.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> demo = sw.closed_loop_demo(plant, plant)    # exact model
    >>> demo.rms_with < 1e-12, round(demo.rms_without, 3)
    (True, 0.149)
    """
    _check_model('plant', plant)
    _check_model('model', model)
    common_dt('plant', plant.dt, 'model', model.dt)
    r = steps_and_sines() if reference is None else \
        check_signal('reference', reference)
    if not (r.size >= 2 and np.ptp(r) > 0):
        raise ValueError(f"reference must move (two samples or more, not "
                         f"all equal) for the loops to be compared; got "
                         f"{r.size} sample{'s' if r.size != 1 else ''}")
    comp = sandwich_compensator(model, smoothing=smoothing,
                                band_fraction=band_fraction,
                                approximate=approximate)
    c_with = tracking_controller(comp.design_plant, feedforward,
                                 modulus_margin, approximate)
    c_without = tracking_controller(linearized_plant(model), feedforward,
                                    modulus_margin, approximate)
    resp_with = closed_loop_response(plant, r, c_with, comp)
    resp_without = closed_loop_response(plant, r, c_without)
    return CompensationDemo(r, resp_with, resp_without, comp, c_with,
                            c_without)


def _rms(e):
    """RMS of `e` scaled by its peak first, so that errors of 1e200 do
    not overflow nor those of 1e-200 underflow (inf where the loop
    diverged)."""
    e = np.asarray(e, dtype=float)
    peak = float(np.max(np.abs(e))) if e.size else 0.0
    if not (np.isfinite(peak) and peak > 0):
        return peak
    return peak * float(np.sqrt(np.mean(np.square(e / peak))))
