r"""Inverse compensation of sandwich systems.

A compensator placed in front of a sandwich system L1 -> backlash -> L2
cancels the backlash and L1, so that a linear controller only sees L2:

.. code-block:: text

          compensator (SandwichCompensator)     plant (SandwichSystem)
    v_d ─► B^-1 ─x_d─► z^-q1 L1^-1 ─u─►  L1 ─x─► backlash ─v─► L2 ─► y
           (BacklashInverse) (causal_inverse)

With an exact model, ``x(k) = x_d(k - q1)`` and ``v(k) = v_d(k - q1)``, so
the compensated plant from v_d to y is the linear system
:math:`z^{-q_1} L_2(z)` (`SandwichCompensator.design_plant`).

Backlash inverse
----------------
`BacklashInverse` is the right inverse of eq. (2.2) in the style of Tao and
Kokotović [1]_. Its state is a copy of the backlash memory,
:math:`[x(k-1), \hat v(k-1)]`, laid out exactly like the state of
`Backlash`; :math:`\hat v(k-1)` is the backlash output the inverse expects
(equal to :math:`v_d(k-1)` whenever the inversion was exact). With
:math:`\Delta(k) = v_d(k) - \hat v(k-1)`,

.. math::

    x(k) = \begin{cases}
      \max\{v_d(k)/m_1 + D_1,\ x(k-1)\} & \Delta(k) > 0
                                          \quad\text{(rise: increase line)}\\
      \min\{v_d(k)/m_2 - D_2,\ x(k-1)\} & \Delta(k) < 0
                                          \quad\text{(fall: decrease line)}\\
      x(k-1)                            & \Delta(k) = 0
                                          \quad\text{(hold)}
    \end{cases}

and the state is advanced with `backlash_step` itself, so the inverse and
the backlash share one implementation of eq. (2.2). (When eq. (2.2) takes
the intended line, :math:`\hat v(k)` is set to :math:`v_d(k)` rather than
to the rounded :math:`m_1(x(k) - D_1)`: otherwise a repeated v_d could
differ from :math:`\hat v` by one ulp and make x jump across the band.)
Fed with this x(k),
eq. (2.2) returns exactly :math:`v_d(k)`: when rising,
:math:`x(k) = v_d/m_1 + D_1 > \hat v(k-1)/m_1 + D_1 \ge x(k-1)` (the memory
of a backlash always lies in its band
:math:`\hat v/m_2 - D_2 \le x \le \hat v/m_1 + D_1`), so both strict
inequalities of the increase zone hold; falling is symmetric; and holding x
gives x(k) = x(k-1), which eq. (2.2) answers with the memory zone.

The ``max``/``min`` only act beyond the crossing point of the slope lines
(`Backlash.crossing`), where the band is empty and some values of v_d cannot
be reached by a monotone step of x: there the inverse holds x until v_d is
reachable again. Elsewhere the inverse is exact.

Smoothing
---------
The exact inverse jumps across the whole band, D1 + D2 wide, whenever v_d
reverses, which makes x chatter when v_d is noisy or when the estimated
band is too wide. With ``smoothing`` = :math:`\delta > 0` the jump is
spread over changes of v_d smaller than :math:`\delta`:

.. math::

    x(k) = x(k-1) + s\big(|\Delta(k)|/\delta\big)\,(e(k) - x(k-1))
                 + \Delta(k)/m_i,
    \qquad s(t) = \begin{cases} 3t^2 - 2t^3 & t < 1 \\ 1 & t \ge 1
                  \end{cases}

where :math:`e(k)` is the edge of the band on the side of motion
(:math:`\hat v(k-1)/m_1 + D_1` when rising, :math:`\hat v(k-1)/m_2 - D_2`
when falling) and :math:`m_i` the slope of that side. x(k) is then a
continuous, monotone function of v_d(k) with slope :math:`1/m_i` at
:math:`\Delta = 0`; changes of at least :math:`\delta` are inverted
exactly, and a held v_d is reached within a few samples without overshoot.

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

References
----------
.. [1] G. Tao and P. V. Kokotović, "Adaptive control of plants with unknown
   hystereses", IEEE Trans. Automatic Control 40(2), 1995; and *Adaptive
   Control of Systems with Actuator and Sensor Nonlinearities*, Wiley, 1996.
"""

