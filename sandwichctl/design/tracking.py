r"""A linear two-degree-of-freedom tracking controller.

`tracking_controller` designs a PI feedback (and a model-inverse
feedforward with reference preview) for the linear plant that a
`SandwichCompensator` leaves (``comp.design_plant``) or for a linear model
(`linearized_plant`); an integrating plant gets the PID design of
`servo_controller`. `closed_loop_response` (module `closedloop`) runs it.
"""

import numpy as np
import control as ct

from .inverse import causal_inverse, _fmt_roots
from .compensator import _tf_text
from ._servo_design import (at_one, frequency_grid, loop_radius, design_pid,
                            phase_crossings, pid_tf)
from .loop import phase_margin
from .._checks import (check_discrete_siso_tf, common_dt, check_bool,
                       check_finite, check_gain, check_int)

__all__ = ['TrackingController', 'tracking_controller']

#: the most poles (samples of delay included) `tracking_controller` takes:
#: its grid search computes the closed-loop poles of 6,541 PI gains,
#: about 23 s at 100 poles and 170 s at 200 (the plant 1/(z^q (z - 0.5)))
TRACKING_MOST_POLES = 100


class TrackingController:
    r"""Two-degree-of-freedom linear tracking controller.

    ``v(k) = C(z)[r - y](k) + F(z)[r](k + preview)``: a PI feedback C and,
    optionally, a model-inverse feedforward F that uses the reference
    `preview` samples ahead (a planned trajectory). Built by
    `tracking_controller` or `TrackingController.from_feedback`; its
    attributes are read-only (each was computed with the others).

    Parameters
    ----------
    feedback : control.TransferFunction
        C(z), input 'e', output 'v_fb'.
    feedforward : control.TransferFunction or None
        F(z), input 'r_ahead', output 'v_ff'.
    preview : int
        Samples of reference preview used by F.
    design_plant : control.TransferFunction or None
        Plant the margins are computed for.
    kp, ki : float or None
        PI gains, for display.

    Attributes
    ----------
    feedback : control.TransferFunction
        C(z) = kp + ki z / (z - 1), input 'e', output 'v_fb'.
    feedforward : control.TransferFunction or None
        F(z) = :math:`z^{-d} P(z)^{-1}` (`causal_inverse` of the design
        plant P), input 'r_ahead', output 'v_ff'; None for feedback only.
    preview : int
        d, the relative degree of P if `feedforward` is used, else 0.
    design_plant : control.TransferFunction
        The linear plant P the controller was designed for.
    kp, ki : float or None
        The PI gains (None for `from_feedback`).
    margins : tuple or None
        As ``ct.stability_margins(C * P)``: gain margin, phase margin
        (deg), stability (modulus) margin and the three frequencies, read
        on a log frequency grid; the phase margin is the angle from the
        loop to -1 where ``|L| = 1``, negative when the closed loop is
        unstable.
    pole_radius : float or None
        Largest modulus of the closed-loop poles of ``ct.feedback(C * P)``.
    """

    def __init__(self, feedback, feedforward, preview, design_plant, kp, ki):
        for name, sys in (('feedback', feedback),
                          ('feedforward', feedforward),
                          ('design_plant', design_plant)):
            if sys is not None or name == 'feedback':
                check_discrete_siso_tf(name, sys)
                if name != 'feedback':
                    common_dt('feedback', feedback.dt, name, sys.dt)
        # checked here: a bad one failed later, inside closed_loop_response
        preview = check_int('preview', preview, minimum=0)
        kp, ki = (None if v is None else check_finite(k, v)
                  for k, v in (('kp', kp), ('ki', ki)))
        self.feedback = feedback
        self.feedforward = feedforward
        self.preview = preview
        self.design_plant = design_plant
        self.kp, self.ki = kp, ki
        self.margins = self.pole_radius = None
        if design_plant is not None:
            loop = feedback * design_plant
            self.pole_radius = float(np.max(np.abs(
                ct.feedback(loop, 1).poles())))
            self.margins = _margins(loop, self.pole_radius < 1)
        self._built = True

    def __setattr__(self, name, value):
        if self.__dict__.get('_built') and name in self.__dict__:
            raise AttributeError(
                f"TrackingController.{name} is read-only (the other "
                f"attributes were computed with it): build another with "
                f"sw.tracking_controller or TrackingController.from_feedback")
        super().__setattr__(name, value)

    @classmethod
    def from_feedback(cls, C, design_plant=None):
        """A feedback-only controller from any discrete SISO C(z).

        Parameters
        ----------
        C : control.TransferFunction
            Controller from the error e = r - y to the plant input.
        design_plant : control.TransferFunction, optional
            Plant for the margins and closed-loop poles; default: none
            (then `margins` and `pole_radius` are None).

        Examples
        --------
        >>> import control as ct, sandwichctl as sw
        >>> ctrl = sw.TrackingController.from_feedback(
        ...     ct.tf([0.2, 0], [1, -1], 1))
        >>> ctrl.preview, ctrl.feedforward is None
        (0, True)
        """
        num, den = check_discrete_siso_tf('C', C)
        if design_plant is not None:
            check_discrete_siso_tf('design_plant', design_plant)
            common_dt('C', C.dt, 'design_plant', design_plant.dt)
        C = ct.tf(num, den, C.dt, inputs='e', outputs='v_fb', name='feedback')
        return cls(C, None, 0, design_plant, None, None)

    def __repr__(self):
        if self.margins is None:
            return (f"TrackingController(feedback={_tf_text(self.feedback)},"
                    f" feedforward={self.feedforward is not None}, "
                    f"preview={self.preview})")
        gm, pm, sm = self.margins[:3]
        gains = (f"kp={self.kp:.4g}, ki={self.ki:.4g}" if self.kp is not None
                 else f"feedback={_tf_text(self.feedback)}")
        return (f"TrackingController({gains}, "
                f"feedforward={self.feedforward is not None}, "
                f"preview={self.preview}, pole_radius={self.pole_radius:.3f},"
                f" gain_margin={gm:.3g}, phase_margin={pm:.3g}, "
                f"modulus_margin={sm:.3g})")


