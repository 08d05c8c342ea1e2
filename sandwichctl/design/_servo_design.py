r"""The design steps behind `servo_controller`: preview inverses, the PID
gains, and the checks of the loop they give.

Preview inverse
---------------
A plant :math:`G = b\,N_s(z) N_u(z) / A(z)` with its zeros split into the
stable ones :math:`N_s` and those on or outside the unit circle
:math:`N_u` is inverted as

.. math::

    F(z) = z^{-d} \frac{A(z)}{b\,N_s(z)}\, Q(z),

where Q is the inverse of :math:`N_u`: with ``'preview'``, the
anticausal series :math:`1/(z - z_j) = -\sum_{i \ge 0} z^i / z_j^{i+1}`
truncated where :math:`|z_j|^{-i}` falls below 1e-3 (a preview of that
many samples), scaled for a unit DC gain of :math:`N_u Q`. Zeros with a
real part below -0.5 (which would make the inverse ring at the Nyquist
frequency) are counted in :math:`N_u` too. With ``'zpetc'``, Tomizuka's
zero-phase error tracking controller, :math:`Q = N_u(z^{-1}) / N_u(1)^2`.
Zeros whose series would need more than `max_preview` samples (at or
near the unit circle) keep only their DC gain. d makes F causal, so
:math:`G F \approx z^{-d}`: the reference is needed d samples ahead.

PID gains
---------
:math:`C(z) = k_p + k_i \frac{z}{z-1} + k_d \frac{(1-p)(z-1)}{z-p}`
(derivative filtered by a pole p). For each (kp, kd, p) on a grid, the
largest ki that keeps :math:`|1 + C P| \ge` `modulus_margin` at every
frequency of a log grid reaching below the slowest pole (denser where a
long delay or a sharp resonance turns the phase fast, `frequency_grid`)
is found in closed form (the constraint is quadratic in ki at each
frequency), and the gains with the largest ki are kept, as in the MIGO
designs of Åström and Hägglund: the integral gain is what rejects load
disturbances. The complementary sensitivity is held at :math:`|T| \le 1`
as well (:math:`\mathrm{Re}\,CP \ge -1/2`, also linear in ki): the loop never
amplifies a frequency of the reference. A peak of T is a lightly damped
closed-loop mode, and on the physically simulated drives, where Coulomb
friction damps the holds less than the model says, the largest-ki PID of
the modulus margin alone rang for 3 reversals after each step. The
closed loop's poles are then computed; an unstable or margin-violating
loop is never returned.
"""

import numba
import numpy as np
import control as ct

from ..model._coefficients import tf_to_ss
from .inverse import _fmt_roots
from .loop import phase_margin
from ._servo_kernel import ADAPT, BLEND
from .references import servo_reference
from ._servo_inverse import (AT_ONE, RINGING, SERIES_TOL,  # noqa: F401
                             ZERO_RADIUS, at_one, coincident,
                             preview_inverse, series_length)

#: the most phase (rad) the poles of a plant may turn between
#: neighbouring points of `frequency_grid`: each turns it by up to about
#: a radian per rad/sample (a pole at 0, one sample of delay, by exactly
#: that), and the log grid's steps widen towards pi, so a plant of many
#: poles (a long delay) gets a uniform grid there too. With the log grid
#: alone, 20 samples of delay in both blocks of the paper's plant gave a
#: PID whose modulus margin, 0.6 on the grid, was 0.58 between its points
#: near the Nyquist frequency (0.52 with 40).
GRID_PHASE_STEP = 0.2
#: points around the angle of a pole whose resonance peak (about 1 - |p|
#: wide) is narrower than the log grid's step there, in units of 1 - |p|
PEAK_OFFSETS = np.r_[np.linspace(-3, 3, 61), np.logspace(0.5, 1.5, 6),
                     -np.logspace(0.5, 1.5, 6)]


def frequency_grid(den, n=1500):
    """Log frequency grid (rad/sample) from below the slowest pole to pi,
    with more points where a log grid of `n` is too coarse for the plant
    of denominator `den` (see `GRID_PHASE_STEP`)."""
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    gap = 1.0 - np.abs(poles[np.abs(poles) < 1.0 - 1e-12])
    low = max(min(1e-4, 0.1 * gap.min()) if gap.size else 1e-4, 1e-9)
    w = np.logspace(np.log10(low), np.log10(np.pi), n)
    step = w[1] / w[0] - 1.0            # the log grid's step over w
    parts = [w]
    if poles.size * np.pi * step > GRID_PHASE_STEP:
        # uniform beyond where the log grid's step passes GRID_PHASE_STEP
        h = GRID_PHASE_STEP / poles.size
        parts.append(np.arange(h / step, np.pi, h))
    r, angle = np.abs(poles), np.abs(np.angle(poles))
    for rj, aj in zip(r, angle):
        if 0 < 1 - rj < aj * step:          # a peak narrower than a step
            parts.append(aj + (1 - rj) * PEAK_OFFSETS)
    if len(parts) == 1:
        return w
    extra = np.concatenate(parts[1:])
    return np.unique(np.r_[w, extra[(extra > w[0]) & (extra < w[-1])]])


