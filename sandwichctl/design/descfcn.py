r"""Describing function of the asymmetric backlash of eq. (2.2).

For the input :math:`x(\theta) = c + A \sin\theta` the steady-state output
of the backlash (m1, m2, D1, D2) is periodic. Let
:math:`v_{lo} = m_2(c - A + D_2)` and :math:`v_{hi} = m_1(c + A - D_1)` be
its values at the bottom and the top of the swing. If
:math:`v_{hi} \le v_{lo}` the swing never leaves the band and the output is
constant. Otherwise, over one period,

.. math::

    v(\theta) = \begin{cases}
      v_{lo}                       & -\pi/2 \le \theta \le \theta_r\\
      m_1(c + A\sin\theta - D_1)   & \theta_r \le \theta \le \pi/2\\
      v_{hi}                       & \pi/2 \le \theta \le \theta_f\\
      m_2(c + A\sin\theta + D_2)   & \theta_f \le \theta \le 3\pi/2
    \end{cases}

with :math:`\sin\theta_r = (v_{lo}/m_1 + D_1 - c)/A` and
:math:`\sin\theta_f = (v_{hi}/m_2 - D_2 - c)/A` (clipped to [-1, 1], which
covers the jumps beyond the slope-line crossing). The describing function
is the first harmonic, :math:`N = (b_1 + j a_1)/A` with
:math:`b_1 = \frac1\pi\int v\sin\theta\,d\theta` and
:math:`a_1 = \frac1\pi\int v\cos\theta\,d\theta`, integrated in closed form
(python-control's convention: the output's fundamental is
:math:`|N| A \sin(\theta + \arg N)`).

The DC offset
-------------
With :math:`m_1 \ne m_2` the shape of the loop, and so N, depends on the
input bias c, and the output has a mean :math:`a_0(c) \ne 0` even when
c = 0. sandwichctl takes the bias from the loop, by *centring*: in a
feedback loop at steady state the DC balance fixes the mean of the backlash
output (with integral action, :math:`\bar v = r / L_2(1)`; 0 for r = 0), so
`BacklashNonlinearity` solves :math:`a_0(c) = \bar v` for c (``output_mean``,
default 0) and returns the first harmonic of that centred oscillation.
Alternatively a fixed input bias c can be given (``input_bias``). With
:math:`m_1 = m_2` the backlash commutes with shifts, N does not depend on
the bias, and N equals python-control's `friction_backlash_nonlinearity`
scaled by m for a width :math:`D_1 + D_2`.

Discrete-time loops
-------------------
``ct.describing_function_response`` evaluates a discrete-time H on the unit
circle but reads the frequency off the contour as if it were continuous
(``contour.imag``), and refines at ``H(1j * omega)``. `unit_circle_frd`
converts a discrete H into a frequency-response-data object whose value at
:math:`j\omega` is :math:`H(e^{j\omega\,dt})`, and `limit_cycles` passes
it to python-control, so amplitudes and frequencies come out right.
"""

import math
import warnings

import numpy as np
import control as ct
from scipy.optimize import brentq

from ..model.backlash import Backlash
from ..model.sandwich import SandwichSystem
from .closedloop import TrackingController, closed_loop_response
from .._checks import (DATA_RANGE, MOST_SAMPLES, check_finite,
                       check_nonnegative, check_positive, check_signal,
                       check_int, check_bool, check_name,
                       check_discrete_siso_tf, check_finite_system,
                       common_dt, warn, SimulationWarning, _real_array)

__all__ = ['BacklashNonlinearity', 'backlash_nonlinearity',
           'backlash_harmonics', 'unit_circle_frd', 'limit_cycles',
           'sandwich_limit_cycles', 'simulate_limit_cycle', 'first_harmonic']


