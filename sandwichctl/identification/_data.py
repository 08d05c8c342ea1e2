"""Measured data and their offsets, as every identifier reads them (private).

`prepare` turns the user's data (arrays, records or lists of experiments,
see `sandwichctl.tools.experiments`) into lists of input and output arrays
and applies the offset choice:

``'none'`` (the default)
    The data are used as given and no offset is fitted: the model is
    simulated from rest on the input as measured. (An estimated output
    offset is nearly confounded with the asymmetry of the backlash:
    shifting both thresholds by d shifts the output by about m L2(1) d.
    On data without offsets it therefore costs accuracy on D1 and D2.)
``'mean'``
    The means of u and y are removed from each experiment before the fit
    (quick, and common practice for linear models; for an integrating
    plant it changes the drift, so prefer 'estimate' there).
``'estimate'``
    A constant output offset per experiment is estimated with the model
    (the sandwich has no bias term; an output offset is also the initial
    position of an integrating plant). The input is used as given (an
    input offset shifts x, which the backlash's two thresholds absorb);
    the fits see the output less the first experiment's first sample
    (where a record from rest starts), so that they start near zero
    offset wherever the sensor's zero is, and the offsets come back in
    the user's coordinates.

The result's ``offsets`` says what was done: the method, and per
experiment the removed or estimated input and output offsets.
"""

import math
from fractions import Fraction

import numpy as np

from ..tools.experiments import as_experiments

__all__ = []

OFFSETS = ('none', 'mean', 'estimate')


def prepare(u, y, dt, offsets):
    """(us, ys, dt, info, estimate) for the identifiers.

    `dt` True means "not given": records supply their own.
    """
    if not isinstance(offsets, str) or offsets not in OFFSETS:
        raise ValueError(f"offsets must be one of {list(OFFSETS)}; got "
                         f"{offsets!r}")
    data = as_experiments(u, y, dt=None if dt is True else dt)
    us, ys = data.u, data.y
    check_varying('u', us, "a constant input cannot excite the backlash or "
                  "identify the dynamics. Use a persistently exciting input "
                  "(e.g. noise, or steps plus sines)")
    check_varying('y', ys, "there is nothing to identify (is the sensor "
                  "connected, or the right channel selected?)")
    n_exp = len(us)
    info = {'method': offsets, 'u': [0.0] * n_exp, 'y': [0.0] * n_exp}
    if offsets == 'mean':
        info['u'] = [float(part.mean()) for part in us]
        info['y'] = [float(part.mean()) for part in ys]
        us = [part - c for part, c in zip(us, info['u'])]
    elif offsets == 'estimate':
        # the fits start near zero offset whatever the user's: the output
        # is taken from the first experiment's first sample (the model's
        # rest; where the output of an integrating plant starts), one
        # constant for all, which leaves every fit (its spread about the
        # mean of all the samples) as it was; `with_shift` adds it back
        # to the estimated offsets
        info['y'] = [float(ys[0][0])] * n_exp
    if offsets != 'none':
        ys = [part - c for part, c in zip(ys, info['y'])]
    return us, ys, data.dt, info, offsets == 'estimate'


def with_shift(info, estimated):
    """The result's ``offsets``: `prepare`'s `info`, and with 'estimate'
    the output offsets `estimated` on the shifted data (one per
    experiment, or None where none were) moved back to the user's
    output."""
    if info['method'] != 'estimate' or estimated is None:
        return dict(info)
    return dict(info, y=[float(c + e) for c, e in zip(info['y'],
                                                        estimated)])


#: A record starts at an operating point when both its first sample and
#: the median of this many leading samples are far from zero: an
#: operating point holds for a while, an impulse at the first sample does
#: not, and a step a few samples in starts from rest.
START_SAMPLES = 10


def input_offset(us):
    """The largest starting level / standard deviation of the input
    experiments, the level the smaller of |first sample| and |the median
    of the first `START_SAMPLES`|: how far from u = 0, where the model
    starts at rest, a record starts (see `result.INPUT_OFFSET`). An
    impulse at the start (one sample at 24 standard deviations in 600)
    is an experiment from rest, not an operating point."""
    return max((min(abs(float(part[0])),
                    abs(float(np.median(part[:START_SAMPLES]))))
                / float(np.std(part)) for part in us if np.std(part) > 0),
               default=0.0)


def scale(x):
    """A positive scale of a signal: its standard deviation (RMS if flat)."""
    s = float(np.std(x))
    if not s > 0:
        s = float(np.sqrt(np.mean(np.square(x))))
    return s if s > 0 else 1.0


#: Scaled signals are rounded to multiples of 2**-QUANTUM_BITS (about
#: 1e-9 of their spread); see `scaled`.
QUANTUM_BITS = 30


