r"""Linear controller and closed loop around a compensated sandwich.

`tracking_controller` designs a linear feedback (and feedforward) for the
linear plant a `SandwichCompensator` leaves; `closed_loop_response` and
`closed_loop_system` run the loop, and `closed_loop_demo` compares it with
and without compensation.

Chattering in closed loop
-------------------------
The exact inverse is infinitely sensitive at :math:`\Delta = 0`: inside a
feedback loop, a v_d that should be constant changes by rounding errors
(1e-16) and x jumps across the band each time. The output is still exact,
but u chatters; any smoothing width, even 1e-9, removes this. Worse, an
inverse built from a model whose band is too wide, or shifted by
identification errors, over-compensates: each small correction of v_d
jumps x across the band and overshoots, so the loop hunts. The output
error stays small, but u jumps by the width of the band at almost every
sample. Smoothing softens small corrections; compensating slightly less
than the estimated band (``band_fraction`` of `sandwich_compensator`, e.g.
0.95) removes the over-compensation and leaves a small dead band that
integral action handles. `CompensationDemo` reports the input activity so
that the options can be compared (``benchmarks/bench_compensation.py``).
"""

import copy
import warnings

import numba
import numpy as np
import control as ct

from .inverse import causal_inverse, _fmt_roots, _inverse_step
from .compensator import (SandwichCompensator, sandwich_compensator,
                          linearized_plant, _tf_text, _check_model)
from .loop import servo_loop, plant_measure, plant_advance
from .servo import ServoController
from ._servo_design import frequency_grid, loop_radius, design_pid, pid_tf
from .references import steps_and_sines
from ..model._kernel import _ss_output, _ss_update
from ..model.sandwich import SandwichSystem, _warn_divergence
from .._checks import (check_discrete_siso_tf, check_signal, common_dt,
                       check_bool, check_finite, check_int, check_name,
                       check_vector)

__all__ = ['TrackingController', 'tracking_controller', 'closed_loop_system',
           'ClosedLoopSystem',
           'closed_loop_response', 'CompensationDemo',
           'closed_loop_demo']


# ----------------------------------------------------------------------
# Linear controller and closed loop
# ----------------------------------------------------------------------
class TrackingController:
    r"""Two-degree-of-freedom linear tracking controller.

    ``v(k) = C(z)[r - y](k) + F(z)[r](k + preview)``: a PI feedback C and,
    optionally, a model-inverse feedforward F that uses the reference
    `preview` samples ahead (a planned trajectory). Built by
    `tracking_controller` or `TrackingController.from_feedback`.

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
        ``ct.stability_margins(C * P)``: gain margin, phase margin (deg),
        stability (modulus) margin and the three frequencies.
    pole_radius : float or None
        Largest modulus of the closed-loop poles of ``ct.feedback(C * P)``.
    """

    def __init__(self, feedback, feedforward, preview, design_plant, kp, ki):
        self.feedback = feedback
        self.feedforward = feedforward
        self.preview = preview
        self.design_plant = design_plant
        self.kp, self.ki = kp, ki
        self.margins = self.pole_radius = None
        if design_plant is not None:
            loop = feedback * design_plant
            with warnings.catch_warnings():
                # ct.stability_margins may evaluate the loop at its
                # integrator pole z = 1 and warn about the division
                warnings.simplefilter('ignore', RuntimeWarning)
                self.margins = ct.stability_margins(loop)
            self.pole_radius = float(np.max(np.abs(
                ct.feedback(loop, 1).poles())))

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
        return (f"TrackingController(kp={self.kp:.4g}, ki={self.ki:.4g}, "
                f"feedforward={self.feedforward is not None}, "
                f"preview={self.preview}, pole_radius={self.pole_radius:.3f},"
                f" gain_margin={gm:.3g}, phase_margin={pm:.3g}, "
                f"modulus_margin={sm:.3g})")


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
    those of ``ct.stability_margins``.

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
        If P is unstable, has zero DC gain, or no PI gains on the grid meet
        the margin.

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
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    at_one = np.abs(poles - 1.0) < 1e-6
    if at_one.sum() == 1 and np.all(np.abs(poles[~at_one]) < 1):
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
    num_p = np.concatenate([np.zeros(den.size - num.size), num])

    def evaluate(kp, ki):
        """Pole radius (inf if the margin is violated) for gain arrays."""
        kp, ki = kp.ravel(), ki.ravel()
        C_w = kp[:, None] + ki[:, None] * zw / (zw - 1.0)
        sm = np.min(np.abs(1.0 + C_w * P_w), axis=1)
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


