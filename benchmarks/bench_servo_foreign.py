"""The documented servo route, judged on an axis simulator of our own
that shares no physics with `sandwichctl.data.drive`.

A seeded family of ball-screw axes (`draw_axis`; ranges in `RANGES`):

- a DC motor (rotor inertia Jm, torque constant Kt, a current limit
  Imax, a first-order current loop of time constant tau_e, viscous
  friction and a cogging torque of six cycles a revolution), run by a
  digital cascade at an inner tick of dt / n_in (n_in 4-10): a P or PI
  position loop on the motor encoder's angle (2^17-2^20 counts a
  revolution) around a PI speed loop on a filtered difference of it, the
  outer input interpolated linearly over the ticks (a drive's fine
  interpolator), with anti-windup at the current limit;
- a torsional coupling (stiffness kc, light damping) to the screw
  (inertia Js, lead); the nut drives the load through an axial contact
  of stiffness ka whose damping gives a restitution e, engaging at the
  edges of a gap of total width `play` (pushing only; with no play a
  preloaded, two-sided spring);
- a load of mass M on guides with LuGre friction (Stribeck curve,
  stiction, presliding bristles) plus viscous friction, pushed by a
  constant and a coloured random force (cable chain);
- a linear encoder of 0.5-2 um on the load with noise of a fraction of a
  count: the output y in m. Outer sample time dt: 0.5-2 ms.

The mechanics are integrated by semi-implicit Euler at a sub-step of at
most 0.05 / (the fastest mode). Loops: 'position' (u the motor angle
reference, rad) and 'speed' (u the motor speed reference, rad/s; y
integrates). `ForeignAxis` has ``reset()``, ``read()`` and
``step(u) -> y(k+1)`` (the protocol of `sw.closed_loop_response`);
`record` simulates an open-loop record.

For each seed, loop, and play (0, ~10 um, 100-300 um), as a new user
would, this
1. logs 6 s (4000-8000 samples) of an excitation of its own (smoothed
   random steps, slow triangle ramps and a multisine; for the speed loop
   zero-mean speeds that keep the travel within a few mm);
2. identifies ``sw.identify(u, y, na=2, nb=1, nc=2, nd=1, q1=1, q2=0,
   dt=dt)`` and the linear baseline ``sw.identify_linear(u, y, nb=3,
   nf=4, nk=1, integrators=res.linear['integrators'], max_iter=400)``,
   the calls of the servo tutorial and `bench_servo.py`;
3. designs ``sw.servo_controller`` of each with defaults, and
4. runs both against the axis for ``sw.servo_reference(dt, 1e-3)``,
   and the linear design on the same axis without play (the limit),
   each `--runs` times (3) with other noise seeds than the record's.

A loop on this axis is chaotic where the load bounces off the nut and
sticks: on axis 3's speed loop with 133 um the sandwich's RMS error over
the linear design's went from 0.79 to 1.17 across six noise seeds. So
every number of a design is the median over its runs, and a ratio to
the linear design is the median of the runs' ratios, run by run on the
same noise (the range is printed beside it).

It prints a row per design (and per ``--variant name:k=v,...``, another
sandwich design with those `servo_controller` keywords, such as
``fixed:adapt=False``): RMS and maximum error, the RMS error in the
100 ms after reversals of r, u's total variation against the linear
design's, the most reversals of y in the second half of a hold (>= 3:
a limit cycle; after the slash, the same without the random load
force and the encoder noise), the share of inner ticks at the current
limit, the hunting guard's scale at the end (1: never fired), the RMS
error of the linear design without play, res.success with the fits,
the share of inner ticks at the current limit in the identification
record (above 1 %: the excitation is too hard for the motor, or the
drawn drive's own loops hunt, as on axis 7 without play), and
the warnings or exceptions of identify / servo_controller and of the
loops; then the summary of `bench_servo.py`.

Run: python benchmarks/bench_servo_foreign.py [--seeds 3] [--seed0 0]
     [--loops position,speed] [--plays 0,small,large] [--runs 3]
     [--variant fixed:adapt=False]
"""