def scaled(x, s):
    """x / s rounded to multiples of 2**-QUANTUM_BITS.

    Data in other units are the same numbers times a factor, up to the
    rounding of the product; after division by their own scale they
    differ in the last bits. The output-error cost of a backlash is
    discontinuous (beyond the crossing of its slope lines the sign of a
    tiny step of x picks the line), so such differences can steer the
    search to another local optimum. Rounded to a grid far coarser than
    that noise and far finer than any measurement, the scaled data, and
    so the whole search, are the same bits in any units (except for a
    sample that falls within a few ulps of a grid boundary).

    >>> import numpy as np
    >>> u = np.random.default_rng(0).standard_normal(1000)
    >>> a = scaled(u, scale(u))
    >>> b = scaled(u * 1e-4, scale(u * 1e-4))
    >>> bool(np.array_equal(a, b))
    True
    >>> bool(np.max(np.abs(a - u / scale(u))) < 1e-9)
    True
    """
    q = 2.0 ** QUANTUM_BITS
    return np.round(np.asarray(x, dtype=float) / s * q) / q


def check_varying(name, parts, why):
    """Refuse a signal that is constant over all experiments."""
    x = np.concatenate(parts)
    if np.ptp(x) <= 1e-14 * np.max(np.abs(x)):
        what = 'all zero' if not np.any(x) else f"all samples = {x[0]:.6g}"
        raise ValueError(f"{name} is constant ({what}); {why}")


def leading(parts, n):
    """The leading samples of the experiments, about n in all (each
    experiment in proportion to its length, at least 50 samples)."""
    total = sum(part.size for part in parts)
    if total <= n:
        return parts
    return [part[:max(50, int(np.ceil(n * part.size / total)))]
            for part in parts]


#: An input satisfies a recurrence of k taps when the best one leaves
#: less than this share of what the k-th difference leaves (the
#: recurrence of a smooth signal's polynomial trend): a sinusoid computed
#: in floating point leaves about 1e-12 of it in two taps.
EXACT_RECURRENCE = 1e-8
#: Leading samples of each experiment the recurrences are fitted on
#: first; the whole record only when those satisfy one (a record at rest
#: for its first samples, or an input that does not excite).
RECURRENCE_SAMPLES = 20_000
#: An experiment whose values lie on a grid of at least QUANTUM_LEVELS
#: steps (a DAC's or a logger's resolution) satisfies a recurrence of at
#: most QUANTUM_TAPS taps (a constant, a sinusoid, a sinusoid about a
#: constant) also when the best one leaves at most QUANTUM_FACTOR times
#: what the rounding's error alone would leave (uniform within a step,
#: independent sample to sample; `_rounded`): a sinusoid rounded to 8 to
#: 16 bits leaves 0.8 to 1.5 times that in two taps, and 4.6 times it or
#: more in one. Only where the signal's k-th difference is at least
#: QUANTUM_POWER times that error, so that the test can tell: the k-th
#: difference of a slow signal sinks below the rounding, and multisines
#: of eight slow sinusoids rounded to 12 and 16 bits left less than
#: twice the rounding's error in three and four taps
#: (benchmarks/bench_single_sine.py --bits 12); not for more taps, which
#: a slow signal holds ever more closely.
QUANTUM_TAPS = 3
QUANTUM_LEVELS = 64
QUANTUM_FACTOR = 2.0
QUANTUM_POWER = 100.0
#: the least distance between two values of a grid is at most this many
#: of its steps (`quantum`)
QUANTUM_DENOMINATOR = 1000


def excitation_order(us, n):
    """How many coefficients (at most n) the input experiments `us` can
    determine of a linear block: the fewest taps k of a recurrence
    u(j) = c1 u(j-1) + ... + ck u(j-k) that every experiment satisfies
    (to `EXACT_RECURRENCE` of what the k-th difference leaves; for up to
    `QUANTUM_TAPS` taps also to within what rounding to the grid of
    an experiment's values leaves, `quantum`: a sinusoid from a 16-bit
    converter is still one sinusoid), else n.
    A constant satisfies one tap, a sinusoid two, a sum of s sinusoids
    2 s, a sinusoid about a constant three; steps, noise and broadband
    records none of fewer than n (a sinusoid switched on from rest in the
    record counts as a step does: its switch is a transient that tells
    L1, as a step's edge does; so does an impulse or a pulse within the
    first n samples of a record that rests after it, whose response is
    the plant's free one). A block of n coefficients is
    determined by the data only where it is n (the input is
    "persistently exciting of order n")."""
    got = _recurrence(us, n, RECURRENCE_SAMPLES)
    if got < n and any(np.size(part) > RECURRENCE_SAMPLES for part in us):
        got = _recurrence(us, n, None)
    return got


