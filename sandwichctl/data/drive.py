r"""A physically simulated servo drive with play (not a sandwich system).

The drive is a ball-screw positioning axis. A motor of inertia J, with
viscous friction and a torque limit, is run by a digital PI speed loop
(sample time dt = 1 ms), optionally inside a P (or PI) position loop on
the motor angle. The motor turns a ball screw whose nut, at
``x_n = theta * lead / (2 pi)``, pushes the platform through a dead-zone
spring: inside the play (total width `play`) no force is transmitted;
outside it a stiff spring with damping (contact only pushes). The
platform of mass M slides with smoothed Coulomb and viscous friction. A
linear encoder measures the platform position with a resolution of
1 um; that measurement is the output y.

In discrete time this is close to, but not exactly, a sandwich: the
closed motor loops play the part of L1 (reference -> nut position), the
play and the platform friction that of the backlash, and the platform
dynamics that of L2. The play makes the platform stop when the nut
reverses, until the nut has crossed the gap, and the friction makes the
platform coast after the nut retreats, so the "backlash" depends on the
platform's speed, and the motor feels a lighter load while the gap is
open.

The continuous mechanics are integrated with semi-implicit (symplectic)
Euler at ``substeps`` sub-steps per sample (default 40, i.e. 25 us),
with the motor torque held between samples. The contact frequency,
about 1,200 rad/s with the defaults, is then resolved with
:math:`\omega h \approx 0.03`.

Physical parameters (`DRIVE_PARAMETERS`, overridable by keyword):

============ ======= =====================================================
name         default meaning
============ ======= =====================================================
J            1e-4    inertia of rotor, coupling and screw [kg m^2]
B            2e-4    viscous friction of motor and bearings [N m s/rad]
T_max        3.0     torque limit [N m]
lead         0.010   ball-screw lead [m/rev]
M            20.0    platform and load mass [kg]
k            2e7     axial contact stiffness of nut and screw [N/m]
c            4000.0  contact damping [N s/m]
Fc           30.0    Coulomb friction of the guides [N]
vs           1e-3    smoothing speed of the Coulomb friction (tanh) [m/s]
b            300.0   viscous friction of the guides [N s/m]
Kv           0.03    speed-loop proportional gain [N m s/rad]
Ti           0.02    speed-loop integral time [s]
Kp           40.0    position-loop gain [1/s]
Ki_pos       0.0     position-loop integral gain [1/s^2] (0: P loop)
counts       65536   motor-encoder counts per revolution (0: ideal)
resolution   1e-6    linear-encoder resolution [m]
torque_noise 2e-3    std of a white torque disturbance per sample [N m]
substeps     40      integration sub-steps per sample
contact      1.0     exponent p of the contact law (see below)
d0           1e-6    reference deflection of the contact law [m]
============ ======= =====================================================

The contact force at a deflection :math:`\delta > 0` beyond the gap, with
:math:`s = \delta / d_0` and relative speed :math:`\dot\delta`, is
:math:`F = k d_0 s^p + c\, s^{p-1} \dot\delta` (pushing only): with
p = 1 the linear spring and damper, with p = 1.5 a Hertzian contact of
the balls with Hunt-Crossley damping, whose force grows from zero
without a jump when the gap closes.

With these values the speed loop crosses over at about 200 rad/s
(Kv / (J + M lead^2 / (2 pi)^2)) and the position loop at about 40 rad/s.
"""

import math
from dataclasses import dataclass, field

import numba
import numpy as np

from .synthetic import same_case
from .._checks import (MOST_SAMPLES, PLAIN_REALS, check_bool, check_int,
                       check_positive, check_nonnegative, check_option,
                       check_real, check_rng, check_signal)

__all__ = ['servo_drive', 'ServoDrive', 'random_drive', 'drive_reference', 'drive_case', 'DriveCase',
           'DRIVE_PARAMETERS', 'DRIVE_DT']

#: Sample time of the digital controller, in seconds.
DRIVE_DT = 1e-3