import warnings

import numba
import numpy as np
import control as ct

from .backlash import Backlash, backlash_step
from .sandwich import SandwichSystem
from ._kernel import _ss_output, _ss_update
from ._validation import (check_discrete_siso_tf, check_nonnegative,
                          check_positive, check_signal, common_dt)

__all__ = ['BacklashInverse', 'backlash_inverse', 'backlash_inverse_response',
           'causal_inverse', 'SandwichCompensator', 'sandwich_compensator',
           'TrackingController', 'tracking_controller', 'linearized_plant',
           'closed_loop_system', 'closed_loop_response', 'steps_and_sines',
           'CompensationDemo', 'closed_loop_demo']


# ----------------------------------------------------------------------
# Backlash inverse
# ----------------------------------------------------------------------
@numba.njit(cache=True)
def _inverse_step(v_d, x_prev, v_prev, m1, m2, D1, D2, width):
    """One step of the (smoothed) right inverse of eq. (2.2).

    Return ``(x, v_hat)``: the backlash input x(k) and the backlash output
    the inverse expects, its next memory. When x(k) is on the intended
    slope line (eq. (2.2) takes the increase or decrease zone), v_hat is
    v_d(k) itself, so that an exact tie v_d(k+1) = v_d(k) is recognised
    as a hold despite rounding in m (x - D); otherwise (smoothed or held
    steps) v_hat is what `backlash_step` returns for x(k).
    """
    dv = v_d - v_prev
    if dv == 0.0:
        return x_prev, v_prev
    zone = 1 if dv > 0.0 else -1
    if width > 0.0 and abs(dv) < width:
        t = abs(dv) / width
        if zone == 1:
            edge, m = v_prev / m1 + D1, m1
        else:
            edge, m = v_prev / m2 - D2, m2
        x = x_prev + t * t * (3.0 - 2.0 * t) * (edge - x_prev) + dv / m
        exact = False
    else:
        x = v_d / m1 + D1 if zone == 1 else v_d / m2 - D2
        exact = True
    if zone * (x - x_prev) <= 0.0:    # unreachable by a monotone step
        return x_prev, v_prev
    v_hat, z = backlash_step(x, x_prev, v_prev, m1, m2, D1, D2)
    if exact and z == zone:
        v_hat = v_d
    return x, v_hat


@numba.njit(cache=True)
def _inverse_loop(v_d, m1, m2, D1, D2, width, x_prev, v_prev, x, v_hat):
    for k in range(v_d.size):
        x_prev, v_prev = _inverse_step(v_d[k], x_prev, v_prev, m1, m2, D1,
                                       D2, width)
        x[k] = x_prev
        v_hat[k] = v_prev


def backlash_inverse_response(v_d, m1, m2, D1, D2, x_prev=0.0, v_prev=0.0,
                              smoothing=0.0, return_expected=False):
    r"""Output of the backlash inverse for a whole sequence of desired v.

    The same map as `BacklashInverse` (see the module notes), over a whole
    signal and compiled. Feeding the result to `backlash_response` with the
    same parameters and the same memory returns `v_d` (exactly, up to
    rounding, when ``smoothing`` is 0 and v_d stays on the side of the
    slope-line crossing where the band is not empty).

    Parameters
    ----------
    v_d : array_like, shape (N,)
        Desired backlash output v_d(0), ..., v_d(N-1).
    m1, m2 : float
        Slopes of the increase and decrease lines of the backlash to invert,
        0 < m < inf.
    D1, D2 : float
        Its thresholds, >= 0.
    x_prev, v_prev : float, optional
        The memory at k = 0, x(-1) and v(-1), shared with the backlash
        (consistent when ``v_prev/m2 - D2 <= x_prev <= v_prev/m1 + D1``).
        Default 0, 0.
    smoothing : float, optional
        Width :math:`\delta` over which the jump across the band is spread,
        in units of v; 0 (default) gives the exact inverse.
    return_expected : bool, optional
        Also return :math:`\hat v`, the backlash output the inverse expects.

    Returns
    -------
    x : ndarray, shape (N,)
        The backlash input that produces v_d.
    v_hat : ndarray, shape (N,)
        Only if `return_expected` is True.

    See Also
    --------
    BacklashInverse : the same map as a python-control system.
    backlash_response : the backlash of eq. (2.2) it inverts.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> v_d = [0.0, 1.0, 1.0, 0.5, 0.8]
    >>> x = sw.backlash_inverse_response(v_d, 1, 1.2, 0.5, 0.6)
    >>> print(x.round(4))
    [ 0.      1.5     1.5    -0.1833  1.3   ]
    >>> print(sw.backlash_response(x, 1, 1.2, 0.5, 0.6))
    [0.  1.  1.  0.5 0.8]
    """
    m1 = check_positive('m1', m1)
    m2 = check_positive('m2', m2)
    D1 = check_nonnegative('D1', D1)
    D2 = check_nonnegative('D2', D2)
    width = check_nonnegative('smoothing', smoothing)
    v_d = check_signal('v_d', v_d)
    x, v_hat = np.empty_like(v_d), np.empty_like(v_d)
    _inverse_loop(v_d, m1, m2, D1, D2, width, float(x_prev), float(v_prev),
                  x, v_hat)
    return (x, v_hat) if return_expected else x