#: an identified sandwich's feedforward that inverts its own mbar L1 L2 is
#: smoothed when, on `design_reference`, it asks for more than FF_ACTIVITY
#: times the input activity (total variation) of the baseline's inverse:
#: the issue's chatter bound on u against the linear design. The window is
#: a zero-phase Hann window of 2 FF_SMOOTH + 1 taps (FF_SMOOTH samples more
#: of preview); the sandwich's relative degree exceeds the baseline's, and
#: near the Nyquist frequency its inverse amplifies what no record
#: vouches for. Random drive 75 of benchmarks/bench_servo.py (261 um of
#: play; 5.0 times the baseline's activity) tracked at 10.2 um with 3.11
#: times the linear design's input activity, random drive 72 (3.2 times) at
#: 20.4 um with 0.64 times; smoothed, see docs/benchmarks.md
FF_ACTIVITY = 3.0
FF_SMOOTH = 2


def smoothed(fn, fd, preview, m=FF_SMOOTH):
    """(fn, fd, preview) of the feedforward fn/fd, with `preview` samples
    of preview, times a zero-phase Hann window of 2 m + 1 taps: m samples
    more of preview."""
    if m == 0:
        return fn, fd, preview
    w = np.hanning(2 * m + 3)[1:-1]
    return (np.convolve(fn, w / w.sum()), np.r_[fd, np.zeros(2 * m)],
            preview + m)


def pid_tf(kp, ki, kd, pole, dt):
    """C(z) as a transfer function (without the integrator if ki = 0)."""
    if ki == 0:
        num = kp * np.array([1.0, -pole]) + kd * (1 - pole) * np.array(
            [1.0, -1.0])
        return ct.tf(num, [1.0, -pole], dt)
    num = np.polymul([1.0, -1.0], [1.0, -pole]) * kp
    num = num + ki * np.polymul([1.0, 0.0], [1.0, -pole])
    num = num + kd * (1 - pole) * np.polymul([1.0, -1.0], [1.0, -1.0])
    den = np.polymul([1.0, -1.0], [1.0, -pole])
    return ct.tf(num, den, dt)


def _roots(a, b, level):
    """Roots r1 <= r2 in ki of |a + ki b|^2 = level^2 (nan where none)."""
    A = np.abs(b) ** 2
    B = 2 * np.real(a * np.conj(b))
    C = np.abs(a) ** 2 - level ** 2
    disc = B ** 2 - 4 * A * C
    with np.errstate(invalid='ignore', divide='ignore'):
        sq = np.where(disc >= 0, np.sqrt(np.maximum(disc, 0)), np.nan)
        return (-B - sq) / (2 * A), (-B + sq) / (2 * A), C


def _outside(a, b, level):
    """Largest ki >= 0 up to which |a + ki b| >= level at every frequency
    (rows designs, columns frequencies; b a single row), grown from ki = 0
    (inf where it never binds), and whether ki = 0 meets it."""
    lim, ok = np.empty(a.shape[0]), np.empty(a.shape[0], bool)
    _outside_rows(np.ascontiguousarray(a), np.ascontiguousarray(b[0]),
                  float(level), lim, ok)
    return lim, ok


@numba.njit(cache=True)
def _outside_rows(a, b, level, lim, ok):
    """`_outside` in one pass over the rows of a, without the temporaries
    of `_roots` (whose formulas it repeats; the limits agree to ~1e-12,
    the root's cancellation where B^2 >> 4AC): most of the cost of a
    design's PID grid (benchmarks/bench_servo_design.py)."""
    level2 = level ** 2
    A = np.abs(b) ** 2                  # of the columns, the same each row
    bc = np.conj(b)
    for i in range(a.shape[0]):
        best, meets = np.inf, True
        for j in range(b.size):
            B = 2 * (a[i, j] * bc[j]).real
            C = abs(a[i, j]) ** 2 - level2
            meets = meets and C >= 0
            disc = B ** 2 - 4 * A[j] * C
            if disc >= 0:
                r1 = ((-B - np.sqrt(disc)) / (2 * A[j]) if A[j] > 0
                      else np.nan)
                if np.isfinite(r1) and r1 > 0 and r1 < best:
                    best = r1
        lim[i], ok[i] = best, meets


#: the bound on the complementary sensitivity, :math:`|T| \le` T_PEAK.
#: It, not the modulus margin or the crossover limit, bounds the PIDs of
#: the play-free position drives of benchmarks/bench_servo.py. At 1.15
#: (``--peak-t 1.15``, position drives of seeds 0 and 1) those track
#: within 2 times the best swept linear design (1.4 -> 1.3 um), but the
#: 12 um drive of seed 0 hunts with both designs (3 reversals in a hold),
#: and the drives that differ from the one identified hunt 6 times of 20
#: with each design (none at 1)
T_PEAK = 1.0