#: Physical and controller parameters: name -> (value, unit, meaning).
DRIVE_PARAMETERS = {
    'J': (1e-4, 'kg m^2', 'inertia of rotor, coupling and screw'),
    'B': (2e-4, 'N m s/rad', 'viscous friction of motor and bearings'),
    'T_max': (3.0, 'N m', 'motor torque limit'),
    'lead': (0.010, 'm/rev', 'ball-screw lead'),
    'M': (20.0, 'kg', 'mass of platform and load'),
    'k': (2e7, 'N/m', 'axial contact stiffness of nut and screw'),
    'c': (4000.0, 'N s/m', 'contact damping'),
    'Fc': (30.0, 'N', 'Coulomb friction of the guides'),
    'vs': (1e-3, 'm/s', 'smoothing speed of the Coulomb friction'),
    'b': (300.0, 'N s/m', 'viscous friction of the guides'),
    'Kv': (0.03, 'N m s/rad', 'speed-loop proportional gain'),
    'Ti': (0.02, 's', 'speed-loop integral time'),
    'Kp': (40.0, '1/s', 'position-loop gain'),
    'Ki_pos': (0.0, '1/s^2', 'position-loop integral gain (0: P loop)'),
    'counts': (65536, 'counts/rev', 'motor-encoder resolution (0: ideal)'),
    'resolution': (1e-6, 'm', 'linear-encoder resolution'),
    'torque_noise': (2e-3, 'N m', 'std of a white torque disturbance'),
    'substeps': (40, '1', 'integration sub-steps per sample'),
    'contact': (1.0, '1', 'exponent p of the contact law (1: linear '
                'spring and damper; 1.5: Hertzian, Hunt-Crossley damping)'),
    'd0': (1e-6, 'm', 'deflection at which a contact law with p != 1 has '
           'the force of the linear one'),
}

_NONNEGATIVE = ('B', 'c', 'Fc', 'b', 'Ki_pos', 'torque_noise')
_INTEGER = {'counts': 0, 'substeps': 1}
#: a physical parameter may lie this many times above or below its
#: default (Ki_pos, 0 by default, up to this many times Kp**2): wider than
#: any drive of this kind, and narrow enough that no force or gain
#: overflows the simulation into a finite nonsense
SPAN = 1e6
#: most play a drive may have, in m (random_drive draws at most 300 um)
MOST_PLAY = 0.1
#: most sub-steps a sample (random_drive draws at most a few hundred)
MOST_SUBSTEPS = 10_000
_LOOPS = ('position', 'speed')


def _params(params):
    unknown = sorted(set(params) - set(DRIVE_PARAMETERS))
    if unknown:
        raise TypeError(
            f"unknown servo-drive parameter(s) {unknown}; valid names are "
            f"{sorted(DRIVE_PARAMETERS)} (see DRIVE_PARAMETERS)")
    out = {}
    for key, (default, unit, _) in DRIVE_PARAMETERS.items():
        value = params.get(key, default)
        label = f"{key} [{unit}]"
        if key in _INTEGER:
            out[key] = check_int(label, value, minimum=_INTEGER[key],
                                 maximum=(MOST_SUBSTEPS if key == 'substeps'
                                          else None))
            continue
        if key in _NONNEGATIVE:
            out[key] = check_nonnegative(label, value)
        else:
            out[key] = check_positive(label, value)
        ref = default if default else DRIVE_PARAMETERS['Kp'][0] ** 2
        if key != 'contact' and (out[key] > SPAN * ref
                                 or 0 < out[key] < ref / SPAN):
            off = ' (or be 0)' if key in _NONNEGATIVE else ''
            raise ValueError(f"{label} must lie within {SPAN:.0e} times "
                             f"{ref:g} either way{off}; got {out[key]!r}")
    if not 1.0 <= out['contact'] <= 3.0:
        raise ValueError(f"contact [1] must be in [1, 3] (1: linear, 1.5: "
                         f"Hertzian); got {out['contact']!r}")
    return out


# The drive's state vector: motor angle [rad] and speed [rad/s], platform
# position [m] and speed [m/s], the last measured motor angle, and the
# speed- and position-loop integrators.
_TH, _W, _P, _VP, _TH_PREV, _I_SPEED, _I_POS = range(7)
_NSTATE = 7


@numba.njit(cache=True)
def _drive_measure(state, res, offset):
    """The linear encoder's reading of the platform position."""
    return (res * np.round((state[_P] + offset) / res)
            - res * np.round(offset / res))