def backlash_harmonics(A, bias, m1, m2, D1, D2):
    r"""Mean and first harmonic of the steady backlash output (closed form).

    For the input :math:`c + A\sin\theta`, return :math:`(a_0, b_1, a_1)`:
    the mean of v and the coefficients of :math:`\sin\theta` and
    :math:`\cos\theta` in its Fourier series (see the module notes).

    Parameters
    ----------
    A : float
        Amplitude, >= 0.
    bias : float
        Input bias c.
    m1, m2, D1, D2 : float
        Backlash parameters (eq. (2.2)).

    Returns
    -------
    a0, b1, a1 : float
        a0 is nan when the output is constant (the swing stays inside the
        band, so the held value depends on history); b1 = a1 = 0 then.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> a0, b1, a1 = sw.backlash_harmonics(2.0, 0.0, 1, 1, 0.5, 0.5)
    >>> round(a0, 12), round(b1, 4), round(a1, 4)
    (0.0, 1.609, -0.4775)
    """
    A = check_nonnegative('A', A)
    c = check_finite('bias', bias)
    m1, m2 = check_positive('m1', m1), check_positive('m2', m2)
    D1, D2 = check_nonnegative('D1', D1), check_nonnegative('D2', D2)
    return _harmonics(A, c, m1, m2, D1, D2)


def _harmonics(A, c, m1, m2, D1, D2):
    v_lo = m2 * (c - A + D2)
    v_hi = m1 * (c + A - D1)
    if A == 0 or v_hi <= v_lo:
        return math.nan, 0.0, 0.0
    th_r = math.asin(min(1.0, max(-1.0, (v_lo / m1 + D1 - c) / A)))
    th_f = math.pi - math.asin(min(1.0, max(-1.0, (v_hi / m2 - D2 - c) / A)))
    h = -0.5 * math.pi
    i0 = is_ = ic = 0.0
    for lo, hi, kind, m, s in ((h, th_r, 0, 0.0, v_lo),
                               (th_r, -h, 1, m1, c - D1),
                               (-h, th_f, 0, 0.0, v_hi),
                               (th_f, 3 * -h, 1, m2, c + D2)):
        dcos = math.cos(lo) - math.cos(hi)
        dsin = math.sin(hi) - math.sin(lo)
        if kind == 0:                      # constant s
            i0 += s * (hi - lo)
            is_ += s * dcos
            ic += s * dsin
        else:                              # m (s + A sin)
            i0 += m * (s * (hi - lo) + A * dcos)
            is_ += m * (s * dcos + A * ((hi - lo) / 2
                                        - (math.sin(2 * hi)
                                           - math.sin(2 * lo)) / 4))
            ic += m * (s * dsin + A * (math.sin(hi) ** 2
                                       - math.sin(lo) ** 2) / 2)
    return i0 / (2 * math.pi), is_ / math.pi, ic / math.pi


def _centring_bias(A, v_mean, m1, m2, D1, D2):
    """Input bias c with mean output v_mean, or None if v is constant."""
    if m1 == m2:
        if m1 * (2 * A - D1 - D2) <= 0:
            return None
        a0 = _harmonics(A, 0.0, m1, m2, D1, D2)[0]
        return (v_mean - a0) / m1
    c_b = -(m1 * (A - D1) + m2 * (A - D2)) / (m1 - m2)
    v_b = m1 * (c_b + A - D1)
    sign = 1.0 if m1 > m2 else -1.0       # side of c_b where the loop opens
    if sign * (v_mean - v_b) <= 0:
        return None

    def f(c):
        a0 = _harmonics(A, c, m1, m2, D1, D2)[0]
        return (v_b if math.isnan(a0) else a0) - v_mean

    step = max(abs(v_mean - v_b) / min(m1, m2), A, 1e-12)
    far = c_b + sign * step
    while sign * f(far) <= 0:
        step *= 2
        far = c_b + sign * step
        if not math.isfinite(far):
            raise ValueError(f"no input bias centres the backlash's output "
                             f"at {v_mean!r} for A={A!r}: the search for "
                             f"it overflows a float")
    lo, hi = sorted((c_b, far))
    return brentq(f, lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)


