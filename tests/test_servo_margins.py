"""The modulus margin that `servo_controller` promises holds between the
points of its frequency grid: long delays and sharp resonances."""

import numpy as np
import control as ct
import pytest

import sandwichctl as sw
from sandwichctl.design._servo_design import frequency_grid


def dense_margin(ctrl, n=400_001):
    """min |1 + C P| on a uniform grid of n points up to pi."""
    z = np.exp(1j * np.linspace(1e-7, np.pi, n))
    return float(np.min(np.abs(1 + ctrl.pid(z) * ctrl.design_plant(z))))


@pytest.mark.parametrize('q', [20, 40])
def test_long_delays_keep_the_margin_between_grid_points(q):
    # the log grid alone was 0.02 rad/sample wide near pi, where 2q + 4
    # poles turn the phase by more than a radian per step: the design met
    # 0.6 on its points and 0.58 (q = 20) or 0.52 (q = 40) between them
    plant = sw.examples.paper_plant().copy_with(q1=q, q2=q)
    ctrl = sw.servo_controller(plant)
    assert ctrl.margins['modulus'] >= 0.6
    assert dense_margin(ctrl) >= 0.6 - 1e-3


def test_a_sharp_resonance_keeps_the_margin():
    pole = 0.9999 * np.exp(0.5j)
    den = np.real(np.poly([pole, np.conj(pole), 0.5]))
    ctrl = sw.servo_controller(ct.tf([0.1, 0.05], den, 1))
    assert dense_margin(ctrl, 2_000_001) >= 0.6 - 1e-3
    grid = frequency_grid(den)
    near = grid[np.abs(grid - 0.5) < 3e-4]
    assert near.size > 50 and np.max(np.diff(near)) < 1.1e-5


@pytest.mark.parametrize('poles', [
    [0.9, 0.5 + 0.3j, 0.5 - 0.3j, 0.2, 0.0],
    [0.99971, 0.5]])      # the log grid's first point a rounding below low
def test_a_low_order_plant_keeps_the_log_grid(poles):
    # what the drives' models are: their designs do not move
    den = np.real(np.poly(poles))
    low = min(1e-4, 0.1 * np.min(1 - np.abs(np.roots(den))))
    np.testing.assert_array_equal(
        frequency_grid(den), np.logspace(np.log10(low), np.log10(np.pi), 1500))