def _no_peak(a, b):
    r"""Largest ki >= 0 with :math:`|T| = |L / (1 + L)| \le` `T_PEAK` at
    every frequency (L = a - 1 + ki b, rows designs, columns
    frequencies), and whether ki = 0 meets it. At 1 that is
    :math:`\mathrm{Re}\,L \ge -1/2`; above, L outside the circle of
    centre :math:`-M^2/(M^2 - 1)` and radius :math:`M/(M^2 - 1)`."""
    if T_PEAK > 1:
        m2 = T_PEAK ** 2
        return _outside(a - 1 + m2 / (m2 - 1), b, T_PEAK / (m2 - 1))
    c = np.real(a) - 0.5
    rb = np.real(b)
    with np.errstate(invalid='ignore', divide='ignore'):
        lim = np.where(rb < 0, c / -rb, np.inf).min(axis=1)
    return lim, np.all(c >= 0, axis=1)


def _ki_max(a, b, mm, high):
    """Largest ki >= 0 with |1 + L| >= mm and |L| <= |1 + L| (`_no_peak`)
    at every frequency, and |L| <= 1 at the frequencies flagged `high`
    (rows of a = 1 + L(ki=0) are designs, columns frequencies;
    L = a - 1 + ki b); -1 where none."""
    lim, ok0 = _outside(a, b, mm)
    lim_t, ok_t = _no_peak(a, b)
    lim, ok0 = np.minimum(lim, lim_t), ok0 & ok_t
    # crossover below the plant's bandwidth: r1 <= ki <= r2 up there
    h1, h2, hc = _roots(a[:, high] - 1, b[:, high], 1.0)
    inside = np.isfinite(h1)
    lo = np.where(inside, h1, np.inf).max(axis=1, initial=-np.inf)
    lo = np.where(np.all(inside, axis=1), lo, np.inf)
    hi = np.where(inside, h2, -np.inf).min(axis=1, initial=np.inf)
    ki = np.minimum(lim, hi)
    ok = ok0 & (ki >= np.maximum(lo, 0.0)) & (ki > 0)
    return np.where(ok, ki, -1.0)


#: in a plant without an integrator, a stable real pole p whose distance
#: 1 - p is below this share of the bandwidth of the rest of the plant is
#: set aside like an integrator when the plant's bandwidth is read
#: (`bandwidth`): P = 0.1 / (z - 0.9999) has a -3 dB frequency of 1e-4
#: rad/sample, and a crossover limit in multiples of it gave a PID of kp
#: 0.003 that reached 1.6 % of a step in 50 samples (kp 7.3 and the whole
#: step now; a pole within `AT_ONE` of 1 was already an integrator, and one
#: at 1 - 1e-6 got kp 3e-5). At 0.01 it also took the slow poles of
#: drives' models (0.9955 beside a rest at 0.97 on the position drive with
#: 200 um of play; next to an integrator on random drive 4's speed loop,
#: whose linear design then saturated the drive): see docs/benchmarks.md
NEAR_INTEGRATOR = 1e-3


def _minus_3db(w, P):
    """The first frequency of w where |P| is 3 dB below |P(w[0])|."""
    mag = np.abs(P)
    below = np.nonzero(mag <= mag[0] / np.sqrt(2))[0]
    return float(w[below[0]]) if below.size else float(w[-1])


def bandwidth(num, den, w):
    """Frequency (rad/sample) where |P| first falls 3 dB below its low-
    frequency level (an integrator of P set aside, and a slow real pole
    that acts as one over the rest of the plant: `NEAR_INTEGRATOR`)."""
    z = np.exp(1j * w)
    P = np.polyval(num, z) / np.polyval(den, z)
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    integrating = np.any(at_one(poles))
    if integrating:
        P = P * (z - 1) / z
    real = poles.real[(np.abs(poles.imag) < 1e-12) & (poles.real > 0)
                      & (poles.real < 1)]
    if real.size and not integrating:
        slow = real.max()
        rest = _minus_3db(w, P * (z - slow) / z)
        if 1 - slow < NEAR_INTEGRATOR * rest:
            return rest
    return _minus_3db(w, P)


#: the loop gain must be below 1 above this multiple of the plant's bandwidth
#: (its -3 dB frequency, an integrator set aside): for a PID, whose
#: complementary sensitivity is also held at |T| <= 1 (`_no_peak`), and for the
#: PD of an integrating plant (which has no such bound: it cost the speed loops
#: of benchmarks/bench_servo.py their margins, and a larger limit made a 12 um
#: speed drive hunt). The PID's was 2: that, not the modulus margin (0.75 to
#: 0.9 on the model), bounded the position drives of bench_servo.py, which then
#: tracked 2 to 3 times worse than the best of a sweep of their gains. At 3 its
#: position drives track better (all but the linear design of one drive with
#: 200 um, 12.1 -> 13.3 um) and none hunts more; 4 tracked better still on the
#: drives identified, but hunted on drives with 200 um whose load was twice as
#: heavy or whose inner loop 1.25 times stiffer than the record's
#: (bench_servo.py --mismatch)
CROSSOVER_LIMIT = {'pid': 3.0, 'pd': 1.0}