def _inverse_update(t, state, inp, params):
    p = params
    return np.array(_inverse_step(inp[0], state[0], state[1], p['m1_hat'],
                                  p['m2_hat'], p['D1_hat'], p['D2_hat'],
                                  p['smoothing']))


def _inverse_output(t, state, inp, params):
    p = params
    return np.array(_inverse_step(inp[0], state[0], state[1], p['m1_hat'],
                                  p['m2_hat'], p['D1_hat'], p['D2_hat'],
                                  p['smoothing'])[:1])


class BacklashInverse(ct.NonlinearIOSystem):
    r"""Right inverse of the backlash of eq. (2.2), as a discrete I/O system.

    Input v_d (desired backlash output), output x (backlash input). The two
    states are the backlash memory [x(k-1), v̂(k-1)], in the same order as
    the states of `Backlash`, so "consistent initial states" means giving
    both systems the same ``initial_state``. The output is a pure function of
    (state, input). See the module notes for the map and its exactness.

    Parameters
    ----------
    m1, m2 : float
        Slopes of the backlash to invert, 0 < m < inf.
    D1, D2 : float
        Its thresholds, 0 <= D < inf.
    smoothing : float, optional
        Width :math:`\delta` (in units of v) over which the jump across the
        band is spread to avoid chattering; 0 (default) is the exact inverse.
    dt : float or True, optional
        Sampling time (default True: discrete, unspecified).
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'x'.
    states : list of str, optional
        State names; default ['x_prev', 'v_prev'].

    Notes
    -----
    The parameters are stored as python-control params named ``m1_hat``,
    ``m2_hat``, ``D1_hat``, ``D2_hat`` (the estimates being inverted) and
    ``smoothing``, not ``m1``...: python-control merges the params of all
    blocks of an interconnection into one dict and pushes it back to every
    block, so an inverse whose params were called ``m1``... would silently
    take the plant backlash's values (or give them its own).

    See Also
    --------
    backlash_inverse : build it from a `Backlash`.
    backlash_inverse_response : the same map over a whole sequence.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> bl = sw.Backlash(1.0, 1.2, 0.5, 0.6, dt=1)
    >>> inv = sw.backlash_inverse(bl)
    >>> both = ct.series(inv, bl)            # v_d -> x -> v
    >>> resp = ct.input_output_response(both, np.arange(5),
    ...                                 [0, 1, 1, 0.5, 0.8])
    >>> print(resp.outputs)
    [0.  1.  1.  0.5 0.8]
    """

    def __init__(self, m1, m2, D1, D2, smoothing=0.0, dt=True, name=None,
                 inputs='v_d', outputs='x', states=('x_prev', 'v_prev')):
        params = {'m1_hat': check_positive('m1', m1),
                  'm2_hat': check_positive('m2', m2),
                  'D1_hat': check_nonnegative('D1', D1),
                  'D2_hat': check_nonnegative('D2', D2),
                  'smoothing': check_nonnegative('smoothing', smoothing)}
        _check_dt('dt', dt)
        super().__init__(
            _inverse_update, _inverse_output, inputs=inputs, outputs=outputs,
            states=list(states), dt=dt, name=name, params=params)

    m1 = property(lambda self: self.params['m1_hat'], doc="Increase slope.")
    m2 = property(lambda self: self.params['m2_hat'], doc="Decrease slope.")
    D1 = property(lambda self: self.params['D1_hat'],
                  doc="Increase threshold.")
    D2 = property(lambda self: self.params['D2_hat'],
                  doc="Decrease threshold.")
    smoothing = property(lambda self: self.params['smoothing'],
                         doc="Smoothing width (0: exact inverse).")

    def response(self, v_d, x_prev=0.0, v_prev=0.0, return_expected=False):
        """Output for a whole sequence; see `backlash_inverse_response`."""
        return backlash_inverse_response(
            v_d, self.m1, self.m2, self.D1, self.D2, x_prev, v_prev,
            self.smoothing, return_expected)

    def __repr__(self):
        return (f"BacklashInverse(m1={self.m1:.6g}, m2={self.m2:.6g}, "
                f"D1={self.D1:.6g}, D2={self.D2:.6g}, "
                f"smoothing={self.smoothing:.6g}, dt={self.dt!r}, "
                f"name={self.name!r})")