def _margins(loop, stable):
    """(gain margin, phase margin [deg], modulus margin and the frequencies
    of the three) of the loop, read on a log grid from below the slowest
    pole to the Nyquist frequency, where the loop is real.
    python-control's ``stability_margins`` took the integrator's z = 1 for
    a phase crossover (a gain margin of 1e-16 for a PI on a first-order
    plant, whose loop doubles its gain safely), wrapped the phase margin
    of a gain crossover at a phase above 0 to a negative number (-52 deg
    for a loop 52 deg from -1 around a lightly damped resonance), and
    warned of its fallback on ordinary plants. The phase margin is the
    angle from the loop to -1 where |L| = 1 (`phase_margin`), negated
    when the closed loop is not `stable` (a crossing past -180 deg)."""
    num, den = loop.num[0][0], loop.den[0][0]
    w = frequency_grid(den, 6000)
    with np.errstate(all='ignore'):
        z = np.exp(1j * w)
        L = np.polyval(num, z) / np.polyval(den, z)
    per = 1.0 if loop.dt is True else loop.dt
    turn = phase_crossings(L)
    gm, wpc = np.inf, np.nan
    if turn.size:
        k = turn[np.argmax(np.abs(L[turn]))]
        gm, wpc = 1 / abs(L[k]), w[k] / per
    pm, at = phase_margin(L)
    wgc = np.nan if at is None else w[at] / per
    if at is not None and not stable:
        pm = -pm
    k = int(np.nanargmin(np.abs(1 + L)))
    return gm, pm, float(np.abs(1 + L[k])), wpc, wgc, w[k] / per