#: a PD found on the coarse grid is refined on a grid this many times
#: finer around it
REFINE = 8

#: the refinement of a PD starts from the best coarse candidate and from
#: the tops of the ridge of the largest kp over kd: for each kd of the
#: coarse grid (and each pole), the largest kp that meets the constraints,
#: found by bisection to RIDGE_STEPS steps per step of the coarse kp grid
#: (0.6 %), from a kp STEP_BELOW times below the best's to two coarse steps
#: above it; at most REFINE_STARTS starts, kd two or more coarse points
#: apart or another pole. The ridge is flat at its top, and a coarse grid
#: ties many kd there: starting from the best coarse candidates instead
#: (random drive 40 of benchmarks/bench_servo.py, speed loop, no play: two
#: baselines of one record got kp 6.0e4 with kd 7.9e4 and kp 5.3e4 with kd
#: 0) left random drive 76's two models of one record at kp 4.7e4 with kd
#: 0 and kp 5.4e4 with kd 6.3e4 (both reach 5.4e4 with kd 6.8e4 and 7.0e4
#: now); on eight integrating plants it ended 0.969 to 1.017 times the
#: largest kp that a scan of 301 kd by 1,400 kp (2.3 % apart) finds, and
#: now 0.994 to 1.021 times
REFINE_STARTS = 6
STEP_BELOW = 1.5
RIDGE_STEPS = 32

#: a raised PID may cross over up to where the residuals vouch for the
#: model (`_servo_data.trusted_band`), at most RAISE_CROSSOVER plant
#: bandwidths (16 stopped random drive 41 of benchmarks/bench_servo.py,
#: vouched to 62, at 1.24 times, 2.3 times the sweep's best; 32 lets it
#: reach 2: 1.1 -> 0.8 um, no hunting mismatched). Raising the design's
#: own limit instead (CROSSOVER_MOST 8 -> 16) let the largest-ki design
#: trade kp for ki (seed 1's play-free position drive 1.12 -> 1.72 um)
RAISE_CROSSOVER = 32.0
#: where the residuals of the data vouch for the model up to
#: `_servo_data.CROSSOVER_MOST` plant bandwidths (the margins are then read
#: on the measured response alone), a PID found under |T| <= `T_PEAK` is
#: raised, its three gains together, by the largest factor up to
#: RAISE_MOST whose loop still meets the modulus margin where the design
#: reads it, crosses over below `RAISE_CROSSOVER`'s limit, and is stable
#: (unconditionally). |T| <= 1 stands in for the model's error, which the
#: data have then measured. On the play-free position drives of
#: benchmarks/bench_servo.py the factor is about 1.25 (1.37 -> 1.13 um,
#: seed 0). Raising ki alone (T_PEAK 1.1 to 1.3) made the 12 um drives
#: hunt: ki / kp, not the loop's speed, is what hunts. The residuals of a
#: drive with 200 um vouch only to 1.5 to 2.6 plant bandwidths, and there
#: the same factor hunted on a heavier load (bench_servo.py --scales)
RAISE_MOST = 2.0
#: factors tried: RAISE_STEPS on a log scale up to RAISE_MOST, to a failure
RAISE_STEPS = 16
#: the raised loop keeps at least this share of the modulus margin on the
#: model alone, and the same crossover limit there too: a record of 3,000
#: samples of the play-free drive measured a response that let the loop
#: cross over at 8.8 bandwidths of its model, at a margin of 0.22 there
MODEL_FLOOR = 0.5

#: most the derivative may add to the controller's gain at the Nyquist
#: frequency, relative to kp (sensor quantisation is amplified by it)
DERIVATIVE_BOOST = 3.0


def low_frequency_gain(num, den):
    """(n, d, integrating): the plant's DC gain n / d, or its integrator's
    gain when it has a pole at z = 1 (d is then the rest of the
    denominator at z = 1)."""
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    one = at_one(poles)
    rest = np.atleast_1d(np.real(np.poly(poles[~one]))) if one.any() else den
    return np.polyval(num, 1.0), np.polyval(rest, 1.0), bool(one.any())


def low_frequency_sign(num, den):
    """Sign of the plant's DC gain (of its integrator's gain if it has a
    pole at z = 1)."""
    n, d, _ = low_frequency_gain(num, den)
    return 1.0 if n / d >= 0 else -1.0


def constraint_columns(w, P, measured, sign=1.0):
    """(w, P) at which a design's constraints are read: the plant's
    response P on the grid w; with `measured` (`_servo_data.data_plant`'s
    (response, alone)) the response the data measured in its place where
    it has data when alone, else appended to it (the constraints then
    hold on both). `sign` multiplies the measured response (a design
    with negated gains reads a negated plant)."""
    if measured is None:
        return w, P
    G = sign * measured[0](w)
    have = np.isfinite(G)
    if measured[1]:
        return w, np.where(have, G, P)
    return np.r_[w, w[have]], np.r_[P, G[have]]


