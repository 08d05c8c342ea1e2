r"""Inverses of the two blocks a compensator cancels: the backlash and L1.

`BacklashInverse` inverts eq. (2.2); `causal_inverse` inverts a linear
block up to its delay. `sandwich_compensator` (module `compensator`)
chains them in front of a plant.

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

References
----------
.. [1] G. Tao and P. V. Kokotović, "Adaptive control of plants with unknown
   hystereses", IEEE Trans. Automatic Control 40(2), 1995; and *Adaptive
   Control of Systems with Actuator and Sensor Nonlinearities*, Wiley, 1996.
"""

import numba
import numpy as np
import control as ct

from ..model.backlash import Backlash, backlash_step, finite_step
from ..model.sandwich import SandwichSystem
from .._checks import (check_discrete_siso_tf, check_nonnegative,
                       check_positive, check_signal, common_dt, check_dt,
                       check_finite, check_bool, check_name, check_label,
                       check_labels, named_copy, warn_overflow)

__all__ = ['BacklashInverse', 'backlash_inverse', 'backlash_inverse_response',
           'causal_inverse']


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
    x_prev = check_finite('x_prev', x_prev)
    v_prev = check_finite('v_prev', v_prev)
    return_expected = check_bool('return_expected', return_expected)
    x, v_hat = np.empty_like(v_d), np.empty_like(v_d)
    _inverse_loop(v_d, m1, m2, D1, D2, width, x_prev, v_prev, x, v_hat)
    warn_overflow(x, "the inverse's output", "(v_d / m1 or v_d / m2 beyond "
                  "1.8e308): rescale v_d or the slopes")
    return (x, v_hat) if return_expected else x


def _inverse_functions(m1, m2, D1, D2, smoothing):
    """Update and output functions of one inverse (parameters fixed, in
    closures: python-control merges the ``params`` of all the blocks of an
    interconnection into one dict, so two inverses held there would share
    one set)."""
    def update(t, state, inp, params):
        return np.array(_inverse_step(*finite_step(t, inp, state), m1, m2,
                                      D1, D2, smoothing))

    def output(t, state, inp, params):
        return np.array(_inverse_step(*finite_step(t, inp, state), m1, m2,
                                      D1, D2, smoothing)[:1])
    return update, output


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
    The parameters are read-only attributes, not python-control
    ``params``: python-control merges the params of all blocks of an
    interconnection into one dict and pushes it back to every block, so
    two inverses there (or an inverse and a plant's backlash) would
    silently share one set.

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
        self._values = (check_positive('m1', m1), check_positive('m2', m2),
                        check_nonnegative('D1', D1),
                        check_nonnegative('D2', D2),
                        check_nonnegative('smoothing', smoothing))
        dt = check_dt('dt', dt)
        name = check_name('name', name)
        inputs = check_label('inputs', inputs, 'input')
        outputs = check_label('outputs', outputs, 'output')
        states = check_labels('states', states, 2)
        update, output = _inverse_functions(*self._values)
        super().__init__(update, output, inputs=inputs, outputs=outputs,
                         states=states, dt=dt, name=name)

    copy = named_copy            # its name checked

    def __reduce__(self):
        # rebuild from plain data, as Backlash does (robust to changes in
        # python-control's internals)
        return (type(self), (self.m1, self.m2, self.D1, self.D2,
                             self.smoothing, self.dt, self.name,
                             self.input_labels[0], self.output_labels[0],
                             list(self.state_labels)))

    m1 = property(lambda self: self._values[0], doc="Increase slope.")
    m2 = property(lambda self: self._values[1], doc="Decrease slope.")
    D1 = property(lambda self: self._values[2], doc="Increase threshold.")
    D2 = property(lambda self: self._values[3], doc="Decrease threshold.")
    smoothing = property(lambda self: self._values[4],
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
        'backlash', backlash.dt, 'the requested inverse', check_dt('dt', dt))
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
    approximate = check_bool('approximate', approximate)
    return _causal_inverse(sys, approximate, check_name('name', name))[0]


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