@numba.njit(cache=True)
def _drive_step(state, ref, position_loop, prm, play, dt, nsub, disturbance):
    """Advance the drive by one sample under reference `ref`.

    Runs the digital loops on the sampled motor angle, then integrates the
    mechanics over the sample with the torque held. Returns the commanded
    torque after the limit.
    """
    J, B, T_max, r, M = prm[0], prm[1], prm[2], prm[3], prm[4]
    k, c, Fc, vs, b = prm[5], prm[6], prm[7], prm[8], prm[9]
    Kv, Ti, Kp, Ki_pos = prm[10], prm[11], prm[12], prm[13]
    q_motor = prm[14]
    law, d0 = prm[16], prm[17]
    h = dt / nsub
    g = 0.5 * play
    th, w, p, vp = state[_TH], state[_W], state[_P], state[_VP]
    i_speed, i_pos = state[_I_SPEED], state[_I_POS]
    thm = th if q_motor == 0.0 else q_motor * np.round(th / q_motor)
    wm = (thm - state[_TH_PREV]) / dt
    state[_TH_PREV] = thm
    # control
    if position_loop:
        e_pos = ref - thm
        i_pos += Ki_pos * dt * e_pos
        w_ref = Kp * e_pos + i_pos
    else:
        w_ref = ref
    e = w_ref - wm
    i_new = i_speed + dt / Ti * e
    T = Kv * (e + i_new)
    if T > T_max:
        T = T_max
        if e < 0.0:
            i_speed = i_new
    elif T < -T_max:
        T = -T_max
        if e > 0.0:
            i_speed = i_new
    else:
        i_speed = i_new
    torque = T
    T += disturbance
    # mechanics over one sample, torque held
    for _ in range(nsub):
        delta = r * th - p
        dv = r * w - vp
        if delta > g:
            if law == 1.0:
                F = k * (delta - g) + c * dv
            else:
                sc = (delta - g) / d0
                F = k * d0 * sc ** law + c * sc ** (law - 1.0) * dv
            if F < 0.0:
                F = 0.0
        elif delta < -g:
            if law == 1.0:
                F = k * (delta + g) + c * dv
            else:
                sc = -(delta + g) / d0
                F = -k * d0 * sc ** law + c * sc ** (law - 1.0) * dv
            if F > 0.0:
                F = 0.0
        else:
            F = 0.0
        w += h * (T - B * w - r * F) / J
        vp += h * (F - b * vp - Fc * np.tanh(vp / vs)) / M
        th += h * w
        p += h * vp
    state[_TH], state[_W], state[_P], state[_VP] = th, w, p, vp
    state[_I_SPEED], state[_I_POS] = i_speed, i_pos
    return torque


@numba.njit(cache=True)
def _drive_kernel(ref, position_loop, prm, play, dt, nsub, disturbance,
                  offset, y, theta_out, torque_out, nut_out, plat_out):
    """Simulate the drive from rest; fill y and the internal signals."""
    state = np.zeros(_NSTATE)
    for n in range(ref.size):
        y[n] = _drive_measure(state, prm[15], offset)
        theta_out[n] = state[_TH]
        nut_out[n] = prm[3] * state[_TH]
        plat_out[n] = state[_P]
        torque_out[n] = _drive_step(state, ref[n], position_loop, prm, play,
                                    dt, nsub, disturbance[n])


