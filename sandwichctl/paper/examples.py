"""Ready-made plants and signals from the paper.

`paper_plant` is the simulation example of Section 5, eqs. (5.1)-(5.2).
`xy_stage` is one axis of the X-Y positioning stage of Section 6, eqs.
(6.1)-(6.3), built from a physical DC-servomotor / ball-screw / platform
model; `xy_stage_input` and `xy_stage_measurement` are its excitation and
its speed measurement.
"""

import numpy as np
import control as ct

from ..model.sandwich import SandwichSystem
from .._checks import (check_int, check_positive, check_nonnegative,
                       check_finite, check_rng, check_signal,
                       check_data_scale)

__all__ = ['paper_plant', 'paper_input', 'add_noise', 'SNR_KINDS',
           'PAPER_THETA0']

#: Starting point theta_0 of the Section 5 study (order of eq. (2.5)).
PAPER_THETA0 = np.array([0, 0, 0, 0, 0.1, 0.1, 0.1, 0.1, 0.0])


def paper_plant(dt=1, name='paper'):
    """The sandwich system of Section 5 (eqs. (5.1) and (5.2)).

    L1: x(k) = -0.1 x(k-1) - 0.2 x(k-2) + 1.5 u(k-1), i.e.
    ``ct.tf([1.5, 0], [1, 0.1, 0.2], dt)``; backlash m1 = 1, m2 = 1.2,
    D1 = 0.5, D2 = 0.6; L2: y(k) = -1.2 y(k-1) - 0.32 y(k-2) + 2 v(k-1)
    - 0.1 v(k-2), i.e. ``ct.tf([2, -0.1], [1, 1.2, 0.32], dt)``.

    Its normalised form (b0 = d0 = 1) has theta = (c1, c2, a1, a2, m1, m2,
    D1, D2, d1) = (1.2, 0.32, 0.1, 0.2, 3, 3.6, 1/3, 0.4, -0.05).

    Parameters
    ----------
    dt : float or True, optional
        Sampling time (default 1).
    name : str, optional
        System name.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.examples.paper_plant().normalized().theta.round(4)
    array([ 1.2   ,  0.32  ,  0.1   ,  0.2   ,  3.    ,  3.6   ,  0.3333,
            0.4   , -0.05  ])
    """
    return SandwichSystem.from_coefficients(
        a=[0.1, 0.2], b=[1.5], c=[1.2, 0.32], d=[2.0, -0.1],
        m1=1.0, m2=1.2, D1=0.5, D2=0.6, q1=1, q2=1, dt=dt, name=name)


def paper_input(n, variance=0.49, seed=None):
    """The Section 5 excitation: white Gaussian noise of variance 0.49.

    Parameters
    ----------
    n : int
        Number of samples.
    variance : float, optional
        Variance of u (default 0.49, the paper's sigma^2).
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.
    """
    n = check_int('n', n, minimum=1)
    variance = check_positive('variance', variance)
    rng = check_rng('seed', seed)
    return np.sqrt(variance) * rng.standard_normal(n)


#: The readings of an output signal-to-noise ratio that `add_noise`
#: accepts: kind -> its name, as the Section 5 study's headings print it.
SNR_KINDS = {'variance': 'variance ratio', 'amplitude': 'amplitude ratio',
             'db': 'dB'}