def design_pid(num, den, dt, modulus_margin, limit=None, measured=None,
               info=None):
    """PID gains (kp, ki, kd, pole) for the plant num/den (descending
    powers of z, at most one pole at z = 1): the largest ki under the
    modulus margin and with :math:`|T| \\le 1` (no frequency of the
    reference amplified: a peak of T rang on the drives, where friction
    damps the loop less than the model says), with the crossover below
    `limit` times the plant's bandwidth (by default `CROSSOVER_LIMIT`;
    see `crossover_limit`), the derivative's
    high-frequency boost bounded, and a loop that stays stable when its
    gain is lowered (no conditional stability, which a saturating drive
    turns into a limit cycle). An integrating plant gets
    the PD with the largest kp instead: a type-2 loop around play has no
    rest point and hunts. With `measured` (`_servo_data.data_plant`'s
    (response, alone, trusted)), the margin, |T| and the crossover limit
    are read on the response the data measured wherever it has data, on
    the model elsewhere, and unless alone on the model too; the loop must
    be stable on the model. Where alone, a PID is then raised
    (`_raised`), crossing over below trusted plant bandwidths (at most
    `RAISE_CROSSOVER`, at least `limit`); a trusted of 0 holds it below
    `limit`. A dict `info` gets the factor ('raised') and that crossover
    limit ('limit')."""
    w = frequency_grid(den)
    z = np.exp(1j * w)
    # a plant with a negative low-frequency gain gets negative gains
    sign = low_frequency_sign(num, den)
    num = sign * num
    P = np.polyval(num, z) / np.polyval(den, z)
    wb = bandwidth(num, den, w)
    integrating = np.any(at_one(np.roots(den)))
    if limit is None:
        limit = CROSSOVER_LIMIT['pd' if integrating else 'pid']
    # scale of the gains: 1/|P| at the plant's bandwidth and where its
    # phase first reaches -180 deg, whichever is smaller
    phase = np.unwrap(np.angle(P))
    cross = np.nonzero(phase <= phase[0] - np.pi)[0]
    k0 = min(1.0 / np.abs(P[cross[0] if cross.size else -1]),
             1.0 / np.abs(P[np.searchsorted(w, wb)]))
    # the frequencies (columns) the constraints are read at; a raised PID
    # (`_raised`) may cross over up to where the data vouch for the model
    most = (limit if measured is None else
            max(limit, min(measured[2], RAISE_CROSSOVER)))
    model = (P, w > most * wb)
    wc, P = constraint_columns(w, P, measured, sign)
    zc = np.exp(1j * wc)
    high = wc > limit * wb
    I = zc / (zc - 1)

    def one_plus(pole, KP, KD):
        """1 + C P of the PDs (KP, KD) with the pole, a row each."""
        D = (1 - pole) * (zc - 1) / (zc - pole)
        return 1 + (KP[:, None] + KD[:, None] * D[None, :]) * P[None, :]

    def meets(a):
        """Whether each row of 1 + C P meets the PD's constraints."""
        return (np.all(np.abs(a) >= 1.005 * modulus_margin, axis=1)
                & np.all(np.abs(a[:, high] - 1) <= 1, axis=1))

    def grid(pole, kp, kd, pd):
        """Candidates (kp, ki, kd, pole) on the grid kp x kd: the PDs (ki
        = 0) that meet both constraints if `pd`, else the PIDs with their
        largest ki."""
        KP, KD = (g.ravel() for g in np.meshgrid(kp, kd))
        boost = KD * (1 - pole) * 2 / (1 + pole) <= DERIVATIVE_BOOST * KP
        KP, KD = KP[boost], KD[boost]
        a = one_plus(pole, KP, KD)
        if pd:
            keep = meets(a)
            return [(p_, 0.0, d, pole) for p_, d in zip(KP[keep], KD[keep])]
        ki = _ki_max(a, I[None, :] * P[None, :], 1.005 * modulus_margin,
                     high)
        keep = np.isfinite(ki) & (ki > 0)
        return [(p_, k, d, pole) for p_, k, d in
                zip(KP[keep], ki[keep], KD[keep])]

    def ridge(pole, kds, lo, step, n):
        """For each kd of kds, the largest kp of lo * step**j (j = 0..n)
        that meets the PD's constraints, by bisection from the least
        that the derivative's boost allows (where that one meets them):
        PD candidates (kp, 0, kd, pole)."""
        least = kds * (1 - pole) * 2 / (1 + pole) / DERIVATIVE_BOOST
        low = np.clip(np.ceil(np.log(np.maximum(least, lo) / lo)
                              / np.log(step) - 1e-9), 0, n + 1).astype(int)
        ok = (low <= n) & meets(one_plus(pole, lo * step ** np.minimum(
            low, n), kds))
        up = np.full(kds.size, n + 1)
        while np.any(up - low > 1):
            mid = (low + up) // 2
            good = meets(one_plus(pole, lo * step ** mid, kds))
            low, up = np.where(good, mid, low), np.where(good, up, mid)
        return [(lo * step ** j, 0.0, d, pole)
                for j, d in zip(low[ok], kds[ok])]

    def first(found):
        """The first candidate whose loop is stable, and unconditionally
        so; None if there is none."""
        for kp, ki, kd, pole in found:
            C = pid_tf(kp, ki, kd, pole, dt)
            if loop_radius(num, den, C) < 1 and \
                    _unconditional(num, den, C, w):
                return kp, ki, kd, pole
        return None

    # no integral action on an integrating plant: with play, a type-2 loop
    # has no rest point and limit-cycles (the drive's own speed loop
    # integrates load torques away); it gets the PD with the largest kp,
    # any other plant the PID with the largest ki
    score = 0 if integrating else 1
    kp_grid = k0 * np.logspace(-4, 1, 60)
    # the PD's kd grid is twice as fine (see REFINE_STARTS)
    kd_grid = k0 * np.r_[0.0, np.logspace(-4, 1, 41 if integrating
                                          else 21)]
    found = [c for pole in (0.0, 0.5, 0.8)
             for c in grid(pole, kp_grid, kd_grid, integrating)]
    best = first(sorted(found, key=lambda c: -c[score]))
    if best is not None and integrating:
        # refine the PD around it on a grid REFINE times finer, so that
        # models that fit alike get alike gains, not the next points of a
        # coarse grid (a PID is not: a larger ki than the coarse grid's
        # made the position drives of benchmarks/bench_servo.py ring
        # longer in their holds); and around the tops of the ridge of the
        # largest kp over kd (REFINE_STARTS, RIDGE_STEPS), which the
        # coarse grid sees only to within its step
        index = {d: i for i, d in enumerate(kd_grid)}
        starts, ratio = [best], kp_grid[1] / kp_grid[0]
        if REFINE:
            n = int(np.ceil(RIDGE_STEPS * np.log(ratio ** 2 * STEP_BELOW)
                            / np.log(ratio)))
            found = [c for pole in (0.0, 0.5, 0.8)
                     for c in ridge(pole, kd_grid, best[0] / STEP_BELOW,
                                    ratio ** (1 / RIDGE_STEPS), n)]
        for c in sorted(found, key=lambda c: -c[0]):
            if len(starts) == REFINE_STARTS or c[0] < best[0] / STEP_BELOW:
                break
            # a start's neighbours in kd are refined with it
            if all(s[3] != c[3] or abs(index[s[2]] - index[c[2]]) > 1
                   for s in starts):
                starts.append(c)
        fine = np.linspace(-1.0, 1.0, 2 * REFINE + 1)
        for kp, _, kd, pole in starts:
            kps = kp * (kp_grid[1] / kp_grid[0]) ** fine
            kds = (kd * (kd_grid[2] / kd_grid[1]) ** fine if kd > 0
                   else np.r_[0.0, kd_grid[1] * (kd_grid[2] / kd_grid[1])
                              ** (fine[REFINE:] - 1)])
            refined = first(sorted(grid(pole, kps, kds, True),
                                   key=lambda c: -c[0]))
            if refined is not None and refined[0] > best[0]:
                best = refined
    if best is not None and not integrating and measured is not None \
            and measured[1]:
        raised = _raised(best, num, den, dt, (wc, P, wc > most * wb),
                         model, modulus_margin, w)
        if info is not None and raised[0] != best[0]:
            info.update(raised=raised[0] / best[0], limit=most)
        best = raised
    if best is not None:
        kp, ki, kd, pole = best
        return sign * kp, sign * ki, sign * kd, pole
    raise ValueError(
        f"no PID gains meet modulus_margin={modulus_margin} with a "
        f"stable loop for this plant (poles {_fmt_roots(np.roots(den))},"
        f" zeros {_fmt_roots(np.roots(num)) if num.size > 1 else 'none'}"
        f"); lower modulus_margin or check the model")