def backlash_inverse(backlash, smoothing=0.0, dt=None, name=None,
                     inputs='v_d', outputs='x'):
    r"""Right inverse of a backlash (Tao-Kokotović style), as an I/O system.

    Parameters
    ----------
    backlash : Backlash
        The backlash to invert (its m1, m2, D1, D2 are used). To see the
        effect of wrong parameters, pass ``backlash.copy_with(m1=...)``.
    smoothing : float, optional
        Width :math:`\delta` over which the switching is smoothed, in units
        of v (default 0: exact inverse); see the module notes.
    dt : float or True, optional
        Sampling time; default that of `backlash`. A different sampling time
        raises ValueError.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'x'.

    Returns
    -------
    BacklashInverse

    Raises
    ------
    TypeError
        If `backlash` is not a `Backlash`.
    ValueError
        If `smoothing` < 0 or `dt` disagrees with ``backlash.dt``.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> inv = sw.backlash_inverse(sw.Backlash(1, 1.2, 0.5, 0.6, dt=1),
    ...                           name='inv')
    >>> inv
    BacklashInverse(m1=1, m2=1.2, D1=0.5, D2=0.6, smoothing=0, dt=1,
                    name='inv')
    """
    if not isinstance(backlash, Backlash):
        hint = (" (for a SandwichSystem use sw.sandwich_compensator(model) "
                "or model.backlash)"
                if isinstance(backlash, SandwichSystem) else "")
        raise TypeError(f"backlash must be a sandwichctl.Backlash{hint}; got "
                        f"{type(backlash).__name__}")
    dt = backlash.dt if dt is None else common_dt(
        'backlash', backlash.dt, 'the requested inverse', _check_dt('dt', dt))
    return BacklashInverse(backlash.m1, backlash.m2, backlash.D1, backlash.D2,
                           smoothing=smoothing, dt=dt, name=name,
                           inputs=inputs, outputs=outputs)


# ----------------------------------------------------------------------
# Inverse of the linear block
# ----------------------------------------------------------------------
def causal_inverse(sys, approximate=False, name=None):
    r"""Stable causal inverse :math:`z^{-q} G(z)^{-1}` of a discrete SISO G.

    `q` is the relative degree of G (its delay: q1 for L1 of eq. (2.1)), so
    the inverse is biproper and ``G * causal_inverse(G)`` is :math:`z^{-q}`:
    the best any causal compensator can do is to reproduce its input q
    samples late.

    Parameters
    ----------
    sys : control.TransferFunction
        Proper, discrete-time SISO transfer function (e.g. ``model.L1``).
    approximate : bool, optional
        What to do if `sys` is non-minimum-phase (a zero with modulus > 1,
        which would be an unstable pole of the inverse). False (default):
        raise ValueError. True: return the stable approximate inverse that
        reflects every such zero :math:`z_i` to :math:`1/\bar z_i`, scaled
        to keep the DC gain; then ``G * causal_inverse(G, True)`` is
        :math:`z^{-q}` times an all-pass filter with unit DC gain (exact
        steady state, phase error at higher frequencies).
    name : str, optional
        System name.

    Returns
    -------
    control.TransferFunction
        The inverse, with the sampling time of `sys`.

    Raises
    ------
    ValueError
        If `sys` has a zero outside the unit circle and `approximate` is
        False, or a zero on the unit circle (whose reflection is itself, so
        no stable inverse exists).

    Examples
    --------
    >>> import control as ct, sandwichctl as sw
    >>> L1 = ct.tf([1.5, 0], [1, 0.1, 0.2], 1)      # x(k) = ... + 1.5 u(k-1)
    >>> Linv = sw.causal_inverse(L1)
    >>> print(ct.minreal(L1 * Linv, verbose=False))  # doctest: +ELLIPSIS
    <TransferFunction>: sys...
    ...
      1
      -
      z
    <BLANKLINE>
    """
    return _causal_inverse(sys, approximate, name)[0]