def _ss_arrays(sys):
    if sys is None:
        return (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)),
                np.zeros((1, 1)))
    ss = ct.ss(sys)
    return tuple(np.ascontiguousarray(np.asarray(M, dtype=float))
                 for M in (ss.A, ss.B, ss.C, ss.D))


@numba.njit(cache=True)
def _closed_loop_kernel(r, r_ahead, Af, Bf, Cf, Df, use_ff, Ac, Bc, Cc, Dc,
                        compensate, Ai, Bi, Ci, Di, im1, im2, iD1, iD2, width,
                        A1, B1, C1, D1, A2, B2, C2, D2, bl, y, u, x, v):
    """Simulate plant, controller and optional compensator from rest."""
    sf = np.zeros(Af.shape[0])
    sc = np.zeros(Ac.shape[0])
    si = np.zeros(Ai.shape[0])
    s1 = np.zeros(A1.shape[0])
    s2 = np.zeros(A2.shape[0])
    wf, wc, wi = np.empty(sf.size), np.empty(sc.size), np.empty(si.size)
    w1, w2 = np.empty(s1.size), np.empty(s2.size)
    mem = np.zeros(4)              # plant backlash memory
    xi_prev = vi_prev = 0.0        # inverse's copy of it
    for k in range(r.size):
        yk = plant_measure(A1, B1, C1, D1, A2, B2, C2, D2, s1, s2, mem, bl)
        e = r[k] - yk
        vd = _ss_output(Ac, Bc, Cc, Dc, sc, e)
        _ss_update(Ac, Bc, sc, e, wc)
        if use_ff:
            vd += _ss_output(Af, Bf, Cf, Df, sf, r_ahead[k])
            _ss_update(Af, Bf, sf, r_ahead[k], wf)
        if compensate:
            xi_prev, vi_prev = _inverse_step(vd, xi_prev, vi_prev, im1, im2,
                                             iD1, iD2, width)
            xd = xi_prev
            uk = _ss_output(Ai, Bi, Ci, Di, si, xd)
            _ss_update(Ai, Bi, si, xd, wi)
        else:
            uk = vd
        plant_advance(A1, B1, C1, D1, A2, B2, s1, s2, w1, w2, mem, bl, uk)
        y[k], u[k], x[k], v[k] = yk, uk, mem[2], mem[3]


def _check_loop(plant, controller, compensator):
    _check_model('plant', plant)
    if not isinstance(controller, TrackingController):
        raise TypeError(f"controller must be a sw.TrackingController (from "
                        f"sw.tracking_controller or "
                        f"sw.TrackingController.from_feedback); got "
                        f"{type(controller).__name__}")
    dt = common_dt('plant', plant.dt, 'controller', controller.feedback.dt)
    if compensator is not None:
        if not isinstance(compensator, SandwichCompensator):
            raise TypeError(f"compensator must be a sw.SandwichCompensator "
                            f"or None; got {type(compensator).__name__}")
        dt = common_dt('plant/controller', dt, 'compensator', compensator.dt)
    o = plant.orders
    if o['q1'] + o['q2'] == 0:
        raise ValueError("plant must have q1 + q2 >= 1: with no delay from u "
                         "to y the loop is algebraic")
    return dt