def servo_drive(reference, loop='position', play=200e-6, dt=DRIVE_DT,
                seed=None, internal=False, **params):
    """Simulate the servo drive and return the measured platform position.

    Parameters
    ----------
    reference : array_like, shape (N,)
        Reference of the outer loop at each sample: the motor angle in rad
        for ``loop='position'``, the motor speed in rad/s for
        ``loop='speed'``.
    loop : {'position', 'speed'}, optional
        Close the position loop around the speed loop (default), or run
        the speed loop alone (the output then integrates the reference).
    play : float, optional
        Total width of the gap between nut and platform, in metres
        (default 200e-6; 0 gives a plain spring).
    dt : float, optional
        Sample time of the controller and of y, in seconds (default 1 ms).
    seed : int or numpy.random.Generator, optional
        Seed of the torque disturbance and of the linear encoder's zero
        offset (within one count). The same seed gives the same y.
    internal : bool, optional
        Also return the internal signals.
    **params
        Overrides of `DRIVE_PARAMETERS` (SI units).

    Returns
    -------
    y : ndarray, shape (N,)
        Platform position as the linear encoder measures it, in metres: a
        multiple of ``resolution`` (1 um), 0 at rest.
    signals : dict
        Only if `internal`: 'theta' (motor angle, rad), 'torque'
        (commanded torque after the limit, N m), 'nut' and 'platform'
        (true positions, m), all at the sample instants.

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.data import servo_drive
    >>> ref = np.r_[np.zeros(10), np.ones(490)]       # 1 rad step
    >>> y = servo_drive(ref, play=0.0, seed=0)
    >>> round(float(y[-1]) * 1e3, 2)                  # mm, = lead / (2 pi)
    1.59
    """
    u = check_signal('reference', reference)
    internal = check_bool('internal', internal)
    setup = _setup(loop, play, dt, seed, u.size, params)
    out = [np.empty(u.size) for _ in range(5)]
    _drive_kernel(u, setup.position_loop, setup.prm, setup.play, setup.dt,
                  setup.nsub, setup.disturbance, setup.offset, *out)
    y = out[0]
    if not np.all(np.isfinite(y)):
        raise RuntimeError("the servo-drive simulation diverged; reduce the "
                           "gains or increase substeps")   # pragma: no cover
    if internal:
        return y, dict(zip(('theta', 'torque', 'nut', 'platform'), out[1:]))
    return y


@dataclass(frozen=True)
class _Setup:
    position_loop: bool
    prm: np.ndarray
    play: float
    dt: float
    nsub: int
    disturbance: np.ndarray
    offset: float
    params: dict


def _check_sample_time(dt):
    """dt in s, between 1e-9 and 1e3."""
    dt = check_positive('dt', dt)
    if not 1e-9 <= dt <= 1e3:
        raise ValueError(f"dt must be a sample time between 1e-9 and 1e3 "
                         f"s; got {dt!r}")
    return dt


def _setup(loop, play, dt, seed, n, params):
    """Checked arguments, kernel parameters and the random draws of a run
    of n samples (the torque disturbance, then the encoder offset)."""
    check_option('loop', loop, _LOOPS)
    play = check_nonnegative('play', play)
    if play > MOST_PLAY:
        raise ValueError(f"play must be at most {MOST_PLAY:g} m (a gap of a "
                         f"ball-screw drive, in metres); got {play!r}")
    dt = _check_sample_time(dt)
    p = _params(params)
    _check_substep(p, dt)
    rng = check_rng('seed', seed)
    disturbance = p['torque_noise'] * rng.standard_normal(n)
    offset = rng.uniform(0, p['resolution'])
    q_motor = 2 * np.pi / p['counts'] if p['counts'] else 0.0
    prm = np.array([p['J'], p['B'], p['T_max'], p['lead'] / (2 * np.pi),
                    p['M'], p['k'], p['c'], p['Fc'], p['vs'], p['b'],
                    p['Kv'], p['Ti'], p['Kp'], p['Ki_pos'], q_motor,
                    p['resolution'], p['contact'], p['d0']])
    return _Setup(loop == 'position', prm, play, dt, p['substeps'],
                  disturbance, offset, p)


#: the integration is refused when a sub-step h = dt / substeps is this
#: near to where its semi-implicit Euler turns unstable (1: at it; the
#: random drives, random_drive(0 to 1999), use at most 0.16 of it)
SUBSTEP_MOST = 0.5


def _check_substep(p, dt):
    """Refuse parameters for which a sub-step is too coarse: the
    semi-implicit Euler of the mechanics is stable while h^2 k/m + 2 h c/m
    < 4 on the contact (m the platform's and the reflected rotor's
    masses in series; k and c the slopes of a contact law at its d0) and
    h (b + Fc/vs)/M < 2 on the guides' friction, h B/J < 2 on the motor's;
    beyond, the simulation blows up into numbers that mean nothing."""
    h = dt / p['substeps']
    rotor = p['J'] / (p['lead'] / (2 * np.pi)) ** 2
    m = p['M'] * rotor / (p['M'] + rotor)
    law = p['contact']
    for what, value, limit in (
            ("the nut's contact (k, c, M, J)",
             h * h * law * p['k'] / m + 2 * h * p['c'] / m, 4.0),
            ("the guides' friction (b, Fc / vs, M)",
             h * (p['b'] + p['Fc'] / p['vs']) / p['M'], 2.0),
            ("the motor's friction (B, J)", h * p['B'] / p['J'], 2.0)):
        if not value < SUBSTEP_MOST * limit:
            raise ValueError(
                f"substeps={p['substeps']} is too few for {what}: a sub-step "
                f"of {h:.3g} s would make the simulation diverge ("
                f"{value / limit:.3g} of the stability limit, at most "
                f"{SUBSTEP_MOST:g}); increase substeps or make the contact "
                f"softer or the masses larger")


