"""Tests of the hysteresis plot (Agg backend, set in conftest.py)."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

import sandwichctl as sw


@pytest.fixture
def ax():
    fig, ax = plt.subplots()
    yield ax
    plt.close(fig)


def _curve(ax, index):
    line = ax.get_lines()[index]
    return np.asarray(line.get_xdata()), np.asarray(line.get_ydata())


def test_backlash_loop_is_eq_2_2(ax):
    bl = sw.Backlash(1.0, 1.2, 0.5, 0.6, dt=1)
    x = np.concatenate([np.linspace(0, 3, 31), np.linspace(3, -3, 61)])
    assert sw.plot_hysteresis(bl, x=x, ax=ax) is ax
    xs, vs = _curve(ax, 0)
    np.testing.assert_array_equal(xs, x)
    np.testing.assert_array_equal(vs, sw.backlash_response(x, 1, 1.2, 0.5,
                                                           0.6))
    assert ax.get_xlabel() == 'x' and ax.get_ylabel() == 'v'


def test_slope_lines(ax):
    bl = sw.Backlash(2.0, 0.5, 0.25, 1.0, dt=1)
    x = np.linspace(-2, 2, 41)
    sw.plot_hysteresis(bl, x=x, ax=ax)
    xi, vi = _curve(ax, 1)                   # increase line
    xd, vd = _curve(ax, 2)                   # decrease line
    np.testing.assert_allclose(vi, 2.0 * (xi - 0.25), rtol=1e-14)
    np.testing.assert_allclose(vd, 0.5 * (xd + 1.0), rtol=1e-14)
    assert xi.min() < -2 and xi.max() > 2    # a margin around the data
    # m1 != m2: the crossing x* = (m1 D1 + m2 D2)/(m1 - m2) = 2/3 is marked
    xc, vc = _curve(ax, 3)
    np.testing.assert_allclose(xc, [2 / 3], rtol=1e-14)
    np.testing.assert_allclose(vc, [2.0 * (2 / 3 - 0.25)], rtol=1e-14)


def test_without_lines(ax):
    sw.plot_hysteresis(sw.Backlash(1, 1, 0.5, 0.5), ax=ax, lines=False)
    assert len(ax.get_lines()) == 1


def test_identified_over_true_sandwich(ax):
    plant = sw.examples.paper_plant()
    model = sw.SandwichSystem.from_theta(
        [1.2, 0.32, 0.1, 0.2, 2.9, 3.5, 0.3, 0.45, -0.05],
        na=2, nb=0, nc=2, nd=1, dt=1)
    sw.plot_hysteresis(model, true=plant, ax=ax)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels[0].startswith('identified (m1=2.9, m2=3.5, D1=0.3')
    # the true plant is drawn normalised (b0 = d0 = 1): m1 = 1*1.5*2 = 3
    assert labels[1].startswith('true (m1=3, m2=3.6, D1=0.333, D2=0.4')
    # default sweep: amplitude 3 * max D over both backlashes = 1.35
    x_model, _ = _curve(ax, 0)
    np.testing.assert_allclose([x_model.min(), x_model.max()],
                               [-1.35, 1.35], rtol=1e-14)
    true_bl = plant.normalized().backlash
    [true_line] = [line for line in ax.get_lines()
                   if line.get_label().startswith('true')]
    x_true, v_true = true_line.get_xdata(), true_line.get_ydata()
    assert true_line.get_linestyle() == '--'
    np.testing.assert_array_equal(x_true, x_model)
    np.testing.assert_array_equal(v_true, true_bl.response(x_model))


def test_sandwich_without_normalising(ax):
    plant = sw.examples.paper_plant()
    sw.plot_hysteresis(plant, ax=ax, normalize=False, label='raw')
    label = ax.get_legend().get_texts()[0].get_text()
    assert label.startswith('raw (m1=1, m2=1.2, D1=0.5, D2=0.6')


def test_default_axes_and_zero_thresholds():
    plt.figure()
    ax = sw.plot_hysteresis(sw.Backlash(1.0, 1.0, 0.0, 0.0))
    assert ax is plt.gca()
    x, v = _curve(ax, 0)
    np.testing.assert_array_equal(v, x)      # no dead band: v = x
    assert x.max() == 1.0                    # amplitude 1 when D = 0
    plt.close(ax.figure)


def test_errors():
    with pytest.raises(TypeError, match=r"model_or_backlash must be a "
                                        r"sandwichctl.SandwichSystem or "
                                        r"sandwichctl.Backlash; got int"):
        sw.plot_hysteresis(3)
    with pytest.raises(TypeError, match=r"true must be .* got str"):
        sw.plot_hysteresis(sw.Backlash(1, 1, 0.5, 0.5), true='plant')
    with pytest.raises(ValueError, match=r"x must be finite"):
        sw.plot_hysteresis(sw.Backlash(1, 1, 0.5, 0.5), x=[0, np.inf])


def test_loop_sensitivity_on_the_model_and_the_measured_response(
        ax, lagged_fit):
    # a first-order fit of a plant with a second lag: the curves part
    lin = lagged_fit[1]
    ctrl = sw.servo_controller(lin)
    assert sw.plot_loop(ctrl, ax=ax) is ax
    model, measured = _curve(ax, 0), _curve(ax, 2)
    assert model[0][-1] == pytest.approx(500.0, rel=1e-3)     # Nyquist, Hz
    # the peaks are 1 / the margins the design reports
    m = ctrl.margins
    assert np.max(model[1]) == pytest.approx(1 / m['modulus'], rel=0.02)
    assert np.max(measured[1]) == pytest.approx(1 / m['modulus_measured'],
                                                rel=0.02)
    assert 'measured' in ax.get_legend().get_texts()[1].get_text()
    assert f"{m['modulus_measured']:.3f}" in ax.get_title()
    # a model without data: the model's curve alone
    fig, ax2 = plt.subplots()
    sw.plot_loop(sw.servo_controller(lin.model), ax=ax2)
    assert len(ax2.get_legend().get_texts()) == 1
    plt.close(fig)
    with pytest.raises(TypeError, match='ServoController'):
        sw.plot_loop(lin)
    with pytest.raises(TypeError, match='Axes'):
        sw.plot_loop(ctrl, ax='here')
