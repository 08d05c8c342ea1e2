"""Closed loops of a `ServoController` around any plant.

`servo_loop` runs ``u(k) = ctrl.step(r(k + preview), y(k))`` against

- a `SandwichSystem` or a discrete linear transfer function: a compiled
  kernel steps plant and controller together;
- any object with a method ``step(u) -> y`` that applies u(k) for one
  sample and returns the next measurement y(k + 1) (a simulator of your
  own, a hardware-in-the-loop rig, ``sandwichctl.data.ServoDrive``): a
  Python loop. The first measurement is ``plant.read()`` where the plant
  has one, else 0 (at rest). An exception the plant's methods raise goes
  on as it is, with a note of the method, the sample and u (Python >=
  3.11).

`closed_loop_response` (module `closedloop`) calls it for a
`ServoController`. `servo_metrics` measures such a loop, and
`phase_margin` reads a loop's phase margin off its frequency response on
a grid (the servo design's and `tracking_controller`'s).
"""

import math

import numba
import numpy as np
import control as ct

from ._servo_kernel import servo_step
from ..model._coefficients import tf_to_ss
from ..model._kernel import _ss_output, _ss_update
from ..model.backlash import backlash_step
from ..model.sandwich import SandwichSystem, _warn_divergence
from .._checks import (DATA_RANGE, check_signal, check_positive,
                       check_nonnegative, check_real)

__all__ = ['servo_metrics']


def ss_arrays(sys):
    """(A, B, C, D) float arrays of a SISO system for the compiled loops;
    None gives a block without states and a zero gain."""
    if sys is None:
        return (np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)),
                np.zeros((1, 1)))
    ss = (tf_to_ss(sys) if isinstance(sys, ct.TransferFunction)
          else ct.ss(sys))
    return tuple(np.ascontiguousarray(np.asarray(M, dtype=float))
                 for M in (ss.A, ss.B, ss.C, ss.D))


@numba.njit(cache=True)
def plant_measure(A1, B1, C1, D1, A2, B2, C2, D2, s1, s2, mem, bl):
    """y(k) of a sandwich plant (blocks A1..D2, states s1, s2) before u(k)
    is chosen. mem is [x(k-1), v(k-1), x(k), v(k)]; when x(k) does not
    depend on u(k) (D1 = 0) x(k) and v(k) are written to it here."""
    if D1[0, 0] == 0.0:
        xk = _ss_output(A1, B1, C1, D1, s1, 0.0)
        mem[2], _ = backlash_step(xk, mem[0], mem[1], bl[0], bl[1], bl[2],
                                  bl[3])
        mem[3] = mem[2]
        mem[2] = xk
        return _ss_output(A2, B2, C2, D2, s2, mem[3])
    return _ss_output(A2, B2, C2, D2, s2, 0.0)


@numba.njit(cache=True)
def plant_advance(A1, B1, C1, D1, A2, B2, s1, s2, w1, w2, mem, bl, uk):
    """Apply u(k) to the plant of `plant_measure` and step it."""
    if D1[0, 0] != 0.0:
        mem[2] = _ss_output(A1, B1, C1, D1, s1, uk)
        mem[3], _ = backlash_step(mem[2], mem[0], mem[1], bl[0], bl[1],
                                  bl[2], bl[3])
    _ss_update(A1, B1, s1, uk, w1)
    _ss_update(A2, B2, s2, mem[3], w2)
    mem[0], mem[1] = mem[2], mem[3]


@numba.njit(cache=True)
def _loop_kernel(p, ix, s, r_ahead, A1, B1, C1, D1, A2, B2, C2, D2, bl,
                 y, u):
    """A sandwich plant (at rest) under the servo controller."""
    s1 = np.zeros(A1.shape[0])
    s2 = np.zeros(A2.shape[0])
    w1, w2 = np.empty(s1.size), np.empty(s2.size)
    mem = np.zeros(4)
    for k in range(r_ahead.size):
        yk = plant_measure(A1, B1, C1, D1, A2, B2, C2, D2, s1, s2, mem, bl)
        uk = servo_step(p, ix, s, r_ahead[k], yk)
        plant_advance(A1, B1, C1, D1, A2, B2, s1, s2, w1, w2, mem, bl, uk)
        y[k], u[k] = yk, uk