class BacklashNonlinearity(ct.DescribingFunctionNonlinearity):
    r"""The asymmetric backlash of eq. (2.2) for describing-function analysis.

    A `control.DescribingFunctionNonlinearity`, so
    ``ct.describing_function``, ``ct.describing_function_response`` and
    ``ct.describing_function_plot`` use its closed-form `describing_function`.
    Build it with `backlash_nonlinearity`.

    Parameters
    ----------
    m1, m2 : float
        Slopes, 0 < m < inf.
    D1, D2 : float
        Thresholds, >= 0.
    output_mean : float, optional
        Mean of the backlash output in the loop's steady state (default 0,
        the value integral action enforces for r = 0); the input bias is
        solved for it (centring, see the module notes).
    input_bias : float, optional
        A fixed input bias c instead of `output_mean`.

    Notes
    -----
    The backlash has memory, so calling the object on a single sample has no
    meaning; simulate with `Backlash` or `backlash_response` instead.
    """

    def __init__(self, m1, m2, D1, D2, output_mean=0.0, input_bias=None):
        super().__init__()
        self.m1, self.m2 = check_positive('m1', m1), check_positive('m2', m2)
        self.D1 = check_nonnegative('D1', D1)
        self.D2 = check_nonnegative('D2', D2)
        self.output_mean = check_finite('output_mean', output_mean)
        self.input_bias = (None if input_bias is None
                           else check_finite('input_bias', input_bias))

    def __call__(self, x):
        raise TypeError(
            "a backlash has memory: it cannot be evaluated on one sample. "
            "Use its describing_function method (ct.describing_function does "
            "so automatically), or simulate it with sw.Backlash or "
            "sw.backlash_response")

    def _isstatic(self):
        return False

    def bias(self, A):
        """Input bias c used at amplitude `A` (None if the output is constant).

        Parameters
        ----------
        A : float
            Amplitude of the sinusoidal input, >= 0.
        """
        A = check_nonnegative('A', A)
        if not math.isfinite(4 * max(self.m1, self.m2)
                             * (A + self.D1 + self.D2)):
            raise ValueError(
                f"A={A!r} is too large for these slopes: the backlash's "
                f"output (about max(m1, m2) A) overflows a float")
        if self.input_bias is not None:
            return self.input_bias
        if A == 0:
            return None
        return _centring_bias(A, self.output_mean, self.m1, self.m2,
                              self.D1, self.D2)

    def describing_function(self, A):
        """Describing function N(A) (complex) of the centred backlash.

        Parameters
        ----------
        A : float
            Amplitude of the sinusoidal input to the backlash, >= 0.

        Returns
        -------
        complex
            0 if the swing stays inside the band (constant output).

        Raises
        ------
        ValueError
            If A < 0.
        """
        A = check_nonnegative('A', A)
        c = self.bias(A)
        if c is None:
            return 0j
        _, b1, a1 = _harmonics(float(A), c, self.m1, self.m2, self.D1,
                               self.D2)
        return complex(b1, a1) / A

    def __repr__(self):
        extra = (f"input_bias={self.input_bias:.6g}"
                 if self.input_bias is not None
                 else f"output_mean={self.output_mean:.6g}")
        return (f"BacklashNonlinearity(m1={self.m1:.6g}, m2={self.m2:.6g}, "
                f"D1={self.D1:.6g}, D2={self.D2:.6g}, {extra})")


def backlash_nonlinearity(backlash, output_mean=0.0, input_bias=None):
    r"""Describing-function nonlinearity of a backlash (eq. (2.2)).

    Parameters
    ----------
    backlash : Backlash
        The backlash (known or identified, e.g. ``res.model.backlash``).
    output_mean : float, optional
        Mean of the backlash output in the loop's steady state; the input
        bias is solved so that the oscillation has this mean (default 0).
    input_bias : float, optional
        Use this fixed input bias instead.

    Returns
    -------
    BacklashNonlinearity

    Examples
    --------
    With m1 = m2 = 1 and D1 = D2 this is python-control's friction backlash:

    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> F = sw.backlash_nonlinearity(sw.Backlash(1, 1, 0.25, 0.25))
    >>> A = np.array([0.5, 1.0, 3.0])
    >>> np.allclose(ct.describing_function(F, A),
    ...             ct.describing_function(
    ...                 ct.friction_backlash_nonlinearity(0.5), A))
    True
    """
    if not isinstance(backlash, Backlash):
        raise TypeError(f"backlash must be a sandwichctl.Backlash; got "
                        f"{type(backlash).__name__}")
    return BacklashNonlinearity(backlash.m1, backlash.m2, backlash.D1,
                                backlash.D2, output_mean=output_mean,
                                input_bias=input_bias)


