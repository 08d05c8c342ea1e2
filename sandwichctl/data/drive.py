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
============ ======= =====================================================

With these values the speed loop crosses over at about 200 rad/s
(Kv / (J + M lead^2 / (2 pi)^2)) and the position loop at about 40 rad/s.
"""

from dataclasses import dataclass, field

import numba
import numpy as np

from .._checks import (check_int, check_positive, check_nonnegative,
                       check_signal)

__all__ = ['servo_drive', 'drive_reference', 'drive_case', 'DriveCase',
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
}

_NONNEGATIVE = ('B', 'c', 'Fc', 'b', 'Ki_pos', 'torque_noise')
_INTEGER = {'counts': 0, 'substeps': 1}
_LOOPS = ('position', 'speed')


def _params(params):
    unknown = sorted(set(params) - set(DRIVE_PARAMETERS))
    if unknown:
        raise TypeError(
            f"unknown servo-drive parameter(s) {unknown}; valid names are "
            f"{sorted(DRIVE_PARAMETERS)} (see DRIVE_PARAMETERS)")
    out = {}
    for key, (value, unit, _) in DRIVE_PARAMETERS.items():
        value = params.get(key, value)
        label = f"{key} [{unit}]"
        if key in _INTEGER:
            out[key] = check_int(label, value, minimum=_INTEGER[key])
        elif key in _NONNEGATIVE:
            out[key] = check_nonnegative(label, value)
        else:
            out[key] = check_positive(label, value)
    return out


@numba.njit(cache=True)
def _drive_kernel(ref, position_loop, prm, play, dt, nsub, disturbance,
                  offset, y, theta_out, torque_out, nut_out, plat_out):
    """Simulate the drive; fill y and the internal signals."""
    J, B, T_max, r, M = prm[0], prm[1], prm[2], prm[3], prm[4]
    k, c, Fc, vs, b = prm[5], prm[6], prm[7], prm[8], prm[9]
    Kv, Ti, Kp, Ki_pos = prm[10], prm[11], prm[12], prm[13]
    q_motor, res = prm[14], prm[15]
    h = dt / nsub
    g = 0.5 * play
    th = 0.0        # motor angle [rad]
    w = 0.0         # motor speed [rad/s]
    p = 0.0         # platform position [m]
    vp = 0.0        # platform speed [m/s]
    th_prev = 0.0
    i_speed = 0.0   # speed-loop integrator (in rad/s of error)
    i_pos = 0.0     # position-loop integrator [rad/s]
    for n in range(ref.size):
        # sample: measure
        y[n] = res * np.round((p + offset) / res) - res * np.round(
            offset / res)
        theta_out[n] = th
        nut_out[n] = r * th
        plat_out[n] = p
        thm = th if q_motor == 0.0 else q_motor * np.round(th / q_motor)
        wm = (thm - th_prev) / dt
        th_prev = thm
        # control
        if position_loop:
            e_pos = ref[n] - thm
            i_pos += Ki_pos * dt * e_pos
            w_ref = Kp * e_pos + i_pos
        else:
            w_ref = ref[n]
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
        torque_out[n] = T
        T += disturbance[n]
        # mechanics over one sample, torque held
        for _ in range(nsub):
            delta = r * th - p
            dv = r * w - vp
            if delta > g:
                F = k * (delta - g) + c * dv
                if F < 0.0:
                    F = 0.0
            elif delta < -g:
                F = k * (delta + g) + c * dv
                if F > 0.0:
                    F = 0.0
            else:
                F = 0.0
            w += h * (T - B * w - r * F) / J
            vp += h * (F - b * vp - Fc * np.tanh(vp / vs)) / M
            th += h * w
            p += h * vp


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
    if loop not in _LOOPS:
        raise ValueError(f"loop must be 'position' or 'speed'; got {loop!r}")
    play = check_nonnegative('play', play)
    dt = check_positive('dt', dt)
    p = _params(params)
    rng = np.random.default_rng(seed)
    disturbance = p['torque_noise'] * rng.standard_normal(u.size)
    offset = rng.uniform(0, p['resolution'])
    q_motor = 2 * np.pi / p['counts'] if p['counts'] else 0.0
    prm = np.array([p['J'], p['B'], p['T_max'], p['lead'] / (2 * np.pi),
                    p['M'], p['k'], p['c'], p['Fc'], p['vs'], p['b'],
                    p['Kv'], p['Ti'], p['Kp'], p['Ki_pos'], q_motor,
                    p['resolution']])
    out = [np.empty(u.size) for _ in range(5)]
    _drive_kernel(u, loop == 'position', prm, play, dt, p['substeps'],
                  disturbance, offset, *out)
    y = out[0]
    if not np.all(np.isfinite(y)):
        raise RuntimeError("the servo-drive simulation diverged; reduce the "
                           "gains or increase substeps")   # pragma: no cover
    if internal:
        return y, dict(zip(('theta', 'torque', 'nut', 'platform'), out[1:]))
    return y


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
    n = check_int('n', n, minimum=2)
    if loop not in _LOOPS:
        raise ValueError(f"loop must be 'position' or 'speed'; got {loop!r}")
    dt = check_positive('dt', dt)
    rng = np.random.default_rng(rng)
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


@dataclass(repr=False)
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

    def __repr__(self):
        return (f"DriveCase(seed={self.seed}, loop={self.loop!r}, "
                f"play={self.play:g}, n={self.u.size}, "
                f"n_val={self.u_val.size}, dt={self.dt:g})")


def drive_case(seed, loop='position', play=200e-6, n=5000, n_val=None,
               **params):
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
    n = check_int('n', n, minimum=2)
    n_val = n if n_val is None else check_int('n_val', n_val, minimum=2)
    r_est, r_val, d_est, d_val = (
        np.random.default_rng(s)
        for s in np.random.SeedSequence([seed, 0xd21e]).spawn(4))
    u = drive_reference(n, loop, r_est)
    u_val = drive_reference(n_val, loop, r_val)
    y = servo_drive(u, loop, play, seed=d_est, **params)
    y_val = servo_drive(u_val, loop, play, seed=d_val, **params)
    return DriveCase(u=u, y=y, u_val=u_val, y_val=y_val, dt=DRIVE_DT,
                     loop=loop, play=float(play), seed=seed,
                     params=_params(params))
