"""The servo design's preview inverse (`design._servo_inverse`): a zero
outside the unit circle right beside a pole is cancelled with it before
the inverse, instead of keeping its DC gain beside the pole."""

import numpy as np

from sandwichctl.design import _servo_inverse as si

#: the linear fit of the drive's speed loop (200 um of play) that stalled
#: on a record of a tenth of its usual amplitude
STALLED = (np.array([3.332331395693157e-08, -6.664727711866099e-08,
                     3.332442121098345e-08, 0.0]),
           np.array([1.0, -3.9791134189139528, 5.937354081707194,
                     -3.93736762488304, 0.979126962089799]))


def _gain(num, den, w):
    z = np.exp(1j * w)
    return np.abs(np.polyval(num, z) / np.polyval(den, z))


def test_a_zero_outside_beside_a_pole_is_cancelled_with_it():
    num, den = STALLED
    poles = np.roots(den)
    pair = poles[np.abs(poles.imag) > 1e-3]
    zeros = np.roots(num)
    outer = zeros[np.abs(zeros.imag) > 1e-3]
    assert np.all(np.abs(outer) > 1)         # just outside, beside the pair
    n2, d2, pairs = si.coincident(num, den)
    assert len(pairs) == 2
    assert np.allclose(sorted(np.roots(d2).real), sorted(
        poles[np.abs(poles.imag) <= 1e-3].real), atol=1e-6)
    assert n2.size == num.size - 2 and n2[0] == num[0]   # gain kept at high w
    # the pair's factor is within 5 % of 1 at low frequencies: the
    # plant's response there is kept
    w = np.logspace(-1.5, 0, 20)
    assert np.allclose(_gain(n2, d2, w), _gain(num, den, w), rtol=0.05)
    assert np.allclose(sorted(p for _, p in pairs), sorted(pair))


def test_the_inverse_of_a_pair_keeps_the_plants_gain():
    """Before, the zeros' DC gain (1.4e-5) stood beside the poles in the
    inverse, whose gain at 10 Hz (1 ms samples) was hundreds of times
    1 / |P| there."""
    num, den = STALLED
    fn, fd, delay, (dc_only, pairs) = si.preview_inverse(num, den)
    assert dc_only == [] and len(pairs) == 2
    w = 2 * np.pi * 10 * 1e-3
    assert np.isclose(_gain(fn, fd, w) * _gain(num, den, w), 1.0, rtol=0.05)


def test_zeros_far_from_poles_or_inside_are_kept():
    # a zero outside far from every pole, one inside beside a pole, and a
    # pole at z = 1 (an integrator) beside a zero: none cancelled
    num = np.poly([1.5, 0.8001])
    den = np.poly([0.9, 0.8, 1.0])
    assert si.coincident(num, den)[2] == []
    assert si.coincident(np.poly([1.00001]), np.poly([1.0, 0.5]))[2] == []
    # a real zero beside one of a complex pair is not paired
    assert si.coincident(np.poly([1.001]),
                         np.poly([0.999 + 1e-4j, 0.999 - 1e-4j]))[2] == []


def test_a_plant_left_without_zeros_or_poles_is_inverted():
    """Every zero (or every pole) cancelled leaves a constant: the first
    version crashed there on a random plant of bench_servo_random.py's
    seeds 50 to 99."""
    z0, p = 1.00001 + 0.0037j, 0.99999 + 0.00367j
    num, den = 2.0 * np.real(np.poly([z0, np.conj(z0)])), np.real(np.poly(
        [p, np.conj(p)]))
    n2, d2, pairs = si.coincident(num, den)
    assert len(pairs) == 2 and n2.shape == d2.shape == (1,)
    assert n2[0] == 2.0
    fn, fd, delay, _ = si.preview_inverse(num, np.polymul(den, [1, -0.5]))
    assert np.all(np.isfinite(fn)) and np.all(np.isfinite(fd))