def unit_circle_frd(sys, omega=None, name=None):
    r"""Frequency response of a discrete system as FRD data in rad/time.

    Returns ``ct.frd(sys(exp(1j*omega*dt)), omega, smooth=True)``: a
    python-control FRD whose value at :math:`j\omega` is
    :math:`H(e^{j\omega\,dt})`. python-control's describing-function tools
    treat their argument as continuous-time; this object makes them see a
    discrete system's true frequency response.

    Parameters
    ----------
    sys : control.LTI
        Discrete-time SISO system (dt > 0 or True, meaning 1).
    omega : array_like, optional
        At least two distinct frequencies in rad per time unit, within
        (0, pi/dt], in any order (the result holds them sorted); default
        2000 points from 1e-3 pi/dt to pi/dt.
    name : str, optional
        Name of the result.

    Returns
    -------
    control.FrequencyResponseData

    Raises
    ------
    ValueError
        If `sys` is not a discrete-time SISO system with finite
        coefficients, or `omega` is not as above.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> H = ct.tf([0.5], [1, -0.5], 1)
    >>> frd = sw.unit_circle_frd(H)
    >>> bool(np.isclose(frd(1j * 0.3), H(np.exp(0.3j))))
    True
    """
    if not isinstance(sys, ct.LTI) or not sys.isdtime(strict=True):
        raise ValueError(
            f"sys must be a discrete-time python-control system (dt > 0 or "
            f"True); got {type(sys).__name__} with dt="
            f"{getattr(sys, 'dt', None)!r}")
    if sys.ninputs != 1 or sys.noutputs != 1:
        raise ValueError(f"sys must be SISO; got {sys.noutputs} outputs and "
                         f"{sys.ninputs} inputs")
    check_finite_system('sys', sys)
    name = check_name('name', name)
    dt = 1.0 if sys.dt is True else float(sys.dt)
    if omega is None:
        omega = np.linspace(1e-3, 1.0, 2000) * np.pi / dt
    else:
        omega = _check_omega(omega, np.pi / dt, 'pi/dt')
    resp = np.squeeze(sys(np.exp(1j * omega * dt)))
    return ct.frd(resp, omega, smooth=True, name=name)


def _check_omega(omega, top=None, label=None):
    """`omega` as sorted frequencies: at least 2 (the FRD interpolates
    between them), distinct, > 0 and (unless `top` is None) at most
    `top`, which `label` names."""
    span = ("above 0" if top is None
            else f"in (0, {label}] = (0, {top:.6g}]")
    want = f"at least 2 distinct frequencies {span} (rad per time unit)"
    arr = _real_array('omega', omega, 'an array of frequencies')
    if arr.ndim == 0:
        raise ValueError(f"omega must be an array of {want}; got the "
                         f"single number {float(arr):g}")
    omega = np.sort(check_signal('omega', arr))
    if omega.size < 2:
        raise ValueError(f"omega must hold {want}; got {omega.size}")
    if omega[0] <= 0 or (top is not None
                         and omega[-1] > top * (1 + 1e-12)):
        raise ValueError(f"omega must lie {span}; got [{omega[0]:.6g}, "
                         f"{omega[-1]:.6g}]")
    same = np.flatnonzero(np.diff(omega) == 0)
    if same.size:
        value = omega[same[0]]
        raise ValueError(f"omega must hold {want}; got {value:g} "
                         f"{int(np.sum(omega == value))} times")
    return omega