def _raised(best, num, den, dt, read, model, modulus_margin, w):
    """The PID `best` (kp, ki, kd, pole) with its gains raised together by
    the largest factor of `RAISE_MOST`'s steps whose loop meets the
    modulus margin and |L| <= 1 where flagged on the columns the design
    reads (`read`: frequencies, P, flags), at least `MODEL_FLOOR` of that
    margin and the same crossover limit on the model (`model`: P and
    flags on the grid w), and is stable, unconditionally, on the plant
    num/den (sign applied)."""
    kp, ki, kd, pole = best
    one, C = np.ones(1), pid_tf(kp, ki, kd, pole, dt)
    loops = [(P * loop_gain(one, one, C, wk), high)
             for wk, P, high in (read, (w, *model))]
    floors = (modulus_margin, MODEL_FLOOR * modulus_margin)
    found = best
    for f in RAISE_MOST ** np.linspace(0.0, 1.0, RAISE_STEPS + 1)[1:]:
        if any(np.any(np.abs(1 + f * L) < 1.005 * m)
               or np.any(np.abs(f * L[high]) > 1)
               for (L, high), m in zip(loops, floors)):
            break
        C = pid_tf(f * kp, f * ki, f * kd, pole, dt)
        if not (loop_radius(num, den, C) < 1
                and _unconditional(num, den, C, w)):
            break
        found = (f * kp, f * ki, f * kd, pole)
    return found