import argparse
import ast
import math
import os
import sys
import time
import warnings

import numba
import numpy as np

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from _timing import print_table                            # noqa: E402

ORDERS = dict(na=2, nb=1, nc=2, nd=1, q1=1, q2=0)
LINEAR = dict(nb=3, nf=4, nk=1, max_iter=400)
TRAVEL = 1e-3

#: name -> (low, high, how drawn): 'log' log-uniform, 'lin' uniform
RANGES = {
    'dt': (0.5e-3, 2e-3, 'log'),        # outer sample time [s]
    'n_in': (4, 10, 'int'),             # inner ticks a sample
    'Jm': (0.3e-4, 3e-4, 'log'),        # rotor inertia [kg m^2]
    'Bm': (1e-4, 5e-4, 'log'),          # motor viscous [N m s/rad]
    'Kt': (0.3, 1.0, 'log'),            # torque constant [N m/A]
    'Imax': (4.0, 12.0, 'log'),         # current limit [A]
    'tau_e': (0.1e-3, 0.4e-3, 'log'),   # current loop [s]
    'cog': (0.005, 0.03, 'log'),        # cogging torque [N m]
    'bits': (17, 20, 'int'),            # motor encoder bits a rev
    'tau_f': (0.1e-3, 0.5e-3, 'log'),   # speed filter [s]
    'w_s': (150.0, 400.0, 'log'),       # speed-loop crossover [rad/s]
    'Ti_w': (4.0, 10.0, 'log'),         # speed-loop Ti in 1 / w_s
    'Kp': (30.0, 80.0, 'log'),          # position gain [1/s]
    'Ki_div': (4.0, 10.0, 'log'),       # Ki = Kp^2 / this (PI drives)
    'kc': (1000.0, 6000.0, 'log'),      # coupling [N m/rad]
    'zc': (0.02, 0.1, 'log'),           # coupling damping ratio
    'Js': (0.3e-4, 2e-4, 'log'),        # screw inertia [kg m^2]
    'M': (5.0, 50.0, 'log'),            # load [kg]
    'ka': (3e7, 2e8, 'log'),            # axial contact [N/m]
    'e': (0.2, 0.8, 'lin'),             # restitution of the contact
    'Fc': (10.0, 60.0, 'log'),          # Coulomb [N]
    'Fs_Fc': (1.1, 1.8, 'lin'),         # stiction / Coulomb
    'vs': (0.5e-3, 3e-3, 'log'),        # Stribeck speed [m/s]
    'z_ss': (2e-6, 10e-6, 'log'),       # presliding at Fc [m]
    'zeta_f': (0.3, 1.0, 'lin'),        # bristle damping ratio
    'sig2': (50.0, 500.0, 'log'),       # viscous [N s/m]
    'F_bias': (-5.0, 5.0, 'lin'),       # constant load force [N]
    'F_std': (0.5, 3.0, 'log'),         # coloured load force [N]
    'F_hz': (2.0, 10.0, 'log'),         # its corner [Hz]
    'res': (0.5e-6, 2e-6, 'log'),       # linear encoder [m]
    'noise': (0.2, 0.6, 'lin'),         # its noise [counts]
    'small': (6e-6, 14e-6, 'lin'),      # small play [m]
    'large': (100e-6, 300e-6, 'lin'),   # large play [m]
}
LEADS = (5e-3, 10e-3, 16e-3, 20e-3)     # ball-screw leads [m/rev]