def limit_cycles(H, F, A, omega=None, refine=True):
    r"""Describing-function prediction of limit cycles of ``x = -H[F(x)]``.

    Calls ``ct.describing_function_response`` for the loop formed by the
    linear system H (from the nonlinearity's output back to its input,
    negative feedback) and the nonlinearity F. A discrete-time H is first
    converted with `unit_circle_frd`, so that frequencies are right.

    Parameters
    ----------
    H : control.LTI
        Linear part of the loop (continuous or discrete), with finite
        coefficients.
    F : ct.DescribingFunctionNonlinearity or callable
        The nonlinearity, e.g. `backlash_nonlinearity`, or a static
        function x -> F(x); not a python-control system (a linear one
        belongs in H).
    A : array_like
        Amplitudes at which to evaluate the describing function. Those
        where it is 0 (inside a dead band, where -1/N(A) is infinite and
        no limit cycle can be) are left out of the scan.
    omega : array_like, optional
        Frequencies (rad per time unit) for the Nyquist curve: at least
        two distinct ones, > 0 (and at most pi/dt for a discrete H).
    refine : bool, optional
        Refine the intersections with ``scipy.optimize`` (default True).

    Returns
    -------
    control.DescribingFunctionResponse
        ``.intersections`` is a list of (amplitude, frequency) pairs: the
        predicted limit cycles. ``.plot()`` draws the Nyquist curve and
        :math:`-1/N(A)` (``ct.describing_function_plot``).

    Raises
    ------
    TypeError
        If `H` is not a SISO LTI system, or `F` is neither a
        describing-function nonlinearity nor a function (a python-control
        system is refused: a linear one belongs in H).
    ValueError
        If `H` has NaN or inf coefficients, `A` holds an amplitude <= 0 or
        only amplitudes where the describing function is 0, or `omega` is
        not as above.
    """
    if not isinstance(H, ct.LTI) or H.ninputs != 1 or H.noutputs != 1:
        raise TypeError(f"H must be a SISO python-control LTI system (e.g. "
                        f"a ct.TransferFunction); got {type(H).__name__}")
    check_finite_system('H', H)
    if isinstance(F, ct.InputOutputSystem) or not (
            isinstance(F, ct.DescribingFunctionNonlinearity)
            or callable(F)):
        kind = type(F).__name__
        raise TypeError(f"F must be a describing-function nonlinearity "
                        f"(e.g. sw.backlash_nonlinearity(...)) or a "
                        f"function x -> F(x); got {kind}"
                        + (", a python-control system: a linear block "
                           "belongs in H (the loop is x = -H[F(x)])"
                           if isinstance(F, ct.InputOutputSystem) else ""))
    A = check_signal('A', A)
    if np.any(A <= 0):
        raise ValueError(f"A must hold amplitudes > 0; got {A.min():g}")
    refine = check_bool('refine', refine)
    # where N(A) = 0 (inside a dead band) -1/N(A) is infinite: no limit
    # cycle there, and python-control's scan and refinement meet NaNs
    with np.errstate(all='ignore'):
        gain = np.array([complex(np.ravel(ct.describing_function(F, a))[0])
                         for a in A])
    live = np.isfinite(gain) & (gain != 0)
    if not live.any():
        raise ValueError(f"the describing function is 0 (or not finite) at "
                         f"every amplitude of A ({A.min():g} to "
                         f"{A.max():g}): inside the nonlinearity's dead "
                         f"band no limit cycle can be predicted; give "
                         f"amplitudes beyond it")
    A = A[live]
    if H.isdtime(strict=True):
        H = unit_circle_frd(H, omega, name=H.name)
        omega = H.omega
    elif omega is not None:
        omega = _check_omega(omega)
    resp = _df_response(H, F, A, omega, refine)
    if refine and any(not A.min() <= a <= A.max()
                      for a, _ in resp.intersections):
        # the refinement can leave the amplitudes scanned (even for a
        # negative one): there the crossing found on the scan stands
        coarse = _df_response(H, F, A, omega, False).intersections
        if len(coarse) == len(resp.intersections):
            resp.intersections = [
                fine if A.min() <= fine[0] <= A.max() else rough
                for fine, rough in zip(resp.intersections, coarse)]
        else:
            resp.intersections = [p for p in resp.intersections
                                  if A.min() <= p[0] <= A.max()]
    return resp