def _recurrence(us, n, samples):
    """`excitation_order` on the leading `samples` of each experiment
    (all of them for None)."""
    cols, target, diffs, noise = [], [], np.zeros(n), 0.0
    for part in us:
        part = np.asarray(part, float)[:samples]
        if part.size <= n:
            continue
        if not np.any(part[n:]) and np.any(part[:n]):
            # an impulse or a pulse within the first n samples, then rest:
            # from rest (the model's own start) its edges are the targets
            part = np.r_[np.zeros(n), part]
        top = float(np.max(np.abs(part)))
        part = part / top if top > 0 else part      # any units
        # what rounding to the experiment's grid leaves in each sample
        noise += (part.size - n) * quantum(part) ** 2 / 12
        lagged = np.lib.stride_tricks.sliding_window_view(part, n + 1)
        cols.append(lagged[:, n - 1::-1])       # u(j-1), ..., u(j-n)
        target.append(lagged[:, n])
        # the k-th difference ending at each target u(j)
        diffs += [np.sum(np.diff(part, k)[n - k:] ** 2)
                  for k in range(1, n + 1)]
    if not cols:
        return n
    A = np.column_stack([np.concatenate(cols), np.concatenate(target)])
    size = float(np.sum(A[:, -1] ** 2))
    if not np.isfinite(size) or size == 0:
        return 0
    r = np.linalg.qr(A, mode='r')
    # the target's residual on the first k lags: the tail of R's last
    # column from row k on
    left = np.cumsum(r[::-1, -1] ** 2)[::-1]
    for k in range(1, n + 1):
        if left[k] <= EXACT_RECURRENCE ** 2 * diffs[k - 1] + 1e-24 * size:
            return k
        if noise > 0 and k <= QUANTUM_TAPS and _rounded(
                r, k, noise, left[k], diffs[k - 1]):
            return k
    return n


def _rounded(r, k, noise, left, rough):
    """Whether the input rows with QR factor r (lags, then the target)
    satisfy the best recurrence of k taps c to within rounding errors of
    energy `noise` a sample: what it leaves, `left`, is at most
    `QUANTUM_FACTOR` times what those errors leave through the filter a
    = (1, -c), while the k-th difference's energy `rough` is at least
    `QUANTUM_POWER` times it (where the signal's own k-th difference is
    no larger than the rounding's, as of a slow multisine, a recurrence
    fitted to within the rounding tells nothing)."""
    c = np.linalg.lstsq(r[:k, :k], r[:k, -1], rcond=None)[0]
    floor = noise * (1.0 + float(c @ c))
    return left <= QUANTUM_FACTOR * floor and rough >= QUANTUM_POWER * floor


def quantum(part):
    """The step of the grid an experiment's values lie on (0 if they do
    not lie on one of at least `QUANTUM_LEVELS` steps): the distances
    between neighbouring values are whole numbers of it (to 1 %). It is
    the least distance over the least common denominator of the others'
    ratios to it (a periodic record may visit only every tenth level),
    then refined by least squares on the distances of a few steps."""
    v = np.unique(part[np.isfinite(part)])
    if v.size < 16:
        return 0.0
    span = float(v[-1] - v[0])
    # values within rounding of the float of each other are one value
    gaps = np.diff(v)
    gaps = gaps[gaps > 1e-9 * span]
    if gaps.size < 15:
        return 0.0
    least, den = float(np.min(gaps)), 1
    for ratio in np.unique(np.round(gaps / least, 9))[:30]:
        den = math.lcm(den, Fraction(float(ratio)).limit_denominator(
            QUANTUM_DENOMINATOR).denominator)
        if den > QUANTUM_DENOMINATOR:
            return 0.0
    q = least / den
    near = np.round(gaps / q)
    use = near <= 64
    if np.any(use):
        q = float(gaps[use] @ near[use] / (near[use] @ near[use]))
    ratio = gaps / q
    if span < QUANTUM_LEVELS * q or np.any(
            np.abs(ratio - np.round(ratio)) > 0.01):
        return 0.0
    return q


def input_order_text(got, need, what):
    """The failure of an input whose `excitation_order` `got` is below
    the `need` coefficients of the block `what`."""
    lines = ("nothing" if got == 0 else "a constant" if got == 1 else
             f"{got // 2} sinusoid" + ("s" if got // 2 > 1 else "")
             + (" about a constant" if got % 2 else ""))
    return (f"the input satisfies a recurrence of {got} taps (as {lines} "
            f"does), so it determines at most {got} of the {need} "
            f"coefficients of {what}: the data do not determine the model, "
            f"and it need not hold for another input (excite more "
            f"frequencies: steps, a multisine or random steps; or lower "
            f"the orders)")