class ServoDrive:
    """The servo drive of `servo_drive`, one sample at a time.

    For running a controller against the physical simulation: `read`
    returns the encoder's reading y(k), `apply` holds the reference u(k)
    for one sample, and `step` does both (``y(k+1) = step(u(k))``), the
    per-sample protocol of `sandwichctl.closed_loop_response`. Over `n`
    samples it is bit for bit `servo_drive` with the same arguments: the
    torque disturbance of n samples and then the encoder offset are drawn
    from `seed` exactly as there. Stepping past n samples raises.

    Parameters
    ----------
    loop, play, dt, seed, **params
        As for `servo_drive`.
    n : int, optional
        Number of samples the disturbance is drawn for (default 100,000).

    Attributes
    ----------
    k : int
        Samples applied since the last `reset`.
    saturated : int
        How many of them ran the motor at its torque limit.
    dt : float
        Sample time in seconds.
    params : dict
        The physical parameters used.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> ref = np.r_[np.zeros(10), np.ones(90)]
    >>> drive = sw.data.ServoDrive(play=0.0, seed=0, n=ref.size)
    >>> y = np.array([drive.step(u) for u in ref[:-1]])
    >>> bool(np.array_equal(np.r_[0.0, y],
    ...                     sw.data.servo_drive(ref, play=0.0, seed=0)))
    True
    """

    def __init__(self, loop='position', play=200e-6, dt=DRIVE_DT, seed=None,
                 n=100_000, **params):
        n = check_int('n', n, minimum=1, maximum=MOST_SAMPLES)
        self._setup = _setup(loop, play, dt, seed, n, params)
        self.loop = loop
        self.dt = self._setup.dt
        self.params = self._setup.params
        self.reset()

    def reset(self):
        """Back to rest at k = 0 (the same disturbance sequence again)."""
        self._state = np.zeros(_NSTATE)
        self.k = 0
        self.saturated = 0

    def read(self):
        """The encoder reading y(k) of the platform position, in metres."""
        return float(_drive_measure(self._state, self._setup.prm[15],
                                    self._setup.offset))

    def apply(self, u):
        """Hold the reference u(k) for one sample (rad or rad/s).

        Returns the commanded motor torque after the limit, in N m.
        """
        su = self._setup
        if self.k >= su.disturbance.size:
            raise RuntimeError(f"the drive was set up for n = "
                               f"{su.disturbance.size} samples; make it "
                               f"with a larger n")
        try:
            u = float(u) if type(u) in PLAIN_REALS else check_real('u', u)
        except OverflowError:                   # an int beyond a float
            u = check_real('u', u)
        if not np.isfinite(u):
            raise ValueError(f"u must be finite; got {u}")
        torque = _drive_step(self._state, u, su.position_loop, su.prm,
                             su.play, su.dt, su.nsub,
                             su.disturbance[self.k])
        if not (math.isfinite(self._state[_P])
                and math.isfinite(self._state[_TH])):
            raise RuntimeError(f"the servo-drive simulation diverged at "
                               f"sample {self.k}; call reset() (u = {u!r})")
        self.k += 1
        if abs(torque) >= su.prm[2]:
            self.saturated += 1
        return float(torque)

    def step(self, u):
        """Apply u(k) for one sample and return the next reading y(k+1)."""
        self.apply(u)
        return self.read()

    def __repr__(self):
        return (f"ServoDrive(loop={self.loop!r}, play={self._setup.play:g},"
                f" dt={self.dt:g}, k={self.k})")


def _staircase(n, rng, hold, step, bound, start=0.0):
    """Random staircase: holds in `hold` samples, steps of at most `step`,
    levels kept within +-bound (reflected)."""
    out = np.empty(n)
    level, k = start, 0
    while k < n:
        m = int(rng.integers(*hold))
        out[k:k + m] = level
        k += m
        level += rng.uniform(-step, step)
        if abs(level) > bound:
            level = np.sign(level) * (2 * bound - abs(level))
    return out


