r"""Seeded random sandwich identification cases (test plants and data).

`random_case` draws one identification problem: a random, stable
sandwich plant L1 -> backlash -> L2 (the truth), an excitation, and the
plant's output with white measurement noise, all reproducible from one
integer seed. `random_family` draws a balanced family of such cases (the
robustness benchmark ``benchmarks/bench_robustness.py`` runs the
identifier on it) and `excitation` the four input signals.

How a case is drawn
-------------------
Everything below is drawn from ``np.random.SeedSequence(seed)``, split
into independent streams for the structure, the plant, the input and the
noise, so that fixing `snr`, `n` or `input_kind` (or the case type)
leaves the rest of the case unchanged: ``random_case(s, snr=5)`` is
``random_case(s)`` with other noise, and ``random_case(s,
negative_gain=True)`` is ``random_case(s)`` with the sign of y flipped.

- Orders: na, nc in 1..3 poles and nb, nd in 1..3 zeros (b has nb + 1
  coefficients), delays q1, q2 in 0..2 with q1 + q2 >= 1.
- Poles: real or complex pairs with modulus in [0.2, 0.95] (a quarter of
  the real ones negative); `integrating` adds a pole exactly at z = 1 to
  L1, counted in na (``integrating='L2'``: to L2, counted in nc; L1's
  poles are then those of the case without an integrator).
- Zeros: real or complex pairs, minimum phase (modulus in [0.1, 0.85]) or,
  with probability 0.3, non-minimum phase (modulus in [1.2, 2.5]); every
  zero is at least 0.2 away from every pole of its block (no
  near-cancellation, so the orders are identifiable).
- Gains: b0 > 0 scales L1 so that std(x) = 1 for the unit-RMS input, and
  d0 > 0 scales L2 so that std(y) = 1 (before units). `negative_gain`
  flips the sign of L2's numerator.
- Backlash: m1, m2 in [0.5, 2], one of them 1.05 to 2 times the other
  (log-ratio uniform in [0.05, log 2], either may be the larger);
  D1, D2 uniform in [0.05, 0.4] * std(x) with ``|D1 - D2| >= 0.02 *
  std(x)``, x = L1 u for the case's own input. The slope lines may cross
  inside the range of x (see `Backlash.crossing`); eq. (2.2) is followed
  there, as everywhere.
- Units: ``scale_u`` and ``scale_y`` are log-uniform in [1e-3, 1e3]; u is
  the unit-RMS excitation times ``scale_u``, and the plant is rebuilt
  (b / scale_u, d * scale_y) so that it maps that u to y in y's units:
  std(u) = scale_u and std(y_clean) = scale_y (times -1 for a negative
  gain, which does not change the std).
- Noise: white Gaussian, variance var(y_clean) / snr (snr is a variance
  ratio; ``inf`` means no noise). Default snr in {inf, 100, 20, 5}.
- Length: default n log-uniform in 2,000..10,000, rounded to 100.
- Input: default kind among `KINDS`. For an integrating plant the
  excitation is passed through a DC blocker (1 - z^-1) / (1 - r z^-1),
  r in [0.98, 0.995], and renormalised, so that its running sum, and
  hence x, stays bounded.
"""

from dataclasses import dataclass, field, fields

import numpy as np
from scipy.signal import lfilter

from ..model.sandwich import SandwichSystem
from .._checks import MOST_SAMPLES, check_int, check_positive, check_rng

__all__ = ['excitation', 'random_case', 'random_family', 'family_specs',
           'SyntheticCase', 'KINDS', 'SNRS', 'N_RANGE', 'N_BUCKETS']

#: Kinds of excitation of `excitation`.
KINDS = ('white', 'lowpass', 'multisine', 'square+sine')

#: Signal-to-noise ratios (variance ratios) drawn by `random_case`.
SNRS = (np.inf, 100.0, 20.0, 5.0)

#: Range of record lengths drawn by `random_case`.
N_RANGE = (2000, 10000)
#: The most cases of one family (`family_specs`): a list of specs, not a
#: stream.
MOST_CASES = 1_000_000

#: Length buckets over which `random_family` spreads its cases.
N_BUCKETS = ((2000, 3000), (3000, 5000), (5000, 7500), (7500, 10000))

