"""Reference signals for closed loops.

- `steps_and_sines`: a staircase of steps, then a sum of sines (the
  compensation tutorial and `closed_loop_demo`).
- `servo_reference`: a servo axis's test trajectory in physical time:
  S-curve steps with reversals and holds, ramps and a sine
  (``benchmarks/bench_servo.py`` and the servo tutorial).
"""

import numpy as np

from .._checks import (MOST_SAMPLES, check_int, check_vector,
                       check_positive)

__all__ = ['steps_and_sines', 'servo_reference']


def steps_and_sines(n=1200, levels=(0.0, 1.0, -0.5, 1.5, 0.3),
                    amplitudes=(0.8, 0.2), periods=(100, 37)):
    """A tracking reference: a staircase of steps, then a sum of sines.

    The first half of the `n` samples holds each of `levels` in turn for an
    equal time; the second half is ``sum(a * sin(2 pi k / p))``.

    Parameters
    ----------
    n : int, optional
        Number of samples (default 1200).
    levels : sequence of float, optional
        Step levels; start with 0 to begin at rest.
    amplitudes, periods : sequence of float, optional
        Sine amplitudes and periods (in samples).

    Returns
    -------
    ndarray, shape (n,)

    Examples
    --------
    >>> import sandwichctl as sw
    >>> r = sw.steps_and_sines(20, levels=(0, 1), amplitudes=(1,),
    ...                        periods=(4,))
    >>> print(r.round(3))
    [ 0.  0.  0.  0.  0.  1.  1.  1.  1.  1.  0.  1.  0. -1. -0.  1.  0. -1.
     -0.  1.]
    """
    n = check_int('n', n, minimum=2, maximum=MOST_SAMPLES)
    levels = check_vector('levels', levels)
    if levels.size == 0:
        raise ValueError("levels must hold at least one level (the first "
                         "half of the reference steps through them)")
    if levels.size > n // 2:
        raise ValueError(f"levels must fit in the first half of the n = {n} "
                         f"samples, one sample each at least; got "
                         f"{levels.size} levels (give n >= "
                         f"{2 * levels.size})")
    amplitudes = check_vector('amplitudes', amplitudes)
    periods = check_vector('periods', periods)
    if periods.size != amplitudes.size:
        raise ValueError(f"amplitudes and periods must have the same length "
                         f"(a period per sine); got {amplitudes.size} "
                         f"amplitude(s) and {periods.size} period(s)")
    if np.any(periods <= 0):
        raise ValueError(f"periods must be > 0 (in samples); got {periods}")
    half = n // 2
    r = np.empty(n)
    edges = np.linspace(0, half, len(levels) + 1).round().astype(int)
    for lev, a, b in zip(levels, edges[:-1], edges[1:]):
        r[a:b] = lev
    k = np.arange(n - half)
    r[half:] = sum(a * np.sin(2 * np.pi * k / p)
                   for a, p in zip(amplitudes, periods))
    return r


def servo_reference(dt, travel, hold=0.5):
    """A test trajectory for a servo axis, in physical time.

    From rest: five S-curve steps of 80 ms between levels of
    ``travel * (1, -0.5, 0.3, -1, 0)`` (reversals after holds), ramps at
    about ``travel / 0.6 s`` to +travel, -travel and back to 0 (reversals
    without a hold), a 1 Hz sine of amplitude 0.7 travel for 2 s (smooth
    reversals), and a last hold. Each level is held for `hold` seconds.

    Parameters
    ----------
    dt : float
        Sample time in seconds.
    travel : float
        Largest excursion, in the units of y (e.g. 1e-3 for 1 mm).
    hold : float, optional
        Seconds of each hold (default 0.5).

    Returns
    -------
    ndarray
        The reference, about 9 s long.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> r = sw.servo_reference(1e-3, 1e-3)
    >>> r.size, float(r.max()), float(r.min())
    (9450, 0.001, -0.001)
    """
    dt = check_positive('dt', dt)
    travel = check_positive('travel', travel)
    hold = check_positive('hold', hold)
    if dt > 0.5:
        raise ValueError(f"dt must be at most 0.5 s (two samples a period "
                         f"of the trajectory's 1 Hz sine); got {dt:g}")
    # about 5.25 s of steps, ramps and sine, and 8.4 holds
    total = (5.25 + 8.4 * hold) / dt
    if total > MOST_SAMPLES:
        raise ValueError(f"servo_reference: holds of {hold:g} s at dt = "
                         f"{dt:g} s make {total:.3g} samples; at most "
                         f"{MOST_SAMPLES:.0e} (a longer dt or a shorter "
                         f"hold)")

    def count(seconds):
        return max(2, int(round(seconds / dt)))

    parts, level = [np.zeros(count(0.3))], 0.0
    for target in (1.0, -0.5, 0.3, -1.0, 0.0):
        s = np.linspace(0.0, 1.0, count(0.08))
        parts += [level + (target - level) * (0.5 - 0.5 * np.cos(np.pi * s)),
                  np.full(count(hold), target)]
        level = target
    for target in (1.0, -1.0, 0.0):
        parts.append(np.linspace(level, target,
                                 count(0.6 * abs(target - level) + 0.05)))
        parts.append(np.full(count(0.4 * hold / 0.5), target))
        level = target
    t = dt * np.arange(count(2.0))
    parts += [0.7 * np.sin(2 * np.pi * t), np.zeros(count(hold))]
    return travel * np.concatenate(parts)
