"""Tests of sandwichctl.data.drive: the simulated servo drive."""

import pickle

import numpy as np
import pytest
from scipy.optimize import least_squares
from scipy.signal import lfilter

import sandwichctl as sw
from sandwichctl.data import (servo_drive, drive_reference, drive_case,
                              DRIVE_PARAMETERS)


def _oe_fit_percent(u, y, u_val, y_val, nb=3, nf=3, nk=1):
    """Fit % on validation data of a linear output-error model (scipy)."""
    su, sy = np.std(u), np.std(y)
    un, yn = u / su, y / sy
    n0 = max(nf, nk + nb)
    phi = np.column_stack(
        [-yn[n0 - i:yn.size - i] for i in range(1, nf + 1)]
        + [un[n0 - nk - j:un.size - nk - j] for j in range(nb)])
    theta0 = np.linalg.lstsq(phi, yn[n0:], rcond=None)[0]   # ARX start

    def simulate(theta, inp):
        return lfilter(np.r_[np.zeros(nk), theta[nf:]],
                       np.r_[1.0, theta[:nf]], inp)

    def residual(theta):
        if np.max(np.abs(np.roots(np.r_[1.0, theta[:nf]]))) >= 1:
            return np.full(yn.size, 1e3)
        return yn - simulate(theta, un)

    theta = least_squares(residual, theta0, method='lm', max_nfev=400).x
    yhat = sy * simulate(theta, u_val / su)
    return 100 * (1 - np.linalg.norm(y_val - yhat)
                  / np.linalg.norm(y_val - y_val.mean()))


def test_drive_is_deterministic_and_quantised():
    ref = drive_reference(1500, 'position', rng=2)
    y1 = servo_drive(ref, seed=5)
    y2 = servo_drive(ref, seed=5)
    np.testing.assert_array_equal(y1, y2)
    assert not np.array_equal(y1, servo_drive(ref, seed=6))
    counts = y1 / 1e-6
    assert np.max(np.abs(counts - np.round(counts))) < 1e-6
    assert y1[0] == 0.0
    # moves a few mm
    assert 1e-3 < np.ptp(y1) < 1e-2
    a, b = drive_case(4, n=1000), drive_case(4, n=1000)
    np.testing.assert_array_equal(a.y_val, b.y_val)
    assert not np.array_equal(a.u, a.u_val[:1000])


def test_drive_follows_position_reference():
    ref = np.r_[np.zeros(10), np.ones(490)]
    y, sig = servo_drive(ref, play=0.0, seed=0, internal=True)
    lead = DRIVE_PARAMETERS['lead'][0]
    assert abs(sig['theta'][-1] - 1) < 1e-3
    assert abs(y[-1] - lead / (2 * np.pi)) < 3e-6
    assert np.all(np.abs(sig['torque']) <= DRIVE_PARAMETERS['T_max'][0])


def test_speed_loop_output_integrates_the_reference():
    case = drive_case(1, 'speed', n=3000)
    lead = DRIVE_PARAMETERS['lead'][0]
    ideal = lead / (2 * np.pi) * np.cumsum(case.u) * case.dt
    # tracks the integral up to the loop lag and the play
    assert np.corrcoef(case.y, ideal)[0, 1] > 0.999
    assert np.max(np.abs(case.y - ideal)) < 0.1 * np.ptp(ideal)
    # the reference is zero mean and the position stays within a few cm
    assert abs(case.u.mean()) < 1e-9
    assert np.max(np.abs(case.y)) < 0.05


def test_play_degrades_a_linear_fit():
    fits = {}
    for play in (0.0, 200e-6):
        c = drive_case(0, 'position', play, n=2000)
        assert c.play == play and c.loop == 'position'
        fits[play] = _oe_fit_percent(c.u, c.y, c.u_val, c.y_val)
    assert fits[0.0] > 97
    assert 2 < fits[0.0] - fits[200e-6] < 15


def test_drive_argument_checks():
    ref = np.zeros(10)
    with pytest.raises(ValueError, match='loop'):
        servo_drive(ref, loop='torque')
    with pytest.raises(ValueError, match='play'):
        servo_drive(ref, play=-1e-6)
    with pytest.raises(TypeError, match='unknown servo-drive parameter'):
        servo_drive(ref, mass=3.0)
    with pytest.raises(ValueError, match='Kv'):
        servo_drive(ref, Kv=0.0)
    with pytest.raises(ValueError, match='reference'):
        servo_drive([0.0, np.nan])


def test_hertzian_contact_law():
    """p = 1.5 (Hertzian, Hunt-Crossley damping) runs, differs from the
    linear contact only by a little, and the stepped drive equals the
    simulation bit for bit; p outside [1, 3] is refused."""
    from sandwichctl.data import ServoDrive
    ref = drive_reference(1500, 'position', rng=4)
    y1 = servo_drive(ref, seed=2)
    y15 = servo_drive(ref, seed=2, contact=1.5)
    assert np.all(np.isfinite(y15))
    assert 0 < np.max(np.abs(y15 - y1)) < 0.05 * np.ptp(y1)
    drive = ServoDrive(seed=2, n=ref.size, contact=1.5)
    stepped = [drive.read()] + [drive.step(u) for u in ref[:-1]]
    assert np.array_equal(stepped, y15)
    for bad in (0.5, 3.5, np.nan):
        with pytest.raises(ValueError, match='contact'):
            servo_drive(ref[:10], contact=bad)


def test_random_drives_vary_the_contact_law():
    from sandwichctl.data import random_drive
    laws = {random_drive(k)['params'].get('contact', 1.0) for k in range(16)}
    assert laws == {1.0, 1.5}


def test_drive_cases_of_one_seed_are_equal():
    # the dataclass's == raised numpy's "truth value of an array"
    a = sw.data.drive_case(1, n=300)
    assert a == sw.data.drive_case(1, n=300)
    assert a != sw.data.drive_case(2, n=300)
    assert pickle.loads(pickle.dumps(a)) == a