def draw_axis(seed):
    """The parameters of axis `seed` (a dict of floats), drawn from
    `RANGES`, the lead from `LEADS`, P or PI position loop at even odds."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0xf0e1]))
    p = {}
    for key, (lo, hi, how) in RANGES.items():
        if how == 'log':
            p[key] = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
        elif how == 'int':
            p[key] = int(rng.integers(lo, hi + 1))
        else:
            p[key] = float(rng.uniform(lo, hi))
    p['lead'] = float(LEADS[rng.integers(len(LEADS))])
    p['Ki'] = p['Kp'] ** 2 / p['Ki_div'] if rng.uniform() < 0.5 else 0.0
    return p


# indices of the kernel's parameter vector
(K_POS, K_NIN, K_NSUB, K_DT, K_JM, K_BM, K_KT, K_IMAX, K_AE, K_COG, K_Q,
 K_ALPHA, K_KV, K_TI, K_KP, K_KI, K_KC, K_CC, K_JS, K_R, K_M, K_KA, K_CA,
 K_FC, K_FS, K_VS, K_S0, K_S1, K_S2, K_G, K_BILAT) = range(31)
# indices of the state vector
(S_THM, S_WM, S_THS, S_WS, S_X, S_V, S_Z, S_CUR, S_THQ, S_WF, S_IS, S_IP,
 S_UPREV, S_SAT, S_TICKS) = range(15)


@numba.njit(cache=False)
def _sample(s, k, u, f_load):
    """One outer sample: n_in controller ticks, each followed by nsub
    mechanical sub-steps with the current command held."""
    nin, nsub = int(k[K_NIN]), int(k[K_NSUB])
    hc = k[K_DT] / nin
    h = hc / nsub
    ae = 1.0 - math.exp(-h / k[K_AE])
    r, g, q = k[K_R], k[K_G], k[K_Q]
    u0 = s[S_UPREV]
    for j in range(nin):
        ref = u0 + (u - u0) * (j + 1) / nin
        thq = q * np.round(s[S_THM] / q)
        s[S_WF] += k[K_ALPHA] * ((thq - s[S_THQ]) / hc - s[S_WF])
        s[S_THQ] = thq
        if k[K_POS] > 0:
            ep = ref - thq
            s[S_IP] += k[K_KI] * hc * ep
            wref = k[K_KP] * ep + s[S_IP]
        else:
            wref = ref
        e = wref - s[S_WF]
        i_new = s[S_IS] + k[K_KV] * hc / k[K_TI] * e
        icmd = (k[K_KV] * e + i_new) / k[K_KT]
        s[S_TICKS] += 1
        if icmd > k[K_IMAX]:
            icmd = k[K_IMAX]
            s[S_SAT] += 1
            if e < 0:
                s[S_IS] = i_new
        elif icmd < -k[K_IMAX]:
            icmd = -k[K_IMAX]
            s[S_SAT] += 1
            if e > 0:
                s[S_IS] = i_new
        else:
            s[S_IS] = i_new
        thm, wm, ths, ws = s[S_THM], s[S_WM], s[S_THS], s[S_WS]
        x, v, z, cur = s[S_X], s[S_V], s[S_Z], s[S_CUR]
        for _ in range(nsub):
            cur += (icmd - cur) * ae
            tc = k[K_KC] * (thm - ths) + k[K_CC] * (wm - ws)
            d = r * ths - x
            dd = r * ws - v
            if k[K_BILAT] > 0:
                fa = k[K_KA] * d + k[K_CA] * dd
            elif d > g:
                fa = max(0.0, k[K_KA] * (d - g) + k[K_CA] * dd)
            elif d < -g:
                fa = min(0.0, k[K_KA] * (d + g) + k[K_CA] * dd)
            else:
                fa = 0.0
            # LuGre: exact bristle update for the sub-step's speed
            gv = k[K_FC] + (k[K_FS] - k[K_FC]) * math.exp(
                -(v / k[K_VS]) ** 2)
            a = k[K_S0] * abs(v) / gv
            z_old = z
            if a > 0:
                z = v / a + (z - v / a) * math.exp(-a * h)
            dz = (z - z_old) / h
            ff = k[K_S0] * z + k[K_S1] * dz + k[K_S2] * v
            tm = (k[K_KT] * cur - k[K_BM] * wm
                  - k[K_COG] * math.sin(6.0 * thm) - tc)
            wm += h * tm / k[K_JM]
            ws += h * (tc - r * fa) / k[K_JS]
            v += h * (fa - ff - f_load) / k[K_M]
            thm += h * wm
            ths += h * ws
            x += h * v
        s[S_THM], s[S_WM], s[S_THS], s[S_WS] = thm, wm, ths, ws
        s[S_X], s[S_V], s[S_Z], s[S_CUR] = x, v, z, cur
    s[S_UPREV] = u


class ForeignAxis:
    """The axis, one outer sample at a time: ``step(u)`` holds u(k) for a
    sample and returns the load encoder's y(k + 1) (``read()``: y(k)).

    Parameters
    ----------
    p : dict
        From `draw_axis`.
    loop : {'position', 'speed'}
    play : float
        Total gap between nut and load [m].
    seed : int
        Seed of the load force and the encoder's noise and offset.
    """

    def __init__(self, p, loop, play, seed):
        self.p, self.loop, self.play, self.seed = p, loop, play, seed
        self.dt = p['dt']
        r = p['lead'] / (2 * np.pi)
        j_tot = p['Jm'] + p['Js'] + p['M'] * r * r
        kv = j_tot * p['w_s']
        j_red = p['Jm'] * p['Js'] / (p['Jm'] + p['Js'])
        cc = 2 * p['zc'] * math.sqrt(p['kc'] * j_red)
        m_screw = p['Js'] / r ** 2
        m_eff = p['M'] * m_screw / (p['M'] + m_screw)
        ln_e = math.log(p['e'])
        zeta = -ln_e / math.sqrt(math.pi ** 2 + ln_e ** 2)
        ca = 2 * zeta * math.sqrt(p['ka'] * m_eff)
        s0 = p['Fc'] / p['z_ss']
        s1 = 2 * p['zeta_f'] * math.sqrt(s0 * p['M'])
        fastest = max(math.sqrt(p['ka'] / m_eff) + ca / m_eff,
                      math.sqrt(p['kc'] / j_red) + cc / j_red,
                      math.sqrt(s0 / p['M']) + s1 / p['M'],
                      1.0 / p['tau_e'])
        hc = self.dt / p['n_in']
        nsub = int(math.ceil(hc * fastest / 0.05))
        self.k = np.array([
            loop == 'position', p['n_in'], nsub, self.dt, p['Jm'], p['Bm'],
            p['Kt'], p['Imax'], p['tau_e'], p['cog'],
            2 * np.pi / 2 ** p['bits'], hc / (p['tau_f'] + hc), kv,
            p['Ti_w'] / p['w_s'], p['Kp'], p['Ki'], p['kc'], cc, p['Js'], r,
            p['M'], p['ka'], ca, p['Fc'], p['Fc'] * p['Fs_Fc'], p['vs'], s0,
            s1, p['sig2'], play / 2, play == 0], dtype=float)
        self.reset()

    def reset(self):
        """Back to rest; the same noise sequence again."""
        self.s = np.zeros(15)
        self.rng = np.random.default_rng([self.seed, 0x5eed])
        self.offset = self.rng.uniform(0, self.p['res'])
        self.f_col = self.p['F_std'] * self.rng.standard_normal()
        self.a_col = math.exp(-2 * np.pi * self.p['F_hz'] * self.dt)
        self.y = 0.0

    def read(self):
        """The last reading of the load encoder [m]."""
        return self.y

    def step(self, u):
        """Apply u(k) over one sample; return y(k + 1)."""
        n = self.rng.standard_normal(2)
        self.f_col = (self.a_col * self.f_col + math.sqrt(
            1 - self.a_col ** 2) * self.p['F_std'] * n[0])
        _sample(self.s, self.k, float(u), self.p['F_bias'] + self.f_col)
        if not math.isfinite(self.s[S_X]):
            raise RuntimeError("the foreign axis diverged")
        res = self.p['res']
        x = self.s[S_X] + self.offset + self.p['noise'] * res * n[1]
        self.y = res * (round(x / res) - round(self.offset / res))
        return self.y

    @property
    def saturation(self):
        """Share of inner ticks at the current limit since reset."""
        return self.s[S_SAT] / max(self.s[S_TICKS], 1)


def record(p, loop, play, u, seed):
    """Open-loop record: y(0) at rest, then y(k + 1) = step(u(k)); and
    the share of inner ticks at the current limit (a drive whose own
    loops hunt in the record shows it there)."""
    axis = ForeignAxis(p, loop, play, seed)
    y = np.empty(len(u))
    y[0] = axis.read()
    for i in range(len(u) - 1):
        y[i + 1] = axis.step(u[i])
    return y, axis.saturation


def excitation(p, loop, seed):
    """Our own identification input, 6 s (4000-8000 samples), in rad or
    rad/s: the load travels a few mm (2 pi / lead rad a metre)."""
    dt, to_rad = p['dt'], 2 * np.pi / p['lead']
    rng = np.random.default_rng([seed, 0xe7c1])
    n = int(np.clip(round(6.0 / dt), 4000, 8000))
    t = np.arange(n) * dt
    ms = np.zeros(n)
    low = 0.3 if loop == 'position' else 1.0
    for f in np.exp(rng.uniform(np.log(low), np.log(15.0), 16)):
        ms += np.cos(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
    ms /= np.sqrt(np.mean(ms ** 2))
    lev, k = np.zeros(n), int(0.1 / dt)
    while k < n:
        m = int(rng.uniform(0.1, 0.5) / dt)
        lev[k:] = rng.uniform(-1, 1)
        k += m
    smooth = np.ones(max(1, int(0.02 / dt)))
    if loop == 'position':
        # steps within +-2 mm, a 1 mm triangle of 3 s, 0.1 mm multisine
        lev = np.convolve(lev, smooth / smooth.size)[:n] * 2e-3
        tri = 1e-3 * (2 / np.pi) * np.arcsin(np.sin(2 * np.pi * t / 3.0))
        x = lev + tri + 1e-4 * ms
        x -= x[0]
        return x * to_rad
    # speeds of up to 15 mm/s whose sign keeps the travel within 3 mm,
    # slow ramps of speed, a 4 mm/s multisine; zero mean
    v, pos = np.zeros(n), 0.0
    for i in range(n):
        v[i] = 15e-3 * lev[i]
        if abs(pos + v[i] * dt) > 3e-3 and np.sign(v[i]) == np.sign(pos):
            lev[i:] = -lev[i:]
            v[i] = -v[i]
        pos += v[i] * dt
    v = np.convolve(v, smooth / smooth.size)[:n]
    v += 3e-3 * np.sin(2 * np.pi * t / 2.0) + 4e-3 * ms
    v[:int(0.1 / dt)] = 0
    v -= np.r_[0, np.full(n - 1, v.mean() * n / (n - 1))]
    return v * to_rad


def caught(func, *args, **kw):
    """(value or None, messages of warnings and of an exception)."""
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter('always')
        try:
            out = func(*args, **kw)
        except Exception as exc:                 # noqa: BLE001
            got.append(exc)
            out = None
    msgs = []
    for w in got:
        text = (f"{type(w).__name__}: {w}" if isinstance(w, Exception)
                else f"{w.category.__name__}: {w.message}")
        if text not in msgs:
            msgs.append(text)
    return out, msgs


def run(ctrl, p, loop, play, r, seed, quiet=False):
    """Closed loop on the axis; `sw.servo_metrics`, the saturation and
    the hunting guard's scale at the end; a run with 3 or more reversals
    in a hold runs again without the random load force and the encoder's
    noise (`quiet`): a limit cycle hunts there too, the noise alone can
    move y by a couple of counts in a hold."""
    if quiet:
        p = dict(p, F_std=0.0, noise=0.0)
    axis = ForeignAxis(p, loop, play, seed)
    with warnings.catch_warnings(record=True) as got, \
            np.errstate(all='ignore'):
        warnings.simplefilter('always')
        try:
            out = sw.closed_loop_response(axis, r, ctrl)
        except Exception as exc:                 # noqa: BLE001
            return dict(error=f"{type(exc).__name__}: {exc}")
    y, u = out.outputs
    m = sw.servo_metrics(r, y, u, p['dt'], deadband=1.5 * p['res'])
    m['saturation'] = axis.saturation
    m['warnings'] = [f"{w.category.__name__}: {w.message}" for w in got]
    m['guard'] = ctrl.feedback_gain
    m['quiet'] = m['hunting']
    if m['hunting'] >= 3 and not quiet:
        m['quiet'] = run(ctrl, p, loop, play, r, seed,
                         True).get('hunting', -1)
    return m


def runs(ctrl, p, loop, play, r, seed, n):
    """`run` with n noise seeds (seed, seed + 1, ...): the medians of
    the RMS, maximum and near-reversal errors and of the activity, the
    most hunting and saturation, the least guard scale, and the runs'
    own metrics under 'runs' (a loop on this axis is chaotic: the load
    bounces off the nut and sticks, and one noise seed against another
    moves a design's RMS error by 20 %; a design is judged on the
    median of its paired ratios, `paired`)."""
    if ctrl is None:
        return dict(error='no design')
    each = [run(ctrl, p, loop, play, r, seed + i) for i in range(n)]
    bad = [m for m in each if 'error' in m]
    if bad:
        return bad[0]
    out = {key: float(np.median([m[key] for m in each]))
           for key in ('rms', 'max', 'near_reversals', 'activity')}
    out.update(hunting=max(m['hunting'] for m in each),
               quiet=max(m['quiet'] for m in each),
               saturation=max(m['saturation'] for m in each),
               guard=min(m['guard'] for m in each), runs=each,
               warnings=sorted({w for m in each for w in m['warnings']}))
    return out


def paired(m, base, key):
    """The median over the runs of m[key] / base[key], run by run (the
    same noise seed), and the least and the most of them."""
    q = [a[key] / b[key] for a, b in zip(m['runs'], base['runs'])]
    return float(np.median(q)), min(q), max(q)


def variants(specs):
    """{name: servo_controller keywords} of --variant name:k=v,k=v."""
    out = {}
    for spec in specs:
        name, _, kws = spec.partition(':')
        out[name] = {k: ast.literal_eval(v) for k, v in (
            item.split('=', 1) for item in kws.split(',') if item)}
    return out


def cases(seeds, seed0, loops, plays):
    for seed in range(seed0, seed0 + seeds):
        p = draw_axis(seed)
        for loop in loops:
            for which in plays:
                play = 0.0 if which == '0' else p[which]
                yield seed, p, loop, play


def fmt(x, scale=1e6, spec='.1f'):
    return '-' if x is None else f"{x * scale:{spec}}"


def describe(p):
    """A short line of the axis's main parameters."""
    return (f"dt {p['dt'] * 1e3:.2f} ms x{p['n_in']}, lead "
            f"{p['lead'] * 1e3:g} mm, M {p['M']:.1f} kg, Fc {p['Fc']:.0f} "
            f"N (stiction x{p['Fs_Fc']:.2f}), Jm {p['Jm'] * 1e4:.2f}e-4, "
            f"Tmax {p['Kt'] * p['Imax']:.1f} N m, w_s {p['w_s']:.0f}, Kp "
            f"{p['Kp']:.0f}{' PI' if p['Ki'] else ' P'}, kc "
            f"{p['kc']:.0f}, ka {p['ka']:.1e}, e {p['e']:.2f}, res "
            f"{p['res'] * 1e6:.2f} um, plays {p['small'] * 1e6:.1f} / "
            f"{p['large'] * 1e6:.0f} um")