def tracking_controller(sys, feedforward=True, modulus_margin=0.6,
                        approximate=False):
    r"""Design a PI (plus feedforward) tracking controller for a linear plant.

    The PI gains minimise the largest closed-loop pole modulus (the decay
    rate of ``ct.feedback(C * P)``) subject to the modulus margin
    :math:`\min_\omega |1 + C P(e^{j\omega})| \ge` `modulus_margin`, which
    also guarantees a gain margin of at least ``1/(1 - modulus_margin)``
    (2.5 for 0.6) and a phase margin of at least
    ``2 asin(modulus_margin/2)`` (35 deg). The search is a two-stage grid
    over the gains scaled by the plant's DC gain; the result's margins are
    read on a log frequency grid (``TrackingController.margins``).

    Parameters
    ----------
    sys : control.TransferFunction
        Stable discrete-time SISO plant P (``comp.design_plant`` with a
        compensator, `linearized_plant` without one).
    feedforward : bool, optional
        Add the model-inverse feedforward :math:`z^{-d}P^{-1}` with a preview
        of d samples (default True).
    modulus_margin : float, optional
        Required stability margin, in (0, 1) (default 0.6, i.e. a
        sensitivity peak of at most 1/0.6 = 1.67).
    approximate : bool, optional
        Passed to `causal_inverse` for the feedforward if P is
        non-minimum-phase.

    Returns
    -------
    TrackingController

    Raises
    ------
    ValueError
        If P is unstable, has zero DC gain, has a gain (largest numerator
        over largest denominator coefficient) outside 1e-100 .. 1e100
        (rescale u or y), has more than `TRACKING_MOST_POLES` poles, or no
        PI gains on the grid meet the margin.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> comp = sw.sandwich_compensator(sw.examples.paper_plant())
    >>> ctrl = sw.tracking_controller(comp.design_plant)
    >>> ctrl.preview, ctrl.pole_radius < 0.6, bool(ctrl.margins[2] >= 0.6)
    (2, True, True)
    """
    num, den = check_discrete_siso_tf('sys', sys)
    feedforward = check_bool('feedforward', feedforward)
    approximate = check_bool('approximate', approximate)
    modulus_margin = check_finite('modulus_margin', modulus_margin)
    if not 0 < modulus_margin < 1:
        raise ValueError(f"modulus_margin must be in (0, 1); got "
                         f"{modulus_margin!r}")
    if den.size - 1 > TRACKING_MOST_POLES:
        raise ValueError(
            f"tracking_controller takes plants of at most "
            f"{TRACKING_MOST_POLES} poles (its grid search computes the "
            f"closed-loop poles of thousands of PI gains); got "
            f"{den.size - 1}. sw.servo_controller designs for such a plant")
    check_gain('sys', num, den, "the design's margins square it, which "
               "would {what} double precision")
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    one = at_one(poles)
    if one.sum() == 1 and np.all(np.abs(poles[~one]) < 1):
        # a type-1 plant: the PID of servo_controller's design
        kp, ki, kd, pole = design_pid(num, den, sys.dt, modulus_margin)
        C = pid_tf(kp, ki, kd, pole, sys.dt)
        C = ct.tf(C.num[0][0], C.den[0][0], sys.dt, inputs='e',
                  outputs='v_fb', name='feedback')
        return TrackingController(C, *_feedforward(sys, feedforward,
                                                   approximate),
                                  sys, kp, ki)
    if np.any(np.abs(poles) >= 1):
        raise ValueError("sys must be stable (all poles inside the unit "
                         "circle) or have one integrator for this design; "
                         f"got poles {_fmt_roots(poles)}")
    g = float(np.polyval(num, 1.0) / np.polyval(den, 1.0))
    if not np.isfinite(g) or g == 0:
        raise ValueError(f"sys must have a finite, non-zero DC gain for "
                         f"integral action; got {g}")
    w = frequency_grid(den)
    zw = np.exp(1j * w)
    P_w = np.polyval(num, zw) / np.polyval(den, zw)
    I_w = zw / (zw - 1.0)                   # the integrator's response
    num_p = np.concatenate([np.zeros(den.size - num.size), num])

    def evaluate(kp, ki):
        """Pole radius (inf if the margin is violated) for gain arrays."""
        kp, ki = kp.ravel(), ki.ravel()
        # the margin in blocks of gains: a fine grid (a long delay) times
        # thousands of gains would take gigabytes at once
        sm = np.concatenate([
            np.min(np.abs(1.0 + (kp[a:a + 256, None] + ki[a:a + 256, None]
                                 * I_w) * P_w), axis=1)
            for a in range(0, kp.size, 256)])
        # characteristic polynomial (z - 1) den + ((kp + ki) z - kp) num
        char = (np.convolve([1.0, -1.0], den)[None, :]
                + (kp + ki)[:, None] * np.append(num_p, 0.0)[None, :]
                - kp[:, None] * np.insert(num_p, 0, 0.0)[None, :])
        comp = np.zeros((kp.size, char.shape[1] - 1, char.shape[1] - 1))
        comp[:, 0, :] = -char[:, 1:] / char[:, :1]
        comp[:, np.arange(1, comp.shape[1]), np.arange(comp.shape[1] - 1)] = 1
        radius = np.max(np.abs(np.linalg.eigvals(comp)), axis=1)
        radius[sm < modulus_margin] = np.inf
        return radius

    kp_grid, ki_grid = np.meshgrid(np.linspace(-1, 2, 61),
                                   np.linspace(0.02, 2, 100))
    radius = evaluate(kp_grid / g, ki_grid / g)
    best = int(np.argmin(radius))
    if not np.isfinite(radius[best]):
        raise ValueError(f"no PI gains meet modulus_margin="
                         f"{modulus_margin}; lower it")
    kp0, ki0 = kp_grid.ravel()[best], ki_grid.ravel()[best]
    kp_fine, ki_fine = np.meshgrid(
        kp0 + np.linspace(-0.05, 0.05, 21),
        max(ki0, 0.021) + np.linspace(-0.02, 0.02, 21))
    radius_fine = evaluate(kp_fine / g, ki_fine / g)
    best = int(np.argmin(radius_fine))
    if radius_fine[best] <= radius.min():
        kp0, ki0 = kp_fine.ravel()[best], ki_fine.ravel()[best]
    kp, ki = kp0 / g, ki0 / g
    C = ct.tf([kp + ki, -kp], [1, -1], sys.dt, inputs='e', outputs='v_fb',
              name='feedback')
    if loop_radius(num, den, C) >= 1:
        raise ValueError("the PI design gives an unstable loop; lower "
                         "modulus_margin or use sw.servo_controller")
    return TrackingController(C, *_feedforward(sys, feedforward,
                                               approximate), sys, kp, ki)


def _feedforward(sys, feedforward, approximate):
    """The model-inverse feedforward and its preview (or None, 0)."""
    if not feedforward:
        return None, 0
    F = causal_inverse(sys, approximate=approximate, name='feedforward')
    F = ct.tf(F.num[0][0], F.den[0][0], sys.dt, inputs='r_ahead',
              outputs='v_ff', name='feedforward')
    return F, sys.den[0][0].size - np.trim_zeros(sys.num[0][0], 'f').size