def _causal_inverse(sys, approximate, name=None):
    """`causal_inverse` and whether zeros were reflected."""
    num, den = check_discrete_siso_tf('sys', sys)
    q = den.size - num.size
    zeros = np.roots(num) if num.size > 1 else np.zeros(0)
    gain = num[0]
    on_circle = np.abs(np.abs(zeros) - 1.0) <= 1e-9
    outside = (np.abs(zeros) > 1.0) & ~on_circle
    if on_circle.any():
        raise ValueError(
            f"sys has zero(s) on the unit circle at "
            f"{_fmt_roots(zeros[on_circle])}; their inverse would be a "
            f"marginally stable pole and no stable approximate inverse "
            f"exists by reflection")
    if outside.any():
        if not approximate:
            raise ValueError(
                f"sys is non-minimum-phase: zero(s) at "
                f"{_fmt_roots(zeros[outside])} lie outside the unit circle, "
                f"so its exact inverse is unstable. Pass approximate=True "
                f"for the stable approximate inverse that reflects them "
                f"inside the unit circle")
        for zi in zeros[outside]:
            gain *= (1.0 - zi) / (1.0 - 1.0 / np.conj(zi))
        zeros = zeros.astype(complex)
        zeros[outside] = 1.0 / np.conj(zeros[outside])
        gain = np.real_if_close(gain)
        if np.iscomplexobj(gain):
            gain = gain.real
    new_num = float(gain) * np.real(np.poly(zeros)) if zeros.size else \
        np.array([float(gain)])
    inv_den = np.concatenate([new_num, np.zeros(q)])
    return ct.tf(den, inv_den, sys.dt, name=name), bool(outside.any())


def _fmt_roots(roots):
    return ', '.join(f"{complex(r):.4g}".strip('()') if np.iscomplex(r)
                     else f"{float(np.real(r)):.4g}" for r in roots)