def closed_loop_response(plant, reference, controller, compensator=None):
    r"""Fast simulation of a sandwich plant under tracking control.

    The loop is ``u = comp[C(z)(r - y) + F(z) r_ahead]`` (without `comp`:
    ``u = C(z)(r - y) + F(z) r_ahead``), where r_ahead(k) = r(k + d) is the
    reference ``controller.preview`` samples ahead, held at its last value
    past the end. All systems start at rest. The result equals
    ``ct.input_output_response`` of `closed_loop_system` (tested to 1e-10)
    and is computed by a compiled kernel that calls `backlash_step` for the
    plant and for the compensator's model.

    Parameters
    ----------
    plant : SandwichSystem
        The (true) plant, with q1 + q2 >= 1.
    reference : array_like, shape (N,)
        Reference r(0), ..., r(N-1).
    controller : TrackingController
        From `tracking_controller`.
    compensator : SandwichCompensator, optional
        From `sandwich_compensator`, placed between controller and plant.

    Returns
    -------
    control.TimeResponseData
        Input r; outputs y, u, x, v (plant output, plant input, and the
        plant's internal backlash input and output).

    Raises
    ------
    ValueError
        If the sampling times disagree or the plant has no delay.

    Warns
    -----
    SimulationWarning
        If the loop is unstable and its output overflows.
    """
    if isinstance(controller, ServoController):
        return _servo_response(plant, reference, controller, compensator)
    dt = _check_loop(plant, controller, compensator)
    r = check_signal('reference', reference)
    d = controller.preview
    r_ahead = np.concatenate([r[d:], np.full(min(d, r.size), r[-1])])
    Af, Bf, Cf, Df = _ss_arrays(controller.feedforward)
    Ac, Bc, Cc, Dc = _ss_arrays(controller.feedback)
    if compensator is not None:
        inv = compensator.backlash_inverse
        Ai, Bi, Ci, Di = compensator._matrices
        ipar = (inv.m1, inv.m2, inv.D1, inv.D2, inv.smoothing)
    else:
        Ai, Bi, Ci, Di = _ss_arrays(None)
        ipar = (1.0, 1.0, 0.0, 0.0, 0.0)
    A1, B1, C1, D1 = _ss_arrays(plant.L1)
    A2, B2, C2, D2 = _ss_arrays(plant.L2)
    bl = plant.backlash
    n = r.size
    y, u, x, v = (np.empty(n) for _ in range(4))
    _closed_loop_kernel(r, r_ahead, Af, Bf, Cf, Df,
                        controller.feedforward is not None, Ac, Bc, Cc, Dc,
                        compensator is not None, Ai, Bi, Ci, Di, *ipar,
                        A1, B1, C1, D1, A2, B2, C2, D2,
                        np.array([bl.m1, bl.m2, bl.D1, bl.D2]), y, u, x, v)
    step = 1.0 if dt is True else float(dt)
    _warn_divergence(f"the closed loop of {plant.name}", y, u[-1:],
                     step * np.arange(n))
    return ct.TimeResponseData(
        step * np.arange(n), np.vstack([y, u, x, v]), None, r,
        issiso=False, output_labels=['y', 'u', 'x', 'v'],
        input_labels=['r'], sysname=plant.name,
        title=("Compensated" if compensator is not None else "Uncompensated")
        + f" closed loop of {plant.name}")


def _servo_response(plant, reference, ctrl, compensator):
    """`closed_loop_response` for a `ServoController`."""
    if compensator is not None:
        raise ValueError("a ServoController carries its own compensation; "
                         "pass compensator=None")
    if isinstance(plant, (SandwichSystem, ct.TransferFunction)):
        if isinstance(plant, ct.TransferFunction):
            check_discrete_siso_tf('plant', plant)
        dt = common_dt('plant', plant.dt, 'controller', ctrl.dt)
        lag = (plant.orders['q1'] + plant.orders['q2']
               if isinstance(plant, SandwichSystem)
               else plant.den[0][0].size - np.trim_zeros(
                   plant.num[0][0], 'f').size)
        if lag < 1:
            raise ValueError("plant must have at least one sample of delay "
                             "from u to y: without it the loop is algebraic")
        name = plant.name
    elif callable(getattr(plant, 'step', None)):
        dt = ctrl.dt
        name = type(plant).__name__
    else:
        raise TypeError(
            f"plant must be a SandwichSystem, a discrete TransferFunction or "
            f"an object with a step(u) -> y method; got "
            f"{type(plant).__name__}")
    r = check_signal('reference', reference)
    y, u = servo_loop(plant, r, ctrl)
    step = 1.0 if dt is True else float(dt)
    return ct.TimeResponseData(
        step * np.arange(r.size), np.vstack([y, u]), None, r,
        issiso=False, output_labels=['y', 'u'], input_labels=['r'],
        sysname=name, title=f"Servo loop of {name}")