def _multisine(n, rng, dt, band, rms, count=20):
    f = np.exp(rng.uniform(*np.log(band), count))
    phase = rng.uniform(0, 2 * np.pi, count)
    s = np.cos(2 * np.pi * np.outer(np.arange(n) * dt, f) + phase).sum(axis=1)
    return rms * s / np.sqrt(np.mean(s ** 2))


def drive_reference(n, loop='position', rng=None, dt=DRIVE_DT):
    """A sensible excitation for `servo_drive`.

    ``'position'``: a random staircase of motor angles (holds 0.15 to
    0.6 s, steps up to 1 rad, levels within +-2 rad, i.e. +-3.2 mm of
    platform travel with the 10 mm lead) plus a multisine of 20 random
    frequencies in 0.2..10 Hz with RMS 0.25 rad. ``'speed'``: a random
    speed staircase (holds 0.1 to 0.4 s, levels within +-20 rad/s, the
    sign chosen so that the integrated angle stays within about
    +-15 rad, i.e. +-2.4 cm) plus a multisine of 0.5..10 Hz with RMS
    5 rad/s, made exactly zero-mean.

    Parameters
    ----------
    n : int
        Number of samples.
    loop : {'position', 'speed'}, optional
        Which reference to draw (rad or rad/s).
    rng : numpy.random.Generator or int or None, optional
        Random generator or seed.
    dt : float, optional
        Sample time (default 1 ms).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> from sandwichctl.data import drive_reference
    >>> r = drive_reference(5000, 'position', rng=1)
    >>> bool(abs(r).max() < 3.5)
    True
    """
    n = check_int('n', n, minimum=2, maximum=MOST_SAMPLES)
    check_option('loop', loop, _LOOPS)
    dt = _check_sample_time(dt)
    rng = check_rng('rng', rng)
    hold = (max(1, int(0.15 / dt)), max(2, int(0.6 / dt)))
    if loop == 'position':
        return (_staircase(n, rng, hold, 1.0, 2.0)
                + _multisine(n, rng, dt, (0.2, 10.0), 0.25))
    hold = (max(1, int(0.1 / dt)), max(2, int(0.4 / dt)))
    out = np.empty(n)
    angle, k = 0.0, 0
    while k < n:
        m = min(int(rng.integers(*hold)), n - k)
        level = rng.uniform(-20.0, 20.0)
        if abs(angle + level * m * dt) > 15.0:
            level = -np.sign(angle) * abs(level)
        out[k:k + m] = level
        angle += level * m * dt
        k += m
    out += _multisine(n, rng, dt, (0.5, 10.0), 5.0)
    return out - out.mean()


def random_drive(seed):
    """A randomised servo drive: the mechanics, loop and sampling of one
    seeded draw, for checking methods beyond the default drive.

    What varies (log-uniform unless said): platform mass M 5-60 kg, motor
    inertia J 0.5-3e-4 kg m^2, Coulomb friction Fc 5-60 N, viscous
    friction b 50-800 N s/m, contact stiffness k 5e6-5e7 N/m and damping
    c 1e3-1e4 N s/m, play uniform in 0-300 um (0 in one draw of five),
    the loop (position or speed, even odds), the speed-loop gain Kv
    (scaled with the reflected inertia so the speed loop crosses over at
    100-300 rad/s) and integral time Ti 10-40 ms, the position gain Kp
    20-60 1/s, the sample time 0.25-2 ms, the linear encoder's resolution
    0.1-5 um, the torque disturbance 0.5-5e-3 N m, and the contact law
    (linear, or Hertzian with Hunt-Crossley damping, even odds).

    Parameters
    ----------
    seed : int
        Seed (>= 0).

    Returns
    -------
    dict
        'loop', 'play' (m), 'dt' (s) and 'params' (overrides of
        `DRIVE_PARAMETERS`), ready for ``servo_drive(ref, d['loop'],
        d['play'], d['dt'], **d['params'])`` or `ServoDrive`.

    Examples
    --------
    >>> from sandwichctl.data import random_drive
    >>> d = random_drive(3)
    >>> sorted(d)
    ['dt', 'loop', 'params', 'play']
    >>> random_drive(3) == d
    True
    """
    seed = check_int('seed', seed)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xd71e]))

    def logu(a, b):
        return float(np.exp(rng.uniform(np.log(a), np.log(b))))

    M, J = logu(5, 60), logu(0.5e-4, 3e-4)
    lead = DRIVE_PARAMETERS['lead'][0]
    inertia = J + M * (lead / (2 * np.pi)) ** 2
    params = dict(M=M, J=J, Fc=logu(5, 60), b=logu(50, 800),
                  k=logu(5e6, 5e7), c=logu(1e3, 1e4),
                  Kv=inertia * logu(100, 300), Ti=logu(0.01, 0.04),
                  Kp=logu(20, 60), resolution=logu(1e-7, 5e-6),
                  torque_noise=logu(0.5e-3, 5e-3))
    play = 0.0 if rng.uniform() < 0.2 else float(rng.uniform(0, 300e-6))
    loop = 'position' if rng.uniform() < 0.5 else 'speed'
    dt = logu(0.25e-3, 2e-3)
    # enough sub-steps to resolve the contact frequency sqrt(k/M)
    params['substeps'] = int(np.ceil(dt * np.sqrt(params['k'] / M) / 0.03))
    # the contact law is drawn last, so the draws above are those of the
    # drives before it was varied
    if rng.uniform() < 0.5:
        # Hertzian: stiffer under load, so twice the sub-steps
        params.update(contact=1.5, substeps=2 * params['substeps'])
    return dict(loop=loop, play=play, dt=dt, params=params)