_POLE_RANGE = (0.2, 0.95)
_ZERO_MP = (0.1, 0.85)
_ZERO_NMP = (1.2, 2.5)
_ZERO_POLE_GAP = 0.2
_M_RANGE = (0.5, 2.0)
_M_LOG_RATIO = (0.05, np.log(2.0))
_D_RANGE = (0.05, 0.4)
_SCALE_RANGE = (1e-3, 1e3)


# ----------------------------------------------------------------------
# Excitation
# ----------------------------------------------------------------------
def _unit(s):
    """Zero mean, unit RMS."""
    s = s - s.mean()
    return s / np.sqrt(np.mean(s ** 2))


def _lowpass(n, rng):
    burn = 300
    e = rng.standard_normal(n + burn)
    if rng.random() < 0.5:                       # first order
        p = rng.uniform(0.5, 0.95)
        b, a = [1 - p], [1, -p]
    else:                                        # second order
        if rng.random() < 0.5:                   # complex pair
            r, w = rng.uniform(0.5, 0.95), rng.uniform(0.05, 0.8)
            poles = [r * np.exp(1j * w), r * np.exp(-1j * w)]
        else:
            poles = rng.uniform(0.3, 0.9, 2)
        a = np.real(np.poly(poles))
        b = [a.sum()]                            # unit DC gain
    return lfilter(b, a, e)[burn:]


def _multisine(n, rng):
    f_lo = rng.uniform(0.001, 0.02)
    f_hi = rng.uniform(0.1, 0.45)
    k = int(rng.integers(10, 61))
    f = np.sort(rng.uniform(f_lo, f_hi, k))
    phase = rng.uniform(0, 2 * np.pi, k)
    t = np.arange(n)
    return np.cos(2 * np.pi * np.outer(t, f) + phase).sum(axis=1)