def one_case(seed, p, loop, play, n_runs, extra):
    """Identify one record, design and run every design; (check, rows,
    notes)."""
    label = f"s{seed} {loop[:3]}"
    u = excitation(p, loop, seed)
    y, rec_sat = record(p, loop, play, u, seed + 1000)
    t0 = time.perf_counter()
    res, m_id = caught(sw.identify, u, y, **ORDERS, dt=p['dt'])
    t_id = time.perf_counter() - t0
    lin, m_lin = caught(
        sw.identify_linear, u, y, **LINEAR, dt=p['dt'],
        integrators=res.linear['integrators'] if res else 'auto')
    designs = {'linear': (lin, {}), 'sandwich': (res, {})}
    designs.update({name: (res, kw) for name, kw in extra.items()})
    key = f"{label} {play * 1e6:.0f}"
    notes = [f"{key} {name}: {m}" for name, msgs in (
        ('identify', m_id), ('identify_linear', m_lin)) for m in msgs]
    ctrls = {}
    for name, (model, kw) in designs.items():
        ctrls[name], msgs = (caught(sw.servo_controller, model, **kw)
                             if model else (None, []))
        notes += [f"{key} servo_controller({name}): {m}" for m in msgs]
    r = sw.servo_reference(p['dt'], TRAVEL)
    got = {name: runs(ctrls[name], p, loop, play, r, seed + 500, n_runs)
           for name in designs}
    got['no play'] = runs(ctrls['linear'], p, loop, 0.0, r, seed + 500,
                          n_runs)
    base, rows = got['linear'], []
    for name in designs:
        m = got[name]
        notes += [f"{key} {name} loop: {w}" for w in m.get('warnings',
                                                              [])[:2]]
        if 'error' in m:
            notes.append(f"{key} {name} loop: {m['error']}")
            rows.append([label, f"{play * 1e6:.0f}", name] + ['-'] * 8
                        + ['', '', ''])
            continue
        ok = 'error' not in base
        mid, lo, hi = paired(m, base, 'rms') if ok else (None,) * 3
        rows.append([
            label, f"{play * 1e6:.0f}", name, fmt(m['rms']),
            fmt(m['max'], spec='.0f'), fmt(m['near_reversals']),
            f"{paired(m, base, 'activity')[0]:.2f}" if ok else '-',
            f"{m['hunting']}/{m['quiet']}", f"{m['saturation']:.2%}",
            f"{m['guard']:.2g}",
            fmt(got['no play'].get('rms')) if name == 'linear' else '',
            f"{mid:.2f} ({lo:.2f}-{hi:.2f})" if ok else '-',
            (f"{res.success} {res.fit:.1f}/{res.linear['fit']:.1f}"
             if res is not None else 'failed') if name == 'sandwich'
            else (f"{lin.fit:.1f}" if lin is not None and name == 'linear'
                  else ''),
            f"{rec_sat:.2%}" if name == 'linear' else ''])
    check = dict(label=label, loop=loop, play=play, got=got, res=res,
                 seed=seed, t_id=t_id, rec_sat=rec_sat)
    return check, rows, notes