def loop_gain(num, den, C, w):
    """The loop :math:`L = C P` at the frequencies w (rad/sample), for the
    plant num/den and the transfer function C."""
    z = np.exp(1j * w)
    return (np.polyval(num, z) / np.polyval(den, z)
            * np.polyval(C.num[0][0], z) / np.polyval(C.den[0][0], z))


def _unconditional(num, den, C, w):
    """True if the loop C P never crosses -180 deg with |L| > 1."""
    L = loop_gain(num, den, C, w)
    turn = (np.diff(np.sign(L.imag)) != 0) & (L.real[1:] < -1)
    return not np.any(turn)


def loop_radius(num, den, C):
    """Largest closed-loop pole modulus of C in feedback with num/den."""
    cn, cd = C.num[0][0], C.den[0][0]
    char = np.polyadd(np.polymul(den, cd), np.polymul(num, cn))
    char = np.trim_zeros(char, 'f')
    return float(np.max(np.abs(np.roots(char)))) if char.size > 1 else 0.0


def crossover(num, den, C):
    """Frequency (rad/sample) where the loop gain :math:`|C P|` first
    falls below 1 on the log grid (pi if it never does)."""
    w = frequency_grid(den)
    L = loop_gain(num, den, C, w)
    below = np.flatnonzero(np.abs(L) < 1)
    return float(w[below[0]]) if below.size else float(np.pi)


def loop_margins(num, den, C):
    """(modulus margin, gain margin, phase margin [deg], closed-loop pole
    radius) of the loop C P, read on the log frequency grid."""
    w = frequency_grid(den, 6000)
    L = loop_gain(num, den, C, w)
    mm = float(np.min(np.abs(1 + L)))
    pm, _ = phase_margin(L)
    turn = phase_crossings(L)
    gm = float(np.min(1 / np.abs(L[turn]))) if turn.size else np.inf
    return mm, gm, pm, loop_radius(num, den, C)


def phase_crossings(L):
    """Indices where the loop L, on a grid ending at the Nyquist
    frequency, crosses -180 deg: where its imaginary part changes sign on
    the negative real axis, and the grid's last point, where L is real,
    when it is negative there (the sign of a rounding-level imaginary
    part would decide that crossing)."""
    turn = np.flatnonzero((np.diff(np.sign(L.imag)) != 0)
                          & (L.real[1:] < 0)) + 1
    return np.r_[turn, L.size - 1] if L.real[-1] < 0 else turn


#: memory of the online estimate of the band's gain, in samples (its
#: forgetting factor is 1 - 1/ADAPT_MEMORY)
ADAPT_MEMORY = 2000
#: the estimate starts from the designed band with a prior worth this many
#: band jumps of data
ADAPT_PRIOR = 10
#: its covariance grows back (forgetting) to at most this many times the
#: initial one while the reference holds still
ADAPT_WINDUP = 10.0
#: the band's gain stays in [0, ADAPT_MOST] (and the share at most 1)
ADAPT_MOST = 3.0


def band_adaptation(adapt, num, den, C, post, band_x, share, exact,
                    by_default, scal, notes):
    """(A, B, C, D) of the process sensitivity when the band's gain is
    estimated online (`servo_controller`'s ``adapt``), else None; fills
    the estimate's scalars into `scal` and says so in `notes`. `post` is
    the band path's (A, B, C, D)."""
    if adapt is False or (adapt is None and (
            exact or not by_default or band_x <= 0)):
        return None
    if exact or band_x <= 0:
        raise ValueError(
            "adapt=True needs a band to adapt: a design from an "
            "identification result (a known model is inverted exactly) "
            "with band_fraction > 0" + (
                "" if exact or share <= 0 else
                ", and a model whose backlash is open (this one's band "
                "D1 + D2 is 0: the identified backlash is closed, so "
                "there is nothing to compensate; leave adapt out)"))
    got = adaptation(num, den, C, ct.ss(*post, C.dt), band_x)
    if got is None:
        if adapt:
            raise ValueError("adapt=True: the loop's process sensitivity "
                             "is not strictly proper, so the error cannot "
                             "tell the band's gain (check the model's "
                             "delay)")
        return None
    ps, lam, p0 = got
    most = min(ADAPT_MOST, 1.0 / share)
    scal[ADAPT] = [lam, p0, ADAPT_WINDUP * p0, most]
    notes.append(
        f"the band's gain is estimated online from the loop's own error "
        f"(recursive least squares, memory {ADAPT_MEMORY} samples), from 1 "
        f"within [0, {most:.3g}]: the share compensated moves between 0 "
        f"and {most * share:.0%} " + ("by default" if adapt is None
                                      else "as asked")
        + "; reset() restarts it")
    return ps


