"""The servo design's inverse of a linear model along the reference
(private): zeros inside the unit circle inverted exactly, those outside
(or on it, or ringing at the Nyquist frequency) by an anticausal series
with some samples of reference preview, or by their DC gain alone where
the series would need more than the preview allowed; a zero beside a pole
cancelled with it first (`coincident`)."""

import numpy as np

__all__ = []

#: a zero this close to the unit circle or outside counts as unstable
ZERO_RADIUS = 1.0
#: zeros left of this real part make an inverse ring at the Nyquist
#: frequency (sampling zeros); they keep only their DC gain
RINGING = -0.5
#: a pole this close to z = 1 is an integrator (`at_one`)
AT_ONE = 1e-6
#: truncation of the anticausal series of an unstable zero
SERIES_TOL = 1e-3
#: `coincident`: a zero on or outside the unit circle within this share of
#: a pole's distance from z = 1 of that pole cancels it in the inverse
COINCIDENT = 0.05


def at_one(roots):
    """Which of the roots sit at z = 1 (within `AT_ONE`): the
    integrators among poles."""
    return np.abs(np.asarray(roots) - 1) < AT_ONE


def series_length(zj):
    """Samples of preview the anticausal series of :math:`1/(z - z_j)`
    needs, its terms :math:`|z_j|^{-i}` cut below `SERIES_TOL`; inf for a
    zero on the unit circle or a ringing one (real part below `RINGING`),
    which only keep their DC gain."""
    if abs(zj) > 1 + 1e-6 and np.real(zj) >= RINGING:
        return int(np.ceil(np.log(SERIES_TOL) / -np.log(abs(zj))))
    return np.inf


def coincident(num, den):
    """(num, den, pairs): num/den (descending powers of z) with each zero
    on or outside the unit circle cancelled against the pole nearest it,
    where that pole, not at z = 1, lies within `COINCIDENT` times its own
    distance from 1 (the pair's factor is within that share of 1 at low
    frequencies), the high-frequency gain kept; pairs lists them as
    (zero, pole). Inverting such a zero alone keeps its DC gain beside the
    pole: a linear fit of the drive's speed loop that stalled on a record
    of a tenth of its usual amplitude (200 um of play) left zeros 1.00001
    +- 0.00371j beside poles 0.99999 +- 0.00367j, the inverse's gain rose
    hundreds of times above 1 Hz, and the loop ran away on the drive (30
    mm of RMS error)."""
    zeros = list(np.roots(num)) if num.size > 1 else []
    poles = list(np.roots(den)) if den.size > 1 else []
    pairs = []
    for z0 in [z for z in zeros
               if abs(z) >= ZERO_RADIUS - 1e-9 and z.imag >= 0]:
        free = [p for p in poles if not at_one(p)]
        p = min(free, key=lambda q: abs(q - z0), default=None)
        if p is None or not (abs(p - z0) < COINCIDENT * abs(1 - p)
                             and (z0.imag > 0) == (p.imag > 0)):
            continue
        for zz, pp in [(z0, p), (np.conj(z0), np.conj(p))][
                :2 if z0.imag > 0 else 1]:
            zeros.remove(min(zeros, key=lambda q: abs(q - zz)))
            poles.remove(min(poles, key=lambda q: abs(q - pp)))
            pairs.append((zz, pp))
    if not pairs:
        return num, den, []
    return (np.atleast_1d(np.real(num[0] * np.poly(zeros))),
            np.atleast_1d(np.real(den[0] * np.poly(poles))), pairs)


def preview_inverse(num, den, kind='preview', max_preview=20):
    """Numerator, denominator (descending powers of z) and delay d of the
    preview inverse of num/den; also (the zeros handled approximately, the
    (zero, pole) pairs cancelled first: `coincident`)."""
    num = np.trim_zeros(np.asarray(num, float), 'f')
    num, den, pairs = coincident(num, np.asarray(den, float))
    zeros = np.roots(num) if num.size > 1 else np.zeros(0)
    ringing = (np.real(zeros) < RINGING) & (np.abs(zeros) < 1 - 1e-9)
    unstable = (np.abs(zeros) >= ZERO_RADIUS - 1e-9) | ringing
    stable_part = num[0] * np.atleast_1d(np.real(np.poly(zeros[~unstable])))
    q = np.ones(1)
    dc_only, kept = [], []
    nu = zeros[unstable]
    if kind == 'zpetc' and nu.size:
        poly_u = np.real(np.poly(nu))
        q = poly_u[::-1] / np.polyval(poly_u, 1.0) ** 2
    elif nu.size:
        for zj in nu:
            count = series_length(zj)
            if count > max_preview:
                dc_only.append(zj)
                stable_part = stable_part * (1.0 - zj)
                continue
            kept.append(zj)
            # 1/(z - zj) ~ -sum_i z^i / zj^(i+1), highest power first
            series = -np.array([zj ** -(i + 1) for i in range(count)])[::-1]
            q = np.convolve(q, series)
        if kept:
            q = q / (np.polyval(np.poly(kept), 1.0) * np.polyval(q, 1.0))
        q = np.real(q)
    stable_part = np.real(stable_part)
    n_num = np.convolve(den, q)
    delay = n_num.size - stable_part.size
    n_den = np.concatenate([stable_part, np.zeros(max(delay, 0))])
    return n_num, n_den, max(delay, 0), (dc_only, pairs)