def _df_response(H, F, A, omega, refine):
    """``ct.describing_function_response`` without its RuntimeWarnings
    (divisions on the Nyquist curve's way; a NaN found is dropped)."""
    with np.errstate(all='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        return ct.describing_function_response(
            H, F, A, omega=omega, refine=refine, warn_nyquist=False)


def first_harmonic(signal, dt=1.0):
    r"""Frequency and first-harmonic amplitude of a periodic signal.

    The frequency is found from the mean period between upward crossings of
    the signal's mean (interpolated between samples); the amplitude is
    that of the projection of the centred signal on the sine and cosine at
    this frequency over whole periods. Use it to measure a simulated limit
    cycle in the terms of the describing function.

    Parameters
    ----------
    signal : array_like, shape (N,)
        Samples of a steady oscillation (drop the transient first).
    dt : float, optional
        Sampling time (default 1).

    Returns
    -------
    amplitude : float
        First-harmonic amplitude.
    omega : float
        Frequency in rad per time unit.
    mean : float
        Mean of the signal over the whole periods used.

    Raises
    ------
    ValueError
        If the signal crosses its mean upwards fewer than three times.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> k = np.arange(2000)
    >>> x = 1 + 2 * np.sin(0.3 * k) + 0.1 * np.sin(0.9 * k)
    >>> amp, w, mean = sw.first_harmonic(x)
    >>> round(amp, 3), round(w, 4), round(mean, 3)
    (2.0, 0.3, 1.0)
    """
    x = check_signal('signal', signal)
    dt = check_positive('dt', dt)
    centre = x.mean()
    s = x - centre
    up = np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0))
    if up.size < 3:
        raise ValueError(f"signal crosses its mean upwards {up.size} "
                         f"time(s); need at least 3 to measure a period")
    times = up + (-s[up]) / (s[up + 1] - s[up])
    period = (times[-1] - times[0]) / (up.size - 1)
    lo, hi = int(np.ceil(times[0])), int(np.floor(times[-1]))
    k = np.arange(lo, hi + 1)
    w = 2 * np.pi / period
    seg = x[lo:hi + 1]
    mean = float(seg.mean())
    a = 2 * np.mean((seg - mean) * np.cos(w * k))
    b = 2 * np.mean((seg - mean) * np.sin(w * k))
    return float(np.hypot(a, b)), float(w / dt), mean


def sandwich_limit_cycles(model, C, A=None, omega=None, output_mean=0.0,
                          refine=True):
    r"""Predict the limit cycles of a sandwich under feedback ``u = -C y``.

    With a constant reference, the loop around the backlash is
    :math:`x = -L_1 C L_2\,[v]`, so `limit_cycles` is applied to
    :math:`H = L_1 C L_2` and the model's `backlash_nonlinearity`
    (centred on `output_mean`, 0 for r = 0 under integral action).

    Parameters
    ----------
    model : SandwichSystem
        Known or identified model; amplitudes are those of its x.
    C : control.TransferFunction
        Discrete controller from the error r - y to u.
    A : array_like, optional
        Amplitudes of x to scan; default 300 points from just above the
        band's half-width to 50 times it.
    omega : array_like, optional
        Frequencies for the Nyquist curve (rad per time unit).
    output_mean : float, optional
        Mean of v in the steady state (see `BacklashNonlinearity`).
    refine : bool, optional
        Refine the intersections (default True).

    Returns
    -------
    control.DescribingFunctionResponse
        ``.intersections``: predicted (amplitude of x, frequency) pairs.

    Examples
    --------
    An integral controller with a low-pass filter around the paper's
    plant: the linearised loop is stable, yet the backlash sustains a
    limit cycle.

    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> model = sw.examples.paper_plant().normalized()
    >>> C = ct.tf([0.05, 0], np.polymul([1, -1], [1, -0.9]), 1)
    >>> resp = sw.sandwich_limit_cycles(model, C)
    >>> [(round(float(a), 2), round(float(w), 3))
    ...  for a, w in resp.intersections]
    [(0.39, 0.031), (1.17, 0.186)]
    """
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"model must be a sandwichctl.SandwichSystem; got "
                        f"{type(model).__name__}")
    check_discrete_siso_tf('C', C)
    common_dt('model', model.dt, 'C', C.dt)
    F = backlash_nonlinearity(model.backlash, output_mean=output_mean)
    if A is None:
        v = F.output_mean
        half = 0.5 * (v / F.m1 + F.D1 - v / F.m2 + F.D2)
        half = max(half, 1e-6)
        A = np.geomspace(half * 1.001, half * 50, 300)
    H = ct.tf(model.L1 * C * model.L2, name='L1*C*L2')   # names the plot
    with np.errstate(all='ignore'):
        peak = np.max(np.abs(H(np.exp(1j * np.linspace(1e-3, np.pi, 64)))))
    if not peak <= DATA_RANGE[1]:
        raise ValueError(f"C's gain makes the loop L1 C L2 reach {peak:.3g} "
                         f"on the unit circle, beyond what the describing "
                         f"function can solve in double precision; check "
                         f"C's units")
    # at large amplitudes the backlash passes x on with slope mbar
    co = model.coefficients
    radius = np.max(np.abs(ct.poles(ct.feedback(
        0.5 * (co['m1'] + co['m2']) * H, 1))), initial=0.0)
    if not radius < 1:
        warn(f"sandwich_limit_cycles: the loop around mbar L1 C L2 is "
             f"unstable (pole radius {radius:.4g}), so large oscillations "
             f"grow without bound: a cycle predicted here is at most an "
             f"unstable one", SimulationWarning)
    return limit_cycles(H, F, A, omega=omega, refine=refine)