# ----------------------------------------------------------------------
# Compensator for a whole sandwich
# ----------------------------------------------------------------------
class SandwichCompensator(ct.InterconnectedSystem):
    r"""Inverse compensator of a sandwich: backlash inverse, then L1 inverse.

    An interconnected python-control system with input v_d (the backlash
    output wanted) and output u (the plant input). Put it in front of the
    plant; a controller designed for `design_plant` then sees a linear plant.
    Its state vector is ``[x_prev, v_prev, L1-inverse states]``; from zero
    state in front of a plant at rest, the loop is consistent. Build it with
    `sandwich_compensator`.

    Parameters
    ----------
    model : SandwichSystem
        The model to invert.
    smoothing, band_fraction, approximate : optional
        See `sandwich_compensator`.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'u'.

    Attributes
    ----------
    model : SandwichSystem
        The model the compensator inverts (known or identified).
    backlash_inverse : BacklashInverse
        The backlash inverse, v_d -> x_d.
    L1_inverse : control.TransferFunction
        :math:`z^{-q_1} L_1^{-1}` (see `causal_inverse`), x_d -> u.
    design_plant : control.TransferFunction
        :math:`z^{-q_1} L_2`: the plant from v_d to y once compensated
        (exactly, if the model is exact and `is_exact`).
    delay : int
        q1, the delay between v_d and v.
    """

    def __init__(self, model, smoothing=0.0, band_fraction=1.0,
                 approximate=False, name=None, inputs='v_d', outputs='u'):
        if not isinstance(model, SandwichSystem):
            raise TypeError(
                f"model must be a sandwichctl.SandwichSystem (known or "
                f"identified, e.g. sw.examples.paper_plant()); got "
                f"{type(model).__name__}")
        co = model.coefficients
        band_fraction = check_positive('band_fraction', band_fraction)
        if band_fraction > 1:
            raise ValueError(f"band_fraction must be in (0, 1] (the share of "
                             f"the model's band to compensate); got "
                             f"{band_fraction!r}")
        self._model = model
        self._band_fraction = band_fraction
        self._approximate = bool(approximate)
        self._L1_inverse, reflected = _causal_inverse(model.L1, approximate)
        self._exact_L1 = not reflected
        self._delay = co['q1']
        self._design_plant = ct.tf(
            model.L2.num[0][0], np.polymul(model.L2.den[0][0],
                                           np.eye(1, co['q1'] + 1)[0]),
            model.dt)
        inv = BacklashInverse(co['m1'], co['m2'], band_fraction * co['D1'],
                              band_fraction * co['D2'],
                              smoothing=smoothing, dt=model.dt,
                              name='backlash_inverse', inputs='v_d',
                              outputs='x_d')
        self._inverse = inv
        lin = ct.ss(self._L1_inverse, inputs='x_d', outputs='u',
                    name='L1_inverse')
        self._matrices = tuple(np.ascontiguousarray(np.asarray(M, float))
                               for M in (lin.A, lin.B, lin.C, lin.D))
        super().__init__(
            [inv, lin],
            connections=[['L1_inverse.x_d', 'backlash_inverse.x_d']],
            inplist=['backlash_inverse.v_d'], outlist=['L1_inverse.u'],
            inputs=inputs, outputs=outputs, dt=model.dt, name=name)

    model = property(lambda self: self._model,
                     doc="The inverted model (a SandwichSystem).")
    backlash_inverse = property(lambda self: self._inverse,
                                doc="The backlash inverse (v_d -> x_d).")
    L1_inverse = property(lambda self: self._L1_inverse,
                          doc="z^-q1 L1^-1 (x_d -> u), a TransferFunction.")
    design_plant = property(lambda self: self._design_plant,
                            doc="z^-q1 L2: the compensated plant v_d -> y.")
    delay = property(lambda self: self._delay, doc="q1 (samples).")
    smoothing = property(lambda self: self._inverse.smoothing,
                         doc="Smoothing width of the backlash inverse.")
    band_fraction = property(lambda self: self._band_fraction,
                             doc="Share of the model's thresholds inverted.")

    @property
    def is_exact(self):
        """True if the compensation is exact for an exact model.

        False if the backlash inverse is smoothed, compensates only part of
        the band, or L1's inverse had to be approximated (non-minimum-phase
        L1).
        """
        return (self.smoothing == 0 and self._band_fraction == 1
                and self._exact_L1)

    def __str__(self):
        return (f"<SandwichCompensator>: {self.name}, "
                f"{self.input_labels[0]} -> {self.output_labels[0]}, "
                f"dt = {self.dt}\n  {self._inverse!r}\n"
                f"  L1 inverse z^-{self._delay} L1^-1 = "
                f"{_tf_text(self._L1_inverse)}"
                + ("  (approximate: non-minimum-phase L1)"
                   if not self._exact_L1 else ""))

    __repr__ = __str__


def _tf_text(tf):
    num = ' '.join(f"{c:+.4g}" for c in tf.num[0][0])
    den = ' '.join(f"{c:+.4g}" for c in tf.den[0][0])
    return f"[{num}] / [{den}]"