def summary(checks, names):
    """The summary lines of `bench_servo.py`'s kind, over the cases that
    ran every loop; ratios are the medians of the runs' paired ones."""
    good = [c for c in checks
            if all('error' not in m for m in c['got'].values())]
    print(f"\n{len(checks)} cases ({len(good)} with every loop run)")
    if not good:
        return

    def ratio(c, key, name='sandwich'):
        return paired(c['got'][name], c['got']['linear'], key)[0]
    for name in names:
        rms = [ratio(c, 'rms', name) for c in good]
        near = [ratio(c, 'near_reversals', name) for c in good]
        act = [ratio(c, 'activity', name) for c in good]
        worst = good[int(np.argmax(rms))]['label']
        over = [f"{c['label']} {c['play'] * 1e6:.0f} ({a:.2f}, {b:.2f})"
                for c, a, b in zip(good, rms, near) if a > 1.05 or b > 1]
        print(f"{name} RMS / linear: median {np.median(rms):.2f}, worst "
              f"{max(rms):.2f} ({worst}) (target <= 1.05)")
        print(f"{name} near-reversal error / linear: median "
              f"{np.median(near):.2f}, worst {max(near):.2f} (target <= 1)")
        print(f"{name} over a target (RMS, near-reversal ratios): "
              + (", ".join(over) if over else "none"))
        sat = max(c['got'][name]['saturation'] for c in good)
        print(f"{name} input activity / linear: worst {max(act):.2f} "
              f"(target <= 3); saturation worst {sat:.2%} (target <= 1 %)")
        big = [ratio(c, 'rms', name) for c in good
               if c['play'] >= 100e-6 and c['loop'] == 'position']
        if big:
            print(f"{name}, large play (>= 100 um), position loops "
                  f"({len(big)}): RMS ratio median {np.median(big):.2f}, "
                  f"worst {max(big):.2f} (goal <= 0.75)")
    for key, what in (('hunting', ''),
                      ('quiet', ', again without noise and force')):
        counts = [f"{name} {sum(c['got'][name][key] >= 3 for c in good)}"
                  for name in ('linear', *names, 'no play')]
        print(f"hunting (>= 3 reversals in a hold in any run){what}: "
              + ", ".join(counts) + f" of {len(good)}")
    fails = sum(c['res'] is None or not c['res'].success for c in checks)
    bad = [f"{c['label']} {c['play'] * 1e6:.0f}" for c in checks
           if c['rec_sat'] > 0.01]
    print(f"records with > 1 % of the ticks at the current limit (the "
          f"excitation too hard for the motor, or the drive's own "
          f"loops hunting; no design in the loop): {len(bad)}"
          + (f" ({', '.join(bad)})" if bad else ""))
    print(f"identify: success False or failed on {fails} of "
          f"{len(checks)}; time median "
          f"{np.median([c['t_id'] for c in checks]):.1f} s")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--seeds', type=int, default=3)
    ap.add_argument('--seed0', type=int, default=0)
    ap.add_argument('--loops', default='position,speed')
    ap.add_argument('--plays', default='0,small,large')
    ap.add_argument('--runs', type=int, default=3,
                    help="noise seeds each design runs with")
    ap.add_argument('--variant', action='append', default=[],
                    help="another sandwich design, name:k=v,k=v (keywords "
                         "of servo_controller), e.g. fixed:adapt=False")
    args = ap.parse_args()
    extra = variants(args.variant)
    start = time.perf_counter()
    rows, checks, notes, seen = [], [], [], set()
    for seed, p, loop, play in cases(args.seeds, args.seed0,
                                     args.loops.split(','),
                                     args.plays.split(',')):
        if seed not in seen:
            seen.add(seed)
            print(f"axis {seed}: {describe(p)}", flush=True)
        check, more, said = one_case(seed, p, loop, play, args.runs, extra)
        checks.append(check)
        rows += more
        notes += said
        print(f"  {check['label']} {play * 1e6:.0f} done ("
              f"{time.perf_counter() - start:.0f} s; identify "
              f"{check['t_id']:.1f} s)", flush=True)
    print(f"\nServo loops on the foreign axis, servo_controller defaults; "
          f"errors in um, medians of {args.runs} runs (noise seeds); "
          f"RMS/lin: the median of the runs' paired ratios (their "
          f"range); fit: sandwich / baseline (%)\n")
    print_table(['case', 'play', 'design', 'RMS', 'max', 'near rev.',
                 'TV/lin', 'hunt/quiet', 'sat.', 'guard', 'no play',
                 'RMS/lin', 'success fit', 'rec. sat.'], rows)
    summary(checks, ['sandwich', *extra])
    print(f"in {time.perf_counter() - start:.0f} s")
    if notes:
        print("\nWarnings and exceptions:")
        for line in notes:
            print(f"  {line[:300]}")


if __name__ == '__main__':
    main()