@dataclass(repr=False, eq=False)
class DriveCase:
    """Estimation and validation records of the servo drive.

    Attributes
    ----------
    u, y : ndarray
        Reference and measured platform position (estimation record).
    u_val, y_val : ndarray
        A separate validation record (new reference and disturbance).
    dt : float
        Sample time in seconds.
    loop : str
        'position' (u in rad) or 'speed' (u in rad/s; y integrates).
    play : float
        Total play in metres.
    seed : int
        Seed of `drive_case`.
    params : dict
        The physical parameters used.
    """

    u: np.ndarray
    y: np.ndarray
    u_val: np.ndarray
    y_val: np.ndarray
    dt: float
    loop: str
    play: float
    seed: int
    params: dict = field(default_factory=dict)

    def __eq__(self, other):
        return same_case(self, other)

    __hash__ = None

    def __repr__(self):
        return (f"DriveCase(seed={self.seed}, loop={self.loop!r}, "
                f"play={self.play:g}, n={self.u.size}, "
                f"n_val={self.u_val.size}, dt={self.dt:g})")


def drive_case(seed, loop='position', play=200e-6, n=5000, n_val=None,
               dt=DRIVE_DT, **params):
    """Estimation and validation data of the servo drive.

    Parameters
    ----------
    seed : int
        Seed (>= 0) of the references and the disturbances.
    loop : {'position', 'speed'}, optional
        Loop to close (see `servo_drive`).
    play : float, optional
        Total play in metres (default 200e-6).
    n : int, optional
        Length of the estimation record (default 5000, i.e. 5 s).
    n_val : int, optional
        Length of the validation record (default n).
    dt : float, optional
        Sample time in seconds (default 1 ms; a `random_drive`'s ``dt``).
    **params
        Overrides of `DRIVE_PARAMETERS`.

    Returns
    -------
    DriveCase

    Examples
    --------
    >>> from sandwichctl.data import drive_case
    >>> case = drive_case(0, 'speed', n=2000)
    >>> case.u.size, case.y_val.size, case.dt
    (2000, 2000, 0.001)
    """
    seed = check_int('seed', seed)
    n = check_int('n', n, minimum=2, maximum=MOST_SAMPLES)
    n_val = n if n_val is None else check_int('n_val', n_val, minimum=2,
                                              maximum=MOST_SAMPLES)
    r_est, r_val, d_est, d_val = (
        np.random.default_rng(s)
        for s in np.random.SeedSequence([seed, 0xd21e]).spawn(4))
    dt = _check_sample_time(dt)
    u = drive_reference(n, loop, r_est, dt)
    u_val = drive_reference(n_val, loop, r_val, dt)
    y = servo_drive(u, loop, play, dt, seed=d_est, **params)
    y_val = servo_drive(u_val, loop, play, dt, seed=d_val, **params)
    return DriveCase(u=u, y=y, u_val=u_val, y_val=y_val, dt=dt,
                     loop=loop, play=float(play), seed=seed,
                     params=_params(params))