def simulate_limit_cycle(plant, C, n=8000, kick=1.0, settle=None):
    r"""Simulate ``u = C(r - y)`` around a sandwich and measure its cycle.

    The reference is a pulse of height `kick` for 20 samples, then 0. The
    first-harmonic amplitude and frequency of the backlash input x (in the
    plant's own units: normalise the plant to compare with a normalised
    model) are measured over the samples after `settle`.

    Parameters
    ----------
    plant : SandwichSystem
        The plant to simulate.
    C : control.TransferFunction
        Discrete controller from r - y to u.
    n : int, optional
        Number of samples (default 8000).
    kick : float, optional
        Height of the reference pulse that starts the oscillation.
    settle : int, optional
        Samples to discard; default n // 2.

    Returns
    -------
    amplitude : float
        First-harmonic amplitude of x; 0 if x does not cross its mean at
        least three times after `settle`, or swings by no more than
        rounding (no sustained oscillation); inf, with a
        SimulationWarning, if the loop diverges.
    omega : float
        Its frequency, rad per time unit (nan without oscillation).
    response : control.TimeResponseData
        The simulation (`closed_loop_response`).
    """
    n = check_int('n', n, minimum=8, maximum=MOST_SAMPLES)
    kick = check_finite('kick', kick)
    settle = n // 2 if settle is None else check_int('settle', settle)
    if settle > n - 4:
        raise ValueError(f"settle must leave samples to measure: at most "
                         f"n - 4 = {n - 4}; got {settle}")
    r = np.zeros(n)
    r[:20] = kick
    resp = closed_loop_response(plant, r, TrackingController.from_feedback(C))
    x = resp.outputs[2][settle:]
    s = x - x.mean()
    half = s.size // 2
    if not np.all(np.isfinite(x)) or np.ptp(x[half:]) > 10 * max(
            np.ptp(x[:half]), 1e-300):
        warn("simulate_limit_cycle: the loop diverges (x grows without "
             "bound), so it has no limit cycle; amplitude inf",
             SimulationWarning)
        return math.inf, math.nan, resp
    scale = np.max(np.abs(resp.outputs[2]))
    if np.ptp(s) <= 1e-9 * scale or \
            np.count_nonzero((s[:-1] < 0) & (s[1:] >= 0)) < 3:
        return 0.0, math.nan, resp          # no sustained oscillation
    amp, w, _ = first_harmonic(x, 1.0)
    dt = 1.0 if plant.dt is True else float(plant.dt)
    return amp, w / dt, resp