def servo_loop(plant, r, ctrl):
    """Run the loop from rest (the controller is reset); return y, u."""
    d = ctrl.preview
    r_ahead = np.concatenate([r[d:], np.full(min(d, r.size), r[-1])])
    n = r.size
    y, u = np.empty(n), np.empty(n)
    ctrl.reset()
    if isinstance(plant, (SandwichSystem, ct.TransferFunction,
                          ct.StateSpace)):
        if isinstance(plant, SandwichSystem):
            bl = plant.backlash
            blocks = ss_arrays(plant.L1) + ss_arrays(plant.L2)
            prm = np.array([bl.m1, bl.m2, bl.D1, bl.D2])
        else:
            blocks = (ss_arrays(plant)
                      + ss_arrays(ct.tf([1.0], [1.0], plant.dt)))
            prm = np.array([1.0, 1.0, 0.0, 0.0])
        _loop_kernel(ctrl._p, ctrl._ix, ctrl._s, r_ahead, *blocks, prm, y, u)
        _warn_divergence(f"the closed loop of {plant.name}", y, u[-1:],
                         np.arange(n))
        if not np.all(np.isfinite(ctrl._s)):
            ctrl.reset()        # a diverged memory would refuse every step
        return y, u
    if hasattr(plant, 'reset'):
        _call(plant.reset, 'reset()', 0)
    yk = (_measured(_call(plant.read, 'read()', 0), 'read()', 0)
          if hasattr(plant, 'read') else 0.0)
    for k in range(n):
        if not abs(yk) <= DATA_RANGE[1]:
            raise ValueError(
                f"the plant returned y = {yk!r} at sample {k} "
                f"({'read' if k == 0 else 'step'}): not finite or above "
                f"{DATA_RANGE[1]:g} in magnitude, which ctrl.step refuses; "
                f"the loop stops there")
        uk = servo_step(ctrl._p, ctrl._ix, ctrl._s, r_ahead[k], yk)
        if not math.isfinite(uk):
            raise OverflowError(
                f"u overflowed at sample {k} (y = {yk!r}, r_ahead = "
                f"{float(r_ahead[k])!r}): too large for the controller's "
                f"gains, so it was not applied to the plant (scale the data "
                f"as the design's model was identified)")
        y[k], u[k] = yk, uk
        if k + 1 < n:
            yk = _measured(_call(plant.step, 'step(u)', k + 1, uk),
                           'step(u)', k + 1)
    return y, u


def _call(method, call, k, *args):
    """A user plant's `method`(*args) for sample k; an exception it raises
    goes on, noting where the loop was (Python >= 3.11)."""
    try:
        return method(*args)
    except Exception as exc:
        if hasattr(exc, 'add_note'):
            exc.add_note(f"raised by plant.{call} at sample {k} of "
                         f"closed_loop_response"
                         + (f" (u = {args[0]!r})" if args else ""))
        raise


def _measured(value, call, k):
    """The float y a user plant's `call` returned for sample k."""
    if type(value) is float:
        return value
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(())[()]       # a one-element array: its y
    try:
        return check_real('y', value)
    except TypeError:
        raise TypeError(
            f"plant.{call} must return the measurement y as a real number; "
            f"got {type(value).__name__} {value!r} at sample {k}") from None


def _holds(r, shortest):
    """(start, stop) of the stretches where r stays constant for at least
    `shortest` samples."""
    same = np.r_[False, np.diff(r) == 0]
    edges = np.flatnonzero(np.diff(np.r_[0, same.astype(int), 0]))
    return [(a - 1, b) for a, b in zip(edges[::2], edges[1::2])
            if b - a + 1 >= shortest]


