r"""Closed loops around a sandwich plant.

`closed_loop_response` runs a controller against a plant fast: a
`TrackingController` (module `tracking`) with an optional compensator in
front of a `SandwichSystem`, by a compiled kernel; a `ServoController`
(module `servo`) against any plant with a ``step(u) -> y`` method (module
`loop`). `closed_loop_system` builds the first loop as a python-control
system, its oracle. `closed_loop_demo` (module `demo`) compares loops with
and without compensation. `plot_loop` draws a `ServoController`'s
sensitivity on its model and on the plant's response as the
identification record measured it.

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

import numba
import numpy as np
import control as ct

from .inverse import _inverse_step
from .compensator import SandwichCompensator, _check_model
from .tracking import TrackingController
from .loop import servo_loop, plant_measure, plant_advance, ss_arrays
from .servo import ServoController
from ._servo_inputs import INPUT_MOST
from ._servo_design import frequency_grid, loop_gain, tf_arrays
from ..model._kernel import _ss_output, _ss_update
from ..model.sandwich import SandwichSystem, _warn_divergence
from .._checks import (check_discrete_siso_tf, check_real, check_signal,
                       common_dt, check_name, check_axes, named_copy)

__all__ = ['closed_loop_system', 'ClosedLoopSystem', 'closed_loop_response',
           'plot_loop']


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


def _check_loop(plant, controller, compensator,
                accepted="a sw.TrackingController"):
    """dt of a loop of a SandwichSystem and a TrackingController (and a
    compensator); `accepted` names the controllers the caller takes."""
    if not isinstance(controller, TrackingController):
        raise TypeError(f"controller must be {accepted} (from "
                        f"sw.tracking_controller or "
                        f"sw.TrackingController.from_feedback); got "
                        f"{type(controller).__name__}")
    _check_model('plant', plant)
    dt = common_dt('plant', plant.dt, 'controller', controller.feedback.dt)
    if compensator is not None:
        if not all(hasattr(compensator, a) for a in
                   ('inverse_parameters', 'linear_matrices', 'dt')):
            raise TypeError(f"compensator must be a sw.SandwichCompensator "
                            f"(or have its inverse_parameters, "
                            f"linear_matrices and dt) or None; got "
                            f"{type(compensator).__name__}")
        dt = common_dt('plant/controller', dt, 'compensator', compensator.dt)
    o = plant.orders
    if o['q1'] + o['q2'] == 0:
        raise ValueError("plant must have q1 + q2 >= 1: with no delay from u "
                         "to y the loop is algebraic")
    return dt


def closed_loop_response(plant, reference, controller, compensator=None):
    r"""Fast simulation of a closed loop: a servo controller on any plant,
    or a sandwich plant under tracking control.

    **With a** `ServoController` (from `servo_controller`) the plant is a
    `SandwichSystem`, a discrete SISO ``ct.TransferFunction`` or any object
    with a ``step(u) -> y`` method (a simulator of one's own, or
    hardware in the loop; optional ``reset()`` and ``read() -> y(0)`` are
    called first, and a ``dt`` attribute other than None or True must be
    a number equal to the controller's). The controller is reset, then at
    every sample ``u(k) = controller.step(r(k + preview), y(k))``, exactly
    as stepping it by hand; a u that overflows is not applied (the loop
    raises ``OverflowError``). The result has the outputs y and u. The
    controller starts at rest and reads r(preview) first, so it takes
    r(0), ..., r(preview - 1) as its rest: start the reference at rest.
    A loop that diverges leaves the controller reset.

    **With a** `TrackingController` (the paper's design), the plant is a
    `SandwichSystem` and the loop is
    ``u = comp[C(z)(r - y) + F(z) r_ahead]`` (without `comp`:
    ``u = C(z)(r - y) + F(z) r_ahead``), where r_ahead(k) = r(k + d) is the
    reference ``controller.preview`` samples ahead, held at its last value
    past the end. All systems start at rest. The result equals
    ``ct.input_output_response`` of `closed_loop_system` (tested to 1e-10)
    and is computed by a compiled kernel that calls `backlash_step` for the
    plant and for the compensator's model.

    Parameters
    ----------
    plant : SandwichSystem, TransferFunction, StateSpace or object with step(u)
        The (true) plant, with at least one sample of delay from u to y
        (a discrete SISO TransferFunction or StateSpace, or an object
        whose ``step(u)`` returns y as a number or a one-element array,
        only with a `ServoController`).
    reference : array_like, shape (N,)
        Reference r(0), ..., r(N-1).
    controller : ServoController or TrackingController
        From `servo_controller`, or from `tracking_controller`.
    compensator : SandwichCompensator, optional
        From `sandwich_compensator`, placed between a `TrackingController`
        and the plant (a `ServoController` carries its own).

    Returns
    -------
    control.TimeResponseData
        Input r; outputs y and u with a `ServoController`; with a
        `TrackingController` y, u, x, v (plant output, plant input, and
        the plant's internal backlash input and output).

    Raises
    ------
    ValueError
        If the sampling times disagree or the plant has no delay, or,
        with a `ServoController`, the reference or a user's plant's y is
        not finite or above 1e100 in magnitude (what ``ctrl.step``
        refuses).
    OverflowError
        If a `ServoController`'s u overflows against a user's plant.

    Warns
    -----
    SimulationWarning
        If the loop is unstable and its output overflows.
    """
    if isinstance(controller, ServoController):
        return _servo_response(plant, reference, controller, compensator)
    dt = _check_loop(plant, controller, compensator, "a sw.ServoController "
                     "(from sw.servo_controller) or a sw.TrackingController")
    r = check_signal('reference', reference)
    d = controller.preview
    r_ahead = np.concatenate([r[d:], np.full(min(d, r.size), r[-1])])
    Af, Bf, Cf, Df = ss_arrays(controller.feedforward)
    Ac, Bc, Cc, Dc = ss_arrays(controller.feedback)
    if compensator is not None:
        Ai, Bi, Ci, Di = compensator.linear_matrices
        ipar = compensator.inverse_parameters
    else:
        Ai, Bi, Ci, Di = ss_arrays(None)
        ipar = (1.0, 1.0, 0.0, 0.0, 0.0)
    A1, B1, C1, D1 = ss_arrays(plant.L1)
    A2, B2, C2, D2 = ss_arrays(plant.L2)
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
    if isinstance(plant, (SandwichSystem, ct.TransferFunction,
                          ct.StateSpace)):
        if isinstance(plant, SandwichSystem):
            lag = plant.orders['q1'] + plant.orders['q2']
        elif isinstance(plant, ct.TransferFunction):
            check_discrete_siso_tf('plant', plant)
            lag = plant.den[0][0].size - np.trim_zeros(plant.num[0][0],
                                                       'f').size
        else:
            if not (plant.isdtime(strict=True) and plant.issiso()):
                raise ValueError(
                    f"a StateSpace plant must be discrete-time and SISO; "
                    f"got dt={plant.dt!r}, {plant.ninputs} input(s), "
                    f"{plant.noutputs} output(s)")
            lag = int(not np.any(plant.D))   # a sample of delay, or none
        dt = common_dt('plant', plant.dt, 'controller', ctrl.dt)
        if lag < 1:
            raise ValueError("plant must have at least one sample of delay "
                             "from u to y: without it the loop is algebraic")
        name = plant.name
    elif callable(getattr(plant, 'step', None)):
        own, dt = getattr(plant, 'dt', None), ctrl.dt
        if own is not None and own is not True and not (
                isinstance(own, np.bool_) and own):
            # None and True (python-control's "some discrete time") say
            # nothing; a number must be the controller's
            try:
                own = check_real('plant.dt', own)
            except TypeError:
                raise TypeError(f"plant.dt must be a number, True or None; "
                                f"got {type(own).__name__} {own!r}") from None
            if dt is not True and not np.isclose(own, dt, rtol=1e-9,
                                                 atol=0.0):
                raise ValueError(f"plant and controller must have the same "
                                 f"sampling time; got plant.dt={own!r} and "
                                 f"controller dt={dt!r}")
        for method in ('reset', 'read'):
            if hasattr(plant, method) and not callable(getattr(plant,
                                                               method)):
                raise TypeError(f"plant.{method} must be a method (called "
                                f"before the first sample); got "
                                f"{type(getattr(plant, method)).__name__}")
        name = type(plant).__name__
    else:
        raise TypeError(
            f"plant must be a SandwichSystem, a discrete TransferFunction "
            f"or StateSpace, or an object with a step(u) -> y method; got "
            f"{type(plant).__name__}")
    r = check_signal('reference', reference)
    if not np.max(np.abs(r)) <= INPUT_MOST:
        raise ValueError(
            f"reference must be at most {INPUT_MOST:g} in magnitude, as "
            f"ctrl.step's r_ahead; got {float(np.max(np.abs(r))):g}")
    if r.size <= ctrl.preview:
        raise ValueError(
            f"reference has {r.size} samples, and the controller reads it "
            f"{ctrl.preview} samples ahead (ctrl.preview): give more than "
            f"{ctrl.preview} samples (hold the last value)")
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
    if isinstance(controller, ServoController):
        raise TypeError("closed_loop_system takes a sw.TrackingController; a "
                        "sw.ServoController is a python-control system "
                        "itself (inputs 'r_ahead' and 'y', output 'u'): "
                        "connect it to the plant with ct.interconnect, or "
                        "run the loop with sw.closed_loop_response")
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
            compensator.band_fraction, compensator.approximate,
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

    copy = named_copy            # its name checked

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


def plot_loop(ctrl, ax=None):
    r"""Plot a servo loop's sensitivity :math:`|S| = 1 / |1 + C P|` on its
    model and on the plant's response as the identification record
    measured it.

    The design holds its modulus margin, :math:`\min |1 + C P|`, on the
    measured response where the record has it (``ctrl.margins
    ['modulus_measured']``, in the title): where the two curves part,
    the record says the model is wrong there, and the measured one is the
    loop the axis will see. The peak of each is marked.

    Parameters
    ----------
    ctrl : ServoController
        A design of `servo_controller`.
    ax : matplotlib.axes.Axes, optional
        Axes to draw on; default the current axes.

    Returns
    -------
    matplotlib.axes.Axes
        The axes drawn on: frequency in Hz (in rad/sample when the model's
        dt is True), :math:`|S|` on a log scale.

    Raises
    ------
    TypeError
        If `ctrl` is not a `ServoController` or `ax` not an Axes.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use('Agg')
    >>> import matplotlib.pyplot as plt, control as ct, sandwichctl as sw
    >>> ctrl = sw.servo_controller(ct.tf([0.1], [1, -0.9], 0.001))
    >>> ax = sw.plot_loop(ctrl, ax=plt.figure().add_subplot())
    >>> ax.get_ylabel()
    '|S| = 1 / |1 + C P|'
    """
    if not isinstance(ctrl, ServoController):
        raise TypeError(f"ctrl must be a ServoController (of "
                        f"sw.servo_controller); got {type(ctrl).__name__}")
    if check_axes('ax', ax) is None:
        import matplotlib.pyplot as plt
        ax = plt.gca()
    num, den = tf_arrays(ctrl.design_plant)
    w, one = frequency_grid(den), np.ones(1)
    curves = [(w, loop_gain(num, den, ctrl.pid, w), 'on the model', '-')]
    if ctrl.measured_response is not None:
        wm, G = ctrl.measured_response
        curves.append((wm, G * loop_gain(one, one, ctrl.pid, wm),
                       'on the measured response', '--'))
    hz = ctrl.dt is not True
    for wk, L, label, style in curves:
        S = 1 / np.abs(1 + L)
        f = wk / (2 * np.pi * ctrl.dt) if hz else wk
        top = np.argmax(S)
        line, = ax.loglog(f, S, style, lw=1.6, label=(
            f"{label}, up to {f[-1]:.3g} {'Hz' if hz else 'rad/sample'}"
            if style == '--' else
            f"{label} (modulus margin {1 / S[top]:.3f})"))
        ax.plot(f[top], S[top], 'o', color=line.get_color())
    ax.axhline(1.0, color='grey', lw=0.8)
    ax.set_xlabel('frequency (Hz)' if hz else 'frequency (rad/sample)')
    ax.set_ylabel('|S| = 1 / |1 + C P|')
    held = ctrl.margins['modulus_measured']
    ax.set_title('Sensitivity of the servo loop' + (
        '' if np.isnan(held) else f': modulus margin {held:.3f} held'))
    ax.legend(fontsize='small')
    return ax