def _square_sine(n, rng):
    mean_hold = rng.uniform(5, 60)
    lo, hi = max(1, int(0.5 * mean_hold)), int(1.5 * mean_hold) + 1
    holds = rng.integers(lo, hi, n // lo + 2)
    edges = np.cumsum(holds)
    segment = np.searchsorted(edges, np.arange(n), side='right')
    if rng.random() < 0.5:                       # square wave
        levels = np.where(np.arange(segment[-1] + 1) % 2, 1.0, -1.0)
        levels *= rng.choice([-1.0, 1.0])
    else:                                        # staircase
        levels = rng.uniform(-1, 1, segment[-1] + 1)
    square = levels[segment]
    # a record shorter than a hold has one level: the sine alone moves it
    amp = rng.uniform(0.2, 1.0) * (np.std(square) or 1.0)
    f = rng.uniform(0.002, 0.05)
    sine = amp * np.sin(2 * np.pi * f * np.arange(n)
                        + rng.uniform(0, 2 * np.pi))
    return square + sine


_GENERATORS = {'white': lambda n, rng: rng.standard_normal(n),
               'lowpass': _lowpass, 'multisine': _multisine,
               'square+sine': _square_sine}


def excitation(kind, n, rng=None):
    """A random excitation signal, zero-mean with unit RMS.

    Parameters
    ----------
    kind : {'white', 'lowpass', 'multisine', 'square+sine'}
        ``'white'``: white Gaussian noise. ``'lowpass'``: white noise
        through a random first- or second-order low-pass filter (pole
        0.5..0.95, or a complex pair of modulus 0.5..0.95). ``'multisine'``:
        10 to 60 cosines with random phases at random frequencies in a
        random band [f_lo, f_hi], f_lo in 0.001..0.02 and f_hi in
        0.1..0.45 cycles per sample. ``'square+sine'``: a square wave (or,
        half of the time, a staircase of uniform random levels) switching
        after random holds of 5 to 90 samples, plus a sine of random
        frequency (0.002..0.05 cycles per sample) and amplitude.
    n : int
        Number of samples (>= 2).
    rng : numpy.random.Generator or int or None, optional
        Random generator, or a seed for `numpy.random.default_rng`.

    Returns
    -------
    ndarray, shape (n,)
        The signal, with mean 0 and RMS 1 (to rounding).

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.data import excitation
    >>> u = excitation('multisine', 1000, np.random.default_rng(0))
    >>> rms = np.sqrt(np.mean(u ** 2))
    >>> bool(abs(u.mean()) < 1e-12), bool(abs(rms - 1) < 1e-12)
    (True, True)
    """
    if not (isinstance(kind, str) and kind in _GENERATORS):
        raise ValueError(f"kind must be one of {list(KINDS)}; got {kind!r}")
    n = check_int('n', n, minimum=2, maximum=MOST_SAMPLES)
    rng = check_rng('rng', rng)
    for _ in range(100):
        s = _GENERATORS[kind](n, rng)
        if np.ptp(s) > 0:
            return _unit(s)
    raise RuntimeError(f"could not draw a non-constant {kind!r} signal of "
                       f"{n} samples")               # pragma: no cover


# ----------------------------------------------------------------------
# Random plants
# ----------------------------------------------------------------------
def _random_poles(count, rng):
    """`count` stable poles (real or complex pairs), |p| in _POLE_RANGE."""
    poles = []
    while len(poles) < count:
        r = rng.uniform(*_POLE_RANGE)
        if count - len(poles) >= 2 and rng.random() < 0.5:
            w = rng.uniform(0.15, np.pi - 0.15)
            poles += [r * np.exp(1j * w), r * np.exp(-1j * w)]
        else:
            poles.append(-r if rng.random() < 0.25 else r)
    return np.array(poles, dtype=complex)


def _random_zeros(count, poles, rng):
    """`count` zeros, at least _ZERO_POLE_GAP from every pole."""
    zeros = []
    while len(zeros) < count:
        for _ in range(10000):
            band = _ZERO_NMP if rng.random() < 0.3 else _ZERO_MP
            r = rng.uniform(*band)
            if count - len(zeros) >= 2 and rng.random() < 0.5:
                w = rng.uniform(0.15, np.pi - 0.15)
                new = [r * np.exp(1j * w), r * np.exp(-1j * w)]
            else:
                new = [r if rng.random() < 0.5 else -r]
            if all(np.min(np.abs(z - poles), initial=np.inf)
                   >= _ZERO_POLE_GAP for z in new):
                zeros += new
                break
        else:                                    # pragma: no cover
            raise RuntimeError("could not place the zeros away from the "
                               "poles")
    return np.array(zeros, dtype=complex)


def _poly(roots):
    """Monic polynomial coefficients (descending) with these roots."""
    p = np.array([1.0])
    for r in roots:
        if abs(r.imag) > 0 and r.imag < 0:
            continue                             # its conjugate did it
        if abs(r.imag) > 0:
            p = np.convolve(p, [1.0, -2 * r.real, abs(r) ** 2])
        else:
            p = np.convolve(p, [1.0, -r.real])
    return p


def _block_output(a, b, q, inp):
    """Output of x(k) = -sum a_i x(k-i) + sum b_j inp(k-q-j), zero state."""
    return lfilter(np.concatenate([np.zeros(q), b]),
                   np.concatenate([[1.0], a]), inp)


def same_case(a, b):
    """Whether two data-set records of one dataclass hold the same
    values: arrays element by element (NaN equal to NaN), dicts entry by
    entry, sandwiches by their coefficients and sample time."""
    if type(a) is not type(b):
        return NotImplemented
    return all(_same(getattr(a, f.name), getattr(b, f.name))
               for f in fields(a))


def _same(x, y):
    if isinstance(x, SandwichSystem) or isinstance(y, SandwichSystem):
        return (isinstance(x, SandwichSystem)
                and isinstance(y, SandwichSystem) and x.dt == y.dt
                and _same(x.coefficients, y.coefficients))
    if isinstance(x, dict) or isinstance(y, dict):
        return (isinstance(x, dict) and isinstance(y, dict)
                and x.keys() == y.keys()
                and all(_same(x[k], y[k]) for k in x))
    if isinstance(x, (list, tuple)) or isinstance(y, (list, tuple)):
        return (isinstance(x, (list, tuple)) and isinstance(y, (list, tuple))
                and len(x) == len(y) and all(map(_same, x, y)))
    if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
        x, y = np.asarray(x), np.asarray(y)
        return x.shape == y.shape and bool(np.array_equal(
            x, y, equal_nan=x.dtype.kind in 'fc' and y.dtype.kind in 'fc'))
    return bool(x == y) or (x != x and y != y)        # NaN == NaN


@dataclass(repr=False, eq=False)
class SyntheticCase:
    """One random identification case (returned by `random_case`).

    Attributes
    ----------
    plant : SandwichSystem
        The truth, in the units of u and y (dt = 1).
    u : ndarray
        The input, ``scale_u`` times a zero-mean unit-RMS excitation.
    y : ndarray
        The measured output, ``y_clean`` plus white noise.
    y_clean : ndarray
        The noise-free output ``plant.simulate(u).outputs``.
    orders : dict
        na, nb, nc, nd, q1, q2 (the keyword arguments of `identify`).
    snr : float
        Variance ratio var(y_clean) / var(noise); ``inf`` if noise-free.
    input_kind : str
        One of `KINDS`.
    n : int
        Number of samples.
    integrating : bool or str
        True: L1 has a pole exactly at z = 1 (counted in na); 'L2': L2
        has it (counted in nc); False: none.
    negative_gain : bool
        L2's numerator has the opposite sign (b0 * d0 < 0), and y that of
        the same case without this flag.
    seed : int
        The seed of `random_case`.
    scale_u, scale_y : float
        Units of u and y (see the module notes).
    """

    plant: SandwichSystem
    u: np.ndarray
    y: np.ndarray
    y_clean: np.ndarray
    orders: dict
    snr: float
    input_kind: str
    n: int
    integrating: object
    negative_gain: bool
    seed: int
    scale_u: float
    scale_y: float
    details: dict = field(default_factory=dict)

    @property
    def case_type(self):
        """'integrating', 'negative gain' or 'ordinary'."""
        if self.integrating:
            return 'integrating'
        return 'negative gain' if self.negative_gain else 'ordinary'

    @property
    def spec(self):
        """Keyword arguments of `random_case` that rebuild this case."""
        return dict(seed=self.seed, snr=self.snr, n=self.n,
                    input_kind=self.input_kind, integrating=self.integrating,
                    negative_gain=self.negative_gain)

    def __eq__(self, other):
        return same_case(self, other)

    __hash__ = None

    def __repr__(self):
        o = self.orders
        return (f"SyntheticCase(seed={self.seed}, {self.case_type}, "
                f"n={self.n}, snr={self.snr:g}, input_kind="
                f"{self.input_kind!r}, orders=({o['na']}, {o['nb']}, "
                f"{o['nc']}, {o['nd']}, {o['q1']}, {o['q2']}), "
                f"scale_u={self.scale_u:.3g}, scale_y={self.scale_y:.3g})")


def _check_snr(snr):
    if snr is None:
        return None
    if isinstance(snr, (int, float, np.integer, np.floating)) \
            and not isinstance(snr, bool) and snr == np.inf:
        return np.inf
    return check_positive('snr', snr)


def _check_integrating(value):
    """``integrating`` checked: False, True ('L1' is True) or 'L2'."""
    if isinstance(value, str) and value in ('L1', 'L2'):
        return True if value == 'L1' else value
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"integrating must be True, False, 'L1' or 'L2'; "
                        f"got {type(value).__name__} {value!r}")
    return bool(value)