def add_noise(y, snr, seed=None, kind='variance'):
    r"""Add white Gaussian output noise at a given signal-to-noise ratio.

    Section 5 of the paper says "SNR equal to 46.5" without a unit. Three
    readings are in use, and they differ by orders of magnitude in the
    noise they add; `kind` names the reading. With :math:`\sigma_y` and
    :math:`\sigma_e` the standard deviations of y and of the noise:

    - ``'variance'`` (default): the variance ratio
      :math:`\mathrm{SNR} = \sigma_y^2 / \sigma_e^2`; 46.5 means
      :math:`\sigma_e` = 14.7 % of :math:`\sigma_y`.
    - ``'amplitude'``: the amplitude ratio
      :math:`\mathrm{SNR} = \sigma_y / \sigma_e`; 46.5 means
      :math:`\sigma_e` = 2.15 % of :math:`\sigma_y`.
    - ``'db'``: decibels,
      :math:`\mathrm{SNR} = 10 \log_{10}(\sigma_y^2 / \sigma_e^2)`; 46.5
      means :math:`\sigma_e` = 0.47 % of :math:`\sigma_y`.

    The default stays the variance ratio, the reading of earlier
    releases, so results computed with it do not change; the Section 5
    study runs all three (``docs/reproduction.md``).

    Parameters
    ----------
    y : array_like
        Noise-free output.
    snr : float
        The signal-to-noise ratio, > 0, in the reading `kind`.
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.
    kind : {'variance', 'amplitude', 'db'}, optional
        How `snr` is read (default 'variance'), see the list above.

    Returns
    -------
    ndarray
        y plus white Gaussian noise of variance var(y) / snr (variance),
        var(y) / snr**2 (amplitude) or var(y) / 10**(snr / 10) (dB).

    Raises
    ------
    ValueError
        If `snr` is not a finite number > 0, `kind` is not one of the
        three readings, y is constant, or y's peak magnitude is outside
        1e-100 .. 1e100 (its variance would overflow or underflow: rescale
        it).

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> y = np.sin(np.arange(100000) * 0.1)
    >>> noisy = sw.examples.add_noise(y, 46.5, seed=0)
    >>> round(float(np.var(y) / np.var(noisy - y)))
    46
    >>> noisy = sw.examples.add_noise(y, 46.5, seed=0, kind='amplitude')
    >>> round(float(np.std(y) / np.std(noisy - y)))
    46
    >>> noisy = sw.examples.add_noise(y, 46.5, seed=0, kind='db')
    >>> round(float(10 * np.log10(np.var(y) / np.var(noisy - y))), 1)
    46.5
    """
    y = check_signal('y', y)
    check_data_scale('y', y, "y's variance", back='scale the noisy output '
                     'back')
    snr = check_positive('snr', snr)
    if kind not in SNR_KINDS:
        raise ValueError(f"kind must be one of {sorted(SNR_KINDS)}; got "
                         f"{kind!r}")
    with np.errstate(over='ignore'):       # a huge snr: no noise
        ratio = {'variance': snr, 'amplitude': np.float64(snr) ** 2,
                 'db': np.float64(10.0) ** (snr / 10)}[kind]
    if np.var(y) == 0:
        raise ValueError("y is constant, so a signal-to-noise ratio gives "
                         "it no noise; add noise of a chosen standard "
                         "deviation instead (y + sigma * "
                         "rng.standard_normal(y.size))")
    rng = check_rng('seed', seed)
    return y + rng.standard_normal(y.shape) * np.sqrt(np.var(y) / ratio)


# ----------------------------------------------------------------------
# Section 6: one axis of the X-Y positioning stage
# ----------------------------------------------------------------------
__all__ += ['xy_stage', 'xy_stage_continuous', 'xy_stage_input',
            'xy_stage_measurement', 'XY_STAGE_PARAMETERS', 'XY_STAGE_DT',
            'XY_STAGE_THETA0']

#: Sample time of the X-Y stage of Section 6, in seconds (0.5 ms).
XY_STAGE_DT = 0.0005

#: Starting point theta_0 of the Section 6 identification (order of eq.
#: (2.5): c1, c2, a1, a2, m1, m2, D1, D2, d1).
XY_STAGE_THETA0 = np.array([0, 0, 0, 0, 1, 1, 0.001, 0.001, 0.0])

#: Physical parameters of the X-Y stage axis: name -> (value, unit,
#: meaning). `xy_stage` and `xy_stage_continuous` accept each name as a
#: keyword argument to override the value.
XY_STAGE_PARAMETERS = {
    # DC servomotor and its amplifier: L1 of eq. (6.1), u [V] -> x [mm/s]
    'Ka': (10.0, 'V/V', 'gain of the power amplifier (DSP output u to '
                        'armature voltage)'),
    'R': (1.2, 'ohm', 'armature resistance'),
    'L': (0.6e-3, 'H', 'armature inductance'),
    'Kt': (0.05, 'N m/A', 'torque constant'),
    'Ke': (0.05, 'V s/rad', 'back-emf constant'),
    'J': (4e-5, 'kg m^2', 'inertia of rotor, coupling and screw'),
    'B': (1e-4, 'N m s/rad', 'viscous friction of motor and screw bearings'),
    'lead': (5.0, 'mm/rev', 'ball-screw lead (nut travel per revolution)'),
    # ball-screw-nut backlash: eq. (6.2), x [mm/s] -> v [mm/s]
    'm1': (0.98, '1', 'slope of the increase line'),
    'm2': (0.94, '1', 'slope of the decrease line'),
    'D1': (8.0, 'mm/s', 'threshold of the increase line'),
    'D2': (10.0, 'mm/s', 'threshold of the decrease line'),
    # work platform: L2 of eq. (6.3), v [mm/s] -> y [mm/s]
    'M': (12.0, 'kg', 'mass of platform and load'),
    'k': (4e6, 'N/m', 'axial stiffness of screw, nut and support bearings'),
    'c': (3300.0, 'N s/m', 'damping of that axial compliance'),
    'b': (150.0, 'N s/m', 'viscous friction of the linear guides'),
}