def _reversals(r):
    """Samples where r changes direction."""
    d = np.diff(r)
    moving = np.flatnonzero(d)
    turn = np.sign(d[moving[1:]]) != np.sign(d[moving[:-1]])
    return moving[1:][turn] + 1


def _turns(y, deadband):
    """Reversals of y, each counted once y has moved back by more than
    deadband from its last extreme."""
    turns, direction = 0, 0
    extreme = y[0] if y.size else 0.0
    for value in y:
        move = value - extreme
        if direction * move > 0:
            extreme = value                     # further the same way
        elif abs(move) > deadband:
            turns += direction != 0
            direction = 1 if move > 0 else -1
            extreme = value
    return int(turns)


def phase_margin(L):
    """(phase margin [deg], its grid index) of the loop L on a grid: the
    least angle from L to -1 where |L| crosses 1, in [0, 180]; (inf,
    None) where it never does."""
    cross = np.flatnonzero(np.diff(np.sign(np.abs(L) - 1)) != 0)
    if not cross.size:
        return np.inf, None
    away = 180 - np.degrees(np.abs(np.angle(L[cross])))
    return float(np.min(away)), int(cross[np.argmin(away)])


def _rms(e):
    """RMS of e, scaled by its peak so that large finite data do not
    overflow the squares."""
    peak = float(np.max(np.abs(e))) if e.size else 0.0
    if peak == 0.0 or not np.isfinite(peak):
        return peak
    return peak * float(np.sqrt(np.mean((e / peak) ** 2)))


def servo_metrics(reference, y, u, dt, window=0.1, hold=0.3, deadband=0.0):
    r"""How well a servo loop tracked: the figures of ``bench_servo.py``.

    Parameters
    ----------
    reference, y, u : array_like, shape (N,)
        Reference, measured output and input of a closed-loop run.
    dt : float
        Sample time in seconds.
    window : float, optional
        Seconds after each reversal of the reference that count as near
        it (default 0.1).
    hold : float, optional
        Shortest hold of the reference, in seconds, checked for hunting
        (default 0.3).
    deadband : float, optional
        A reversal of y counts once y has moved back by more than this
        from its last extreme (default 0; 1.5 encoder counts ignores the
        flicker of a reading between two counts).

    Returns
    -------
    dict
        'rms' and 'max' of the error r - y; 'near_reversals', the RMS
        error in the `window` after each reversal of r; 'activity', the
        total variation of u, :math:`\sum |u(k) - u(k-1)|`; 'hunting',
        the most reversals of y in the second half of a hold (3 or more
        is a limit cycle).

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> r = np.r_[np.zeros(50), np.ones(400)]
    >>> m = sw.servo_metrics(r, r, np.zeros(450), 1e-3)
    >>> m['rms'], m['hunting']
    (0.0, 0)
    """
    r = check_signal('reference', reference)
    y = check_signal('y', y, r.size, of='reference')
    u = check_signal('u', u, r.size, of='reference')
    dt = check_positive('dt', dt)
    deadband = check_nonnegative('deadband', deadband)
    window = check_nonnegative('window', window)
    hold = check_nonnegative('hold', hold)
    e = r - y
    hunting = 0
    # in samples, at most the record's (window / dt may overflow)
    shortest = max(2, int(round(min(hold / dt, r.size + 2.0))))
    for a, b in _holds(r, shortest):
        hunting = max(hunting, _turns(y[(a + b) // 2:b], deadband))
    win = max(1, int(round(min(window / dt, r.size + 2.0))))
    near = [e[k:k + win] for k in _reversals(r)]
    near = np.concatenate(near) if near else e
    return dict(rms=_rms(e), max=float(np.max(np.abs(e))),
                near_reversals=_rms(near),
                activity=float(np.sum(np.abs(np.diff(u)))),
                hunting=hunting)