def _check_bool(name, value):
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False; got "
                        f"{type(value).__name__} {value!r}")
    return bool(value)


def _check_n_range(n_range):
    if n_range is None:
        return N_RANGE
    try:
        lo, hi = n_range
    except (TypeError, ValueError):
        raise TypeError(f"n_range must be a pair (n_min, n_max); got "
                        f"{n_range!r}") from None
    lo = check_int('n_range[0]', lo, minimum=100, maximum=MOST_SAMPLES)
    hi = check_int('n_range[1]', hi, minimum=lo, maximum=MOST_SAMPLES)
    return lo, hi


def random_case(seed, *, snr=None, n=None, input_kind=None,
                integrating=False, negative_gain=False):
    """A random sandwich identification case, reproducible from its seed.

    The module notes give the distributions of orders, poles, zeros,
    backlash, units, noise, length and input.

    Parameters
    ----------
    seed : int
        Seed (>= 0); the same seed and arguments give the same case.
    snr : float, optional
        Variance ratio var(y_clean) / var(noise), > 0, or ``np.inf`` for
        noise-free data. Default: drawn from `SNRS`.
    n : int, optional
        Number of samples (>= 100). Default: drawn log-uniformly in
        `N_RANGE`, rounded to 100.
    input_kind : str, optional
        One of `KINDS`. Default: drawn at random.
    integrating : {False, True, 'L1', 'L2'}, optional
        True (or 'L1'): put one pole exactly at z = 1 in L1 (counted in
        na), as a drive's nut integrates the speed before the play; 'L2':
        in L2 (counted in nc), as a cylinder integrates the flow of a
        valve after its play. Either way the input is DC-blocked so that
        x stays bounded (with an integrator in L2 the asymmetry of the
        backlash still makes y drift). The case's ``integrating`` is True
        for 'L1'.
    negative_gain : bool, optional
        Flip the sign of L2's numerator: b0 * d0 < 0, so the plant has a
        negative gain and the paper's normalisation b0 = d0 = 1 does not
        exist for it.

    Returns
    -------
    SyntheticCase

    Examples
    --------
    >>> import numpy as np
    >>> from sandwichctl.data import random_case
    >>> case = random_case(3, snr=20, n=2000)
    >>> case.orders == case.plant.orders, case.u.size, case.snr
    (True, 2000, 20.0)
    >>> bool(np.allclose(case.plant.simulate(case.u).outputs, case.y_clean))
    True
    """
    seed = check_int('seed', seed)
    snr = _check_snr(snr)
    if n is not None:
        n = check_int('n', n, minimum=100, maximum=MOST_SAMPLES)
    if input_kind is not None and not (isinstance(input_kind, str)
                                       and input_kind in KINDS):
        raise ValueError(f"input_kind must be one of {list(KINDS)} or "
                         f"None; got {input_kind!r}")
    integrating = _check_integrating(integrating)
    negative_gain = _check_bool('negative_gain', negative_gain)

    r_meta, r_plant, r_input, r_noise = (
        np.random.default_rng(s)
        for s in np.random.SeedSequence(seed).spawn(4))

    # meta: the defaults (always drawn, so fixing one keeps the others)
    snr_d = SNRS[int(r_meta.integers(len(SNRS)))]
    lo, hi = N_RANGE
    n_d = int(round(np.exp(r_meta.uniform(np.log(lo), np.log(hi))), -2))
    kind_d = KINDS[int(r_meta.integers(len(KINDS)))]
    scale_u = float(np.exp(r_meta.uniform(*np.log(_SCALE_RANGE))))
    scale_y = float(np.exp(r_meta.uniform(*np.log(_SCALE_RANGE))))
    snr = snr_d if snr is None else snr
    n = n_d if n is None else n
    input_kind = kind_d if input_kind is None else input_kind

    # structure and plant
    na, nc = (int(v) for v in r_plant.integers(1, 4, 2))
    nb, nd = (int(v) for v in r_plant.integers(1, 4, 2))
    while True:
        q1, q2 = (int(v) for v in r_plant.integers(0, 3, 2))
        if q1 + q2 >= 1:
            break
    in_l2 = integrating == 'L2'
    poles1 = _random_poles(na - 1 if integrating is True else na, r_plant)
    if integrating is True:
        poles1 = np.concatenate([[1.0 + 0j], poles1])
    poles2 = _random_poles(nc - 1 if in_l2 else nc, r_plant)
    if in_l2:
        poles2 = np.concatenate([[1.0 + 0j], poles2])
    zeros1 = _random_zeros(nb, poles1, r_plant)
    zeros2 = _random_zeros(nd, poles2, r_plant)
    ratio = r_plant.uniform(*_M_LOG_RATIO)
    m1 = float(np.exp(r_plant.uniform(np.log(_M_RANGE[0]),
                                      np.log(_M_RANGE[1]) - ratio)))
    m1, m2 = (m1, m1 * np.exp(ratio)) if r_plant.random() < 0.5 else \
        (m1 * np.exp(ratio), m1)
    while True:
        f1, f2 = r_plant.uniform(*_D_RANGE, 2)
        if abs(f1 - f2) >= 0.02:
            break
    a = _poly(poles1)[1:]
    c = _poly(poles2)[1:]
    b = _poly(zeros1)
    d = _poly(zeros2)

    # input (dimensionless, unit RMS)
    e = excitation(input_kind, n, r_input)
    if integrating:
        r = r_input.uniform(0.98, 0.995)
        e = _unit(lfilter([1.0, -1.0], [1.0, -r], e))

    # gains: std(x) = 1, then D relative to std(x), then std(y) = 1
    x = _block_output(a, b, q1, e)
    b = b / np.std(x)
    x = _block_output(a, b, q1, e)
    sx = float(np.std(x))
    D1, D2 = f1 * sx, f2 * sx
    unit = SandwichSystem.from_coefficients(a, b, c, d, m1, m2, D1, D2,
                                            q1, q2, dt=1)
    d = d / np.std(unit.simulate(e).outputs)
    if negative_gain:
        d = -d

    # units
    u = scale_u * e
    plant = SandwichSystem.from_coefficients(
        a, b / scale_u, c, d * scale_y, m1, m2, D1, D2, q1, q2, dt=1,
        name=f"case{seed}")
    # a plain array: python-control's NamedSignal does not unpickle
    y_clean = np.asarray(plant.simulate(u).outputs)
    noise = r_noise.standard_normal(n)
    if np.isfinite(snr):
        y = y_clean + noise * np.sqrt(np.var(y_clean) / snr)
    else:
        y = y_clean.copy()
    orders = dict(na=na, nb=nb, nc=nc, nd=nd, q1=q1, q2=q2)
    details = dict(poles1=poles1, zeros1=zeros1, poles2=poles2,
                   zeros2=zeros2, std_x=sx, D_over_std_x=(f1, f2))
    return SyntheticCase(plant=plant, u=u, y=y, y_clean=y_clean,
                         orders=orders, snr=float(snr),
                         input_kind=input_kind, n=n, integrating=integrating,
                         negative_gain=negative_gain, seed=seed,
                         scale_u=scale_u, scale_y=scale_y, details=details)