def adaptation(num, den, C, post, band_x):
    """(A, B, C, D) of the process sensitivity PS = P / (1 + C P), the
    forgetting factor and the initial covariance of the recursive
    estimate of the band's gain g; None when PS is not strictly proper.

    The regressor is PS applied to the band path's output u_post (the
    error's sensitivity to g). The initial covariance is 1 / (ADAPT_PRIOR
    E), with E the regressor's energy over the estimate's memory after
    one band jump of band_x through `post` (the band path, a state-space
    system): the prior is worth ADAPT_PRIOR jumps, whatever the units."""
    PS = ct.feedback(tf_to_ss(ct.tf(num, den, C.dt)), tf_to_ss(C))
    if np.any(np.asarray(PS.D) != 0) or band_x <= 0:
        return None
    steps = np.full(ADAPT_MEMORY, band_x)
    phi = ct.forced_response(PS * post, inputs=steps).outputs
    energy = float(np.sum(phi ** 2))
    if not np.isfinite(energy) or energy <= 0:
        return None
    arrays = tuple(np.asarray(M, float) for M in (PS.A, PS.B, PS.C, PS.D))
    return arrays, 1.0 - 1.0 / ADAPT_MEMORY, 1.0 / (ADAPT_PRIOR * energy)


#: the prior of the blend is worth one `servo_reference` run travelling
#: this many of the model's bands
BLEND_TRAVEL = 5.0


def design_reference(model, bands, dt):
    """`servo_reference` travelling `bands` of the sandwich's band as seen
    in y, sampled at dt (at most 0.01 s; 0.01 s for a model without a
    sample time): the reference the design checks its choices on. The
    band is seen through L2's DC gain or, where L2 integrates, its gain
    at the reference's 1 Hz sine (a travel of 1 in y's units, as before,
    made the checks depend on the units: y in mm instead of m turned a
    valve's compensation off); 1 where neither is finite."""
    co = model.coefficients
    num, den = model.L2.num[0][0], model.L2.den[0][0]
    with np.errstate(divide='ignore', invalid='ignore', over='ignore'):
        at_dc = np.polyval(den, 1.0)
        gain = abs(np.polyval(num, 1.0) / at_dc)
        # a pole at z = 1, to the rounding of den's coefficients
        if not (np.isfinite(gain) and abs(at_dc) > 1e-9 * np.sum(
                np.abs(den))):
            z = np.exp(2j * np.pi * _reference_step(dt))
            gain = abs(np.polyval(num, z) / np.polyval(den, z))
    band = 0.5 * (co['m1'] + co['m2']) * (co['D1'] + co['D2']) * gain
    travel = bands * band if np.isfinite(band) and band > 0 else 1.0
    return reference_at(travel, dt)


def reference_at(travel, dt):
    """`servo_reference` travelling `travel`, sampled at dt (at most
    0.01 s; 0.01 s without a sample time)."""
    return servo_reference(_reference_step(dt), travel)


def _reference_step(dt):
    """The sample time of the design's references: dt, at most 0.01 s,
    and 0.01 s without a sample time."""
    return dt if dt is not True and dt <= 0.01 else 0.01


def record_reference(result, dt):
    """`reference_at` the output spread of the record `result` was
    identified on (the RMS of its residuals over 1 - fit / 100), or None
    where the result does not tell."""
    errors, fit = getattr(result, 'errors', None), getattr(result, 'fit',
                                                           None)
    if errors is None or fit is None or not np.size(errors):
        return None
    with np.errstate(all='ignore'):
        spread = float(np.sqrt(np.mean(np.square(errors)))
                       / (1 - fit / 100))
    return reference_at(spread, dt) if np.isfinite(spread) and spread > 0 \
        else None


def blend(ps, other, chosen, model, dt, scal, notes):
    """Whether the share b of the other linear feedforward is estimated
    online beside the band's gain, and its prior in `scal`: the inverse
    of the energy of its regressor PS (other - chosen) over
    `design_reference` travelling `BLEND_TRAVEL` of the model's bands (a
    prior worth one such run, whatever the units). `ps`, `other` and
    `chosen` are (A, B, C, D) arrays, dt their sample time."""
    diff = ct.ss(*other, dt) - ct.ss(*chosen, dt)
    r = design_reference(model, BLEND_TRAVEL, dt)
    phi = ct.forced_response(ct.ss(*ps, dt) * diff, inputs=r).outputs
    energy = float(np.sum(phi ** 2))
    if not np.isfinite(energy) or energy <= 0:
        return False
    scal[BLEND] = [1.0 / energy, ADAPT_WINDUP / energy]
    notes.append("the linear feedforward's share of the other model (the "
                 "baseline or the sandwich's mbar L1 L2) is estimated "
                 "online too, from 0 within [0, 1]")
    return True


def tf_arrays(sys):
    """(num, den) of a SISO transfer function, leading zeros trimmed."""
    return (np.trim_zeros(sys.num[0][0].astype(float), 'f'),
            sys.den[0][0].astype(float))