def sandwich_compensator(model, smoothing=0.0, band_fraction=1.0,
                         approximate=False, name=None, inputs='v_d',
                         outputs='u'):
    r"""Inverse compensator for a sandwich system, ready for ct.interconnect.

    The compensator is the backlash inverse of `model` followed by the
    causal inverse :math:`z^{-q_1} L_1^{-1}` of its L1 (see the module
    notes). With an exact model, the compensated plant from v_d to y is the
    linear :math:`z^{-q_1} L_2` (``comp.design_plant``), so any linear
    design method applies.

    Parameters
    ----------
    model : SandwichSystem
        The model to invert: known, or identified (e.g. ``res.model`` of the
        identifier, which is normalised; any equivalent representation gives
        the same compensated plant).
    smoothing : float, optional
        Smoothing width of the backlash inverse, in units of the model's v
        (default 0: exact).
    band_fraction : float, optional
        Share of the model's thresholds D1, D2 that the inverse compensates,
        in (0, 1] (default 1). An over-estimated band (or one shifted by
        the identification error) makes the loop hunt across it: the output
        error stays tiny, but u chatters by the width of the band at every
        sample. A fraction slightly below 1 (e.g. 0.95) leaves a small
        residual dead band instead, which integral action handles.
    approximate : bool, optional
        If L1 is non-minimum-phase: False (default) raises ValueError, True
        uses the stable approximate inverse of `causal_inverse`.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'u'.

    Returns
    -------
    SandwichCompensator

    Raises
    ------
    TypeError
        If `model` is not a `SandwichSystem`.
    ValueError
        If L1 is non-minimum-phase and `approximate` is False, if
        `smoothing` < 0, or if `band_fraction` is not in (0, 1].

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> comp = sw.sandwich_compensator(plant)
    >>> P = comp.design_plant                 # z^-1 L2
    >>> P.num[0][0], P.den[0][0]
    (array([ 2. , -0.1]), array([1.  , 1.2 , 0.32, 0.  ]))
    >>> v_d = np.array([0.0, 1.0, 2.0, 2.0, 1.0, -1.0, 0.5])
    >>> u = ct.input_output_response(comp, np.arange(7), v_d).outputs
    >>> v = plant.simulate(u, internal=True).outputs[2]
    >>> print(v)                              # v(k) = v_d(k - 1)
    [ 0.  0.  1.  2.  2.  1. -1.]
    """
    return SandwichCompensator(model, smoothing=smoothing,
                               band_fraction=band_fraction,
                               approximate=approximate, name=name,
                               inputs=inputs, outputs=outputs)


# ----------------------------------------------------------------------
# Linear controller and closed loop
# ----------------------------------------------------------------------
def linearized_plant(model):
    r"""The sandwich with its backlash replaced by its mean slope.

    :math:`\bar m L_1 L_2` with :math:`\bar m = (m_1 + m_2)/2`: the linear
    model an engineer would design for without a backlash compensator (the
    dead band is ignored; integral action removes its static offset). The
    result is the same for every equivalent representation of the model.

    Parameters
    ----------
    model : SandwichSystem
        Known or identified model.

    Returns
    -------
    control.TransferFunction

    Examples
    --------
    >>> import control as ct, sandwichctl as sw
    >>> P = sw.linearized_plant(sw.examples.paper_plant())
    >>> round(float(ct.dcgain(P)), 4)     # 1.1 * (1.5/1.3) * (1.9/2.52)
    0.957
    """
    _check_model('model', model)
    co = model.coefficients
    return 0.5 * (co['m1'] + co['m2']) * model.L1 * model.L2


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
    if not 0 < modulus_margin < 1:
        raise ValueError(f"modulus_margin must be in (0, 1); got "
                         f"{modulus_margin!r}")
    if np.any(np.abs(np.roots(den)) >= 1) if den.size > 1 else False:
        raise ValueError("sys must be stable (all poles inside the unit "
                         "circle) for this PI design; got poles "
                         f"{_fmt_roots(np.roots(den))}")
    g = float(np.polyval(num, 1.0) / np.polyval(den, 1.0))
    if not np.isfinite(g) or g == 0:
        raise ValueError(f"sys must have a finite, non-zero DC gain for "
                         f"integral action; got {g}")
    w = np.linspace(1e-4, np.pi, 600)
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
    if feedforward:
        F = causal_inverse(sys, approximate=approximate, name='feedforward')
        F = ct.tf(F.num[0][0], F.den[0][0], sys.dt, inputs='r_ahead',
                  outputs='v_ff',
                  name='feedforward')
        preview = den.size - num.size
    else:
        F, preview = None, 0
    return TrackingController(C, F, preview, sys, kp, ki)


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
                        A1, B1, C1, D1, A2, B2, C2, D2, m1, m2, bD1, bD2,
                        y, u, x, v):
    """Simulate plant, controller and optional compensator from rest."""
    sf = np.zeros(Af.shape[0])
    sc = np.zeros(Ac.shape[0])
    si = np.zeros(Ai.shape[0])
    s1 = np.zeros(A1.shape[0])
    s2 = np.zeros(A2.shape[0])
    wf, wc, wi = np.empty(sf.size), np.empty(sc.size), np.empty(si.size)
    w1, w2 = np.empty(s1.size), np.empty(s2.size)
    x_prev = v_prev = 0.0          # plant backlash memory
    xi_prev = vi_prev = 0.0        # inverse's copy of it
    x_first = D1[0, 0] == 0.0      # x(k) does not depend on u(k)
    for k in range(r.size):
        if x_first:
            xk = _ss_output(A1, B1, C1, D1, s1, 0.0)
            vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, bD1, bD2)
            yk = _ss_output(A2, B2, C2, D2, s2, vk)
        else:
            yk = _ss_output(A2, B2, C2, D2, s2, 0.0)
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
        if not x_first:
            xk = _ss_output(A1, B1, C1, D1, s1, uk)
            vk, _ = backlash_step(xk, x_prev, v_prev, m1, m2, bD1, bD2)
        _ss_update(A1, B1, s1, uk, w1)
        _ss_update(A2, B2, s2, vk, w2)
        x_prev, v_prev = xk, vk
        y[k], u[k], x[k], v[k] = yk, uk, xk, vk


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
    reference `controller.preview` samples ahead, held at its last value
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
    """
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
                        A1, B1, C1, D1, A2, B2, C2, D2, bl.m1, bl.m2,
                        bl.D1, bl.D2, y, u, x, v)
    step = 1.0 if dt is True else float(dt)
    return ct.TimeResponseData(
        step * np.arange(n), np.vstack([y, u, x, v]), None, r,
        issiso=False, output_labels=['y', 'u', 'x', 'v'],
        input_labels=['r'], sysname=plant.name,
        title=("Compensated" if compensator is not None else "Uncompensated")
        + f" closed loop of {plant.name}")


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
    control.InterconnectedSystem
    """
    dt = _check_loop(plant, controller, compensator)
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
    return ct.interconnect(blocks, inplist=['r_ahead'], outlist=['y', 'u'],
                           inputs=['r_ahead'], outputs=['y', 'u'], dt=dt,
                           name=name)