def closed_loop_system(plant, controller, compensator=None, name=None):
    r"""The closed loop of `closed_loop_response` as a python-control system.

    Built with ``ct.interconnect`` from the plant, the controller blocks, a
    :math:`z^{-d}` block that turns the previewed reference r_ahead into r,
    summing junctions, and the compensator if given. Input 'r_ahead'
    (r(k + preview)); outputs 'y' and 'u'. Slow but independent of the
    compiled kernel, so it serves as its oracle.

    Parameters
    ----------
    plant : SandwichSystem
        The plant.
    controller : TrackingController
        From `tracking_controller`.
    compensator : SandwichCompensator, optional
        Placed between controller and plant.
    name : str, optional
        System name.

    Returns
    -------
    ClosedLoopSystem
        A ``control.InterconnectedSystem`` that also pickles (it is rebuilt
        from its parts; python-control's state-space blocks do not pickle).

    Examples
    --------
    >>> import pickle, numpy as np, control as ct, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> comp = sw.sandwich_compensator(plant)
    >>> ctrl = sw.tracking_controller(comp.design_plant)
    >>> loop = sw.closed_loop_system(plant, ctrl, comp, name='loop')
    >>> loop.input_labels, loop.output_labels
    (['r_ahead'], ['y', 'u'])
    >>> again = pickle.loads(pickle.dumps(loop))
    >>> r = np.ones(20)
    >>> a = ct.input_output_response(loop, np.arange(20), r).outputs
    >>> b = ct.input_output_response(again, np.arange(20), r).outputs
    >>> bool(np.array_equal(a, b))
    True
    """
    dt = _check_loop(plant, controller, compensator)
    name = check_name('name', name)
    parts = (plant, controller, compensator, name)
    d = controller.preview
    blocks = [SandwichSystem(plant.L1, plant.backlash, plant.L2,
                             name='plant', inputs='u', outputs='y'),
              ct.summing_junction(['r', '-y'], 'e', name='error', dt=dt),
              controller.feedback]
    if d > 0:
        blocks.append(ct.tf([1.0], np.eye(1, d + 1)[0], dt, inputs='r_ahead',
                            outputs='r', name='preview_delay'))
    else:
        blocks.append(ct.summing_junction(['r_ahead'], 'r', name='no_delay',
                                          dt=dt))
    act = 'v_d' if compensator is not None else 'u'
    if controller.feedforward is not None:
        blocks += [controller.feedforward,
                   ct.summing_junction(['v_fb', 'v_ff'], act, name='sum',
                                       dt=dt)]
    else:
        blocks.append(ct.summing_junction(['v_fb'], act, name='sum', dt=dt))
    if compensator is not None:
        blocks.append(SandwichCompensator(
            compensator.model, compensator.smoothing,
            compensator.band_fraction, compensator._approximate,
            name='compensator'))
    loop = ct.interconnect(blocks, inplist=['r_ahead'], outlist=['y', 'u'],
                           inputs=['r_ahead'], outputs=['y', 'u'], dt=dt,
                           name=name)
    loop.__class__ = ClosedLoopSystem
    loop._parts = parts
    return loop


class ClosedLoopSystem(ct.InterconnectedSystem):
    """The ``control.InterconnectedSystem`` built by `closed_loop_system`.

    It is the interconnection python-control returns, with pickling
    added: it is rebuilt from the plant, controller and compensator it was
    made of, and its name, signal names and parameters are then set as
    they were. ``copy`` and ``deepcopy`` copy it as any other system.
    """

    def __reduce__(self):
        parts = getattr(self, '_parts', None)
        if parts is None:
            raise TypeError("only a ClosedLoopSystem made by "
                            "closed_loop_system can be pickled")
        return (_rebuild_loop, (parts[:3], self.name, self.input_labels,
                                self.output_labels, self.state_labels,
                                dict(self.params)))

    def __copy__(self):
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        return new

    def __deepcopy__(self, memo):
        new = object.__new__(type(self))
        memo[id(self)] = new
        for key, value in self.__dict__.items():
            setattr(new, key, copy.deepcopy(value, memo))
        return new


def _rebuild_loop(parts, name, inputs, outputs, states, params):
    """Unpickle a `ClosedLoopSystem`: build it again, then restore its
    name, signal names and parameters."""
    loop = closed_loop_system(*parts, name=name)
    loop.set_inputs(inputs)
    loop.set_outputs(outputs)
    loop.set_states(states)
    loop.params = params
    return loop


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
        self.ratio = self.rms_with / self.rms_without
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
    return float(np.sqrt(np.mean(np.square(e))))