# ----------------------------------------------------------------------
# Families
# ----------------------------------------------------------------------
def family_specs(n_cases, seed=0, n_range=None):
    """The `random_case` arguments of the cases of `random_family`.

    Parameters
    ----------
    n_cases : int
        Number of cases (>= 1).
    seed : int, optional
        Seed of the family (default 0).
    n_range : (int, int), optional
        Range of record lengths (default `N_RANGE`). The lengths are
        spread evenly over the buckets of `N_BUCKETS` that overlap it (or
        drawn in the whole range if none does).

    Returns
    -------
    list of dict
        ``random_case(**spec)`` builds case i. Each dict has the keys
        seed, snr, n, input_kind, integrating, negative_gain.

    Examples
    --------
    >>> from sandwichctl.data import family_specs
    >>> specs = family_specs(20, seed=1)
    >>> sum(s['integrating'] for s in specs), sum(s['negative_gain']
    ...                                           for s in specs)
    (2, 2)
    >>> sorted({s['input_kind'] for s in specs})
    ['lowpass', 'multisine', 'square+sine', 'white']
    """
    n_cases = check_int('n_cases', n_cases, 1, MOST_CASES)
    seed = check_int('seed', seed)
    lo, hi = _check_n_range(n_range)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x5a9d]))
    buckets = [(max(a, lo), min(b, hi)) for a, b in N_BUCKETS
               if max(a, lo) < min(b, hi)] or [(lo, hi)]

    def spread(levels):
        """`levels` repeated evenly over the cases, in random order."""
        start = int(rng.integers(len(levels)))
        out = [levels[(start + i) % len(levels)] for i in range(n_cases)]
        return [out[i] for i in rng.permutation(n_cases)]

    n_special = int(round(0.1 * n_cases))
    types = ['integrating'] * n_special + ['negative'] * n_special
    types += ['ordinary'] * (n_cases - len(types))
    types = [types[i] for i in rng.permutation(n_cases)]
    snrs = spread(list(SNRS))
    kinds = spread(list(KINDS))
    bucket = spread(list(range(len(buckets))))
    seeds = np.random.SeedSequence(seed).generate_state(n_cases)
    specs = []
    for i in range(n_cases):
        b_lo, b_hi = buckets[bucket[i]]
        n = int(np.exp(rng.uniform(np.log(b_lo), np.log(b_hi))))
        specs.append(dict(seed=int(seeds[i]) % 2 ** 31, snr=float(snrs[i]),
                          n=max(lo, min(hi, n)), input_kind=kinds[i],
                          integrating=types[i] == 'integrating',
                          negative_gain=types[i] == 'negative'))
    return specs


def random_family(n_cases, seed=0, n_range=None):
    """A balanced family of random identification cases (a generator).

    About 10% of the cases are integrating, 10% have a negative gain and
    the rest are ordinary; the SNRs (`SNRS`), input kinds (`KINDS`) and
    length buckets (`N_BUCKETS`) are spread evenly over the cases, in
    random combinations. See `family_specs` for the arguments.

    Yields
    ------
    SyntheticCase

    Examples
    --------
    >>> from sandwichctl.data import random_family
    >>> [c.case_type for c in random_family(10, seed=2)].count('ordinary')
    8
    """
    # the specs are drawn (and the arguments checked) at the call, not at
    # the first next(): a bad argument raises where it was given
    specs = family_specs(n_cases, seed, n_range)
    return (random_case(**spec) for spec in specs)