def steps_and_sines(n=1200, levels=(0.0, 1.0, -0.5, 1.5, 0.3),
                    amplitudes=(0.8, 0.2), periods=(100, 37)):
    """A tracking reference: a staircase of steps, then a sum of sines.

    The first half of the `n` samples holds each of `levels` in turn for an
    equal time; the second half is ``sum(a * sin(2 pi k / p))``.

    Parameters
    ----------
    n : int, optional
        Number of samples (default 1200).
    levels : sequence of float, optional
        Step levels; start with 0 to begin at rest.
    amplitudes, periods : sequence of float, optional
        Sine amplitudes and periods (in samples).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> import sandwichctl as sw
    >>> r = sw.steps_and_sines(20, levels=(0, 1), amplitudes=(1,),
    ...                        periods=(4,))
    >>> print(r.round(3))
    [ 0.  0.  0.  0.  0.  1.  1.  1.  1.  1.  0.  1.  0. -1. -0.  1.  0. -1.
     -0.  1.]
    """
    n = int(n)
    if n < 2:
        raise ValueError(f"n must be >= 2; got {n}")
    half = n // 2
    r = np.empty(n)
    edges = np.linspace(0, half, len(levels) + 1).round().astype(int)
    for lev, a, b in zip(levels, edges[:-1], edges[1:]):
        r[a:b] = lev
    k = np.arange(n - half)
    r[half:] = sum(a * np.sin(2 * np.pi * k / p)
                   for a, p in zip(amplitudes, periods))
    return r


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


def _check_model(name, model):
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"{name} must be a sandwichctl.SandwichSystem; got "
                        f"{type(model).__name__}")


def _check_dt(name, dt):
    if dt is None or dt is False or (dt is not True and not dt > 0):
        raise ValueError(f"{name} must be a positive sampling time or True "
                         f"(discrete, unspecified); got {dt!r}. The backlash "
                         f"and its inverse are discrete-time maps")
    return dt