def _xy_params(params):
    unknown = sorted(set(params) - set(XY_STAGE_PARAMETERS))
    if unknown:
        raise TypeError(
            f"unknown X-Y stage parameter(s) {unknown}; valid names are "
            f"{sorted(XY_STAGE_PARAMETERS)} (see XY_STAGE_PARAMETERS)")
    out = {}
    for key, (value, unit, _) in XY_STAGE_PARAMETERS.items():
        out[key] = check_positive(f"{key} [{unit}]", params.get(key, value))
    return out


def xy_stage_continuous(**params):
    r"""Continuous-time motor and platform models of the X-Y stage axis.

    The DC servomotor, driven through an amplifier of gain Ka, turns the
    ball screw; with the lead :math:`\ell` the screw's surface speed is
    the nut speed the motor commands, x = (lead / 2 pi) omega, in mm/s:

    .. math:: L_1(s) = \frac{X(s)}{U(s)} = \frac{\ell}{2\pi}
              \frac{K_a K_t}{(L s + R)(J s + B) + K_t K_e}.

    The platform of mass M is coupled to the nut through the axial
    stiffness k and damping c of screw, nut and bearings, and slides on
    guides with viscous friction b. With v the nut speed delivered
    through the backlash, the platform speed y obeys
    :math:`M \ddot p = k (p_n - p) + c (v - y) - b y`, so

    .. math:: L_2(s) = \frac{Y(s)}{V(s)} = \frac{c s + k}
              {M s^2 + (c + b) s + k}.

    Both are second-order and stable, as Section 6 describes.

    Parameters
    ----------
    **params : float
        Overrides of `XY_STAGE_PARAMETERS` (SI units, except lead in
        mm/rev, which makes the speeds come out in mm/s).

    Returns
    -------
    motor, platform : control.TransferFunction
        L1(s) from u [V] to x [mm/s] and L2(s) from v [mm/s] to
        y [mm/s], continuous time.

    Raises
    ------
    TypeError
        If a parameter name is unknown.
    ValueError
        If a parameter is not a finite positive number.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> motor, platform = sw.examples.xy_stage_continuous()
    >>> motor.poles().real.round(1)      # electrical and mechanical poles
    array([-1946.4,   -56.1])
    >>> round(float(motor.dcgain()), 1)  # mm/s per volt
    151.9
    >>> round(float(platform.dcgain()), 6)
    1.0
    """
    p = _xy_params(params)
    gain = p['Ka'] * p['Kt'] * p['lead'] / (2 * np.pi)
    motor = ct.tf([gain], [p['L'] * p['J'], p['L'] * p['B'] + p['R'] * p['J'],
                            p['R'] * p['B'] + p['Kt'] * p['Ke']],
                   inputs='u', outputs='x', name='motor')
    platform = ct.tf([p['c'], p['k']], [p['M'], p['c'] + p['b'], p['k']],
                      inputs='v', outputs='y', name='platform')
    return motor, platform


def _impulse_invariant(sysc, dt):
    """(a, b, q) of eq. (2.1) of the DC-matched impulse-invariant model."""
    sysd = ct.sample_system(sysc, dt, method='impulse')
    num = np.array(sysd.num[0][0], dtype=float)
    den = np.array(sysd.den[0][0], dtype=float)
    num[np.abs(num) <= 1e-12 * np.max(np.abs(num))] = 0.0
    num *= float(sysc.dcgain()) * den.sum() / num.sum()
    lead = np.flatnonzero(num)[0]
    q = den.size - num.size + lead
    return den[1:] / den[0], np.trim_zeros(num[lead:], 'b') / den[0], q


#: longest sample time `xy_stage` takes, in seconds: there its slowest
#: pole (-56 /s) maps to e^{s dt} = 0.06 and the others to 0; much longer
#: ones leave nothing of its dynamics, and impulse invariance underflows
XY_STAGE_MOST_DT = 0.05


def xy_stage(dt=XY_STAGE_DT, name='xy_stage', **params):
    r"""One axis of the X-Y positioning stage of Section 6 (eqs. (6.1)-(6.3)).

    A DC servomotor (L1, eq. (6.1)) drives the work platform (L2, eq.
    (6.3)) through a ball-screw-nut mechanism whose clearance is the
    backlash-like hysteresis of eq. (6.2). The input u is the DSP's
    command in volts (after the dead-zone compensation that Section 6
    mentions), x is the nut speed the motor commands, v the speed the nut
    actually delivers and y the platform speed, all three in mm/s. As in
    the paper, the hysteresis acts on the speed: after a reversal the nut
    delivers no change of speed until the clearance is taken up, which
    takes D1 (rising) or D2 (falling) mm/s of motor speed.

    The continuous models of `xy_stage_continuous` are discretised with
    sample time `dt` by impulse invariance
    (``ct.sample_system(G, dt, method='impulse')``): each pole s maps to
    :math:`e^{s\,dt}`, and the numerator is then scaled so that the DC
    gain equals the continuous one. For these second-order models this
    gives exactly the structures of the paper,

    .. math::

        x(k) &= -a_1 x(k-1) - a_2 x(k-2) + b_0 u(k-1)
                \quad\text{(6.1)},\\
        y(k) &= -c_1 y(k-1) - c_2 y(k-2) + d_0 v(k) + d_1 v(k-1)
                \quad\text{(6.3)},

    with q1 = 1 and q2 = 0. (Zero-order-hold sampling would add a b1 term
    to L1 and a sample of delay to L2, which is not the paper's model.)

    With the default parameters (`XY_STAGE_PARAMETERS`) the motor has a
    mechanical time constant of 18 ms and an electrical one of 0.5 ms and
    gives 152 mm/s per volt; the platform resonates at 92 Hz with damping
    ratio 0.25. The command range of Section 6, about +-1.1 V, then moves
    x over about +-150 mm/s, far beyond the dead band D1 + D2 = 18 mm/s.

    Parameters
    ----------
    dt : float, optional
        Sample time in seconds (default 0.0005, as in Section 6).
    name : str, optional
        System name.
    **params : float
        Overrides of the physical parameters, see `XY_STAGE_PARAMETERS`.

    Returns
    -------
    SandwichSystem
        Orders na = 2, nb = 0, nc = 2, nd = 1 and delays q1 = 1, q2 = 0.
        Its ``theta`` is the normalised vector (b0 = d0 = 1) that
        identification estimates.

    Raises
    ------
    TypeError
        If a parameter name is unknown.
    ValueError
        If a parameter or dt is not a finite positive number, or dt is
        above `XY_STAGE_MOST_DT`.

    See Also
    --------
    xy_stage_input : the square-plus-sine excitation of Section 6.
    xy_stage_measurement : the platform speed as an encoder measures it.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.xy_stage()
    >>> plant.orders
    {'na': 2, 'nb': 0, 'nc': 2, 'nd': 1, 'q1': 1, 'q2': 0}
    >>> print(plant)  # doctest: +NORMALIZE_WHITESPACE
    SandwichSystem xy_stage: u -> y, dt = 0.0005
      L1: x(k) = 1.35022 x(k-1) - 0.36742 x(k-2) + 2.6127 u(k-1)
      B:  v(k) = backlash(x(k)) with m1 = 0.98, m2 = 0.94, D1 = 8, D2 = 10
      L2: y(k) = 1.78902 y(k-1) - 0.866104 y(k-2) + 0.129296 v(k)
          - 0.0522129 v(k-1)
    >>> plant.theta.round(3)
    array([-1.789,  0.866, -1.35 ,  0.367,  0.331,  0.318,  3.062,  3.827,
           -0.404])
    """
    dt = check_positive('dt', dt)
    if dt > XY_STAGE_MOST_DT:
        raise ValueError(f"dt must be at most {XY_STAGE_MOST_DT} s for the "
                         f"stage, whose slowest time constant is 18 ms "
                         f"(longer samples leave nothing of its dynamics); "
                         f"got {dt}")
    motor, platform = xy_stage_continuous(**params)
    p = _xy_params(params)
    a, b, q1 = _impulse_invariant(motor, dt)
    c, d, q2 = _impulse_invariant(platform, dt)
    return SandwichSystem.from_coefficients(
        a=a, b=b, c=c, d=d, m1=p['m1'], m2=p['m2'], D1=p['D1'], D2=p['D2'],
        q1=q1, q2=q2, dt=dt, name=name)


def xy_stage_input(n, dt=XY_STAGE_DT, square_amplitude=0.62,
                   sine_amplitude=0.45, offset=-0.02, square_period=0.2,
                   sine_frequency=7.0, jitter=0.3, seed=None):
    r"""Square wave plus sinusoid: the excitation of Section 6.

    .. math:: u(k) = u_0 + A_s\,\mathrm{sq}(k) + A \sin(2\pi f k\,dt
              + \varphi),

    where sq switches between +1 and -1 after half-periods drawn
    uniformly from :math:`(1 \pm \text{jitter})\,T_s/2` (so the record is
    not periodic and fresh validation data differ from the training
    data), and the phases are random. With the defaults u stays within
    [offset - A_s - A, offset + A_s + A] = [-1.09 V, 1.05 V], the range of
    Section 6.

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float, optional
        Sample time in seconds (default 0.0005).
    square_amplitude : float, optional
        A_s in volts (default 0.62).
    sine_amplitude : float, optional
        A in volts (default 0.45).
    offset : float, optional
        u_0 in volts (default -0.02).
    square_period : float, optional
        Mean period T_s of the square wave in seconds (default 0.2).
    sine_frequency : float, optional
        f in Hz (default 7).
    jitter : float, optional
        Relative spread of the half-periods, in [0, 1) (default 0.3; 0
        gives a periodic square wave).
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.

    Returns
    -------
    ndarray, shape (n,)
        The input in volts.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> u = sw.examples.xy_stage_input(20000, seed=0)
    >>> bool(u.min() >= -1.09 and u.max() <= 1.05)
    True
    >>> float(u.min().round(2)), float(u.max().round(2))
    (-1.09, 1.05)
    """
    n = check_int('n', n, minimum=1)
    dt = check_positive('dt', dt)
    amp_sq = check_nonnegative('square_amplitude', square_amplitude)
    amp_sin = check_nonnegative('sine_amplitude', sine_amplitude)
    offset = check_finite('offset', offset)
    period = check_positive('square_period', square_period)
    freq = check_nonnegative('sine_frequency', sine_frequency)
    jitter = check_nonnegative('jitter', jitter)
    if jitter >= 1:
        raise ValueError(f"jitter must be in [0, 1); got {jitter}")
    rng = check_rng('seed', seed)
    half = period / 2 / dt                       # samples per half-period
    square = np.empty(n)
    level = 1.0 if rng.random() < 0.5 else -1.0
    k = 0
    first = rng.uniform(0, half)                 # random phase
    while k < n:
        length = first if k == 0 else half * rng.uniform(1 - jitter,
                                                          1 + jitter)
        stop = min(n, k + max(int(round(length)), 1))
        square[k:stop] = level
        level = -level
        k = stop
    t = dt * np.arange(n)
    phase = rng.uniform(0, 2 * np.pi)
    return (offset + amp_sq * square
            + amp_sin * np.sin(2 * np.pi * freq * t + phase))


def xy_stage_measurement(y, dt=XY_STAGE_DT, resolution=1e-4, noise_std=0.2,
                         seed=None):
    r"""The platform speed as the stage measures it: encoder plus noise.

    The linear encoder counts the platform position in steps of
    `resolution`; the DSP differentiates the count. With the position
    :math:`p(k) = p_0 + dt \sum_{i \le k} y(i)` (p0 random within one
    step) and :math:`Q` rounding down to the encoder grid,

    .. math:: y_m(k) = \frac{Q(p(k)) - Q(p(k-1))}{dt} + n(k),

    where n is white Gaussian noise of standard deviation `noise_std`
    (sampling jitter and electrical pick-up). The quantisation error alone
    is smaller than resolution / dt in magnitude (0.2 mm/s by default).

    Parameters
    ----------
    y : array_like, shape (N,)
        True platform speed in mm/s.
    dt : float, optional
        Sample time in seconds (default 0.0005).
    resolution : float, optional
        Encoder resolution in mm (default 1e-4, i.e. 0.1 um); 0 turns the
        quantisation off.
    noise_std : float, optional
        Standard deviation of n(k) in mm/s (default 0.2); 0 turns it off.
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.

    Returns
    -------
    ndarray, shape (N,)
        Measured speed in mm/s.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> y = 100 * np.sin(np.linspace(0, 20, 5000))
    >>> ym = sw.examples.xy_stage_measurement(y, noise_std=0, seed=0)
    >>> bool(np.max(np.abs(ym - y)) < 1e-4 / 0.0005)
    True
    """
    y = check_signal('y', y)
    dt = check_positive('dt', dt)
    resolution = check_nonnegative('resolution', resolution)
    noise_std = check_nonnegative('noise_std', noise_std)
    rng = check_rng('seed', seed)
    measured = y.copy()
    if resolution > 0:
        p0 = rng.uniform(0, resolution)
        position = p0 + dt * np.cumsum(y)
        counts = np.floor(np.concatenate([[p0], position]) / resolution)
        measured = np.diff(counts) * resolution / dt
    if noise_std > 0:
        measured = measured + noise_std * rng.standard_normal(y.size)
    return measured
