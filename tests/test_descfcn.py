"""Tests of the describing function of the asymmetric backlash (issue 5)."""

import warnings

import matplotlib.pyplot as plt
import numpy as np
import control as ct
import pytest

import sandwichctl as sw
from sandwichctl.model.backlash import backlash_step

NORMALISED = (3.0, 3.6, 1 / 3, 0.4)        # the paper's plant, b0 = d0 = 1


def _harmonics_by_simulation(A, c, m1, m2, D1, D2, n=20000):
    """Mean and first harmonic of eq. (2.2) driven by c + A sin, simulated
    with the package's backlash over three periods (the last one used)."""
    theta = 2 * np.pi * np.arange(n) / n
    x = c + A * np.sin(theta)
    v = sw.backlash_response(np.tile(x, 3), m1, m2, D1, D2,
                             x_prev=x[0], v_prev=m2 * (x[0] + D2))[2 * n:]
    return (v.mean(), 2 * np.mean(v * np.sin(theta)),
            2 * np.mean(v * np.cos(theta)))


class _SteppedBacklash:
    """A stateful scalar backlash with input bias, for python-control's
    *numerical* describing function (test oracle only: the package itself
    keeps memory in state)."""

    def __init__(self, c, m1, m2, D1, D2):
        self.c, self.p = c, (m1, m2, D1, D2)
        self.x, self.v = c, 0.0

    def __call__(self, x):
        x = self.c + x
        self.v, _ = backlash_step(x, self.x, self.v, *self.p)
        self.x = x
        return self.v


@pytest.mark.parametrize('b', [0.2, 1.0, 3.0])
def test_matches_python_control_friction_backlash(b):
    F = sw.backlash_nonlinearity(sw.Backlash(1, 1, b / 2, b / 2))
    A = np.concatenate([[b / 4, b / 2], np.linspace(b / 2 + 1e-3, 10 * b, 40)])
    np.testing.assert_allclose(
        ct.describing_function(F, A),
        ct.describing_function(ct.friction_backlash_nonlinearity(b), A),
        rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize('m, D1, D2, bias', [(2.5, 0.1, 0.7, 0.0),
                                             (0.4, 0.3, 0.0, -2.0),
                                             (1.0, 0.5, 0.5, 5.0)])
def test_equal_slopes_scale_the_symmetric_case(m, D1, D2, bias):
    # m1 = m2 = m: shifting the input shifts v by m times the shift, so N is
    # m times python-control's friction backlash of width D1 + D2, whatever
    # the bias or output mean
    A = np.linspace(0.6, 4, 20)
    expected = m * ct.describing_function(
        ct.friction_backlash_nonlinearity(D1 + D2), A)
    for F in (sw.BacklashNonlinearity(m, m, D1, D2, output_mean=bias),
              sw.BacklashNonlinearity(m, m, D1, D2, input_bias=bias)):
        np.testing.assert_allclose(ct.describing_function(F, A), expected,
                                   rtol=1e-12)


@pytest.mark.parametrize('A, c, params', [
    (1.0, 0.0, NORMALISED),
    (2.0, 0.5, (1.0, 1.2, 0.5, 0.6)),
    (1.0, -0.3, (3.6, 3.0, 0.4, 0.3)),
    (0.8, 0.2, (0.5, 2.0, 0.1, 0.3)),
    (5.0, -5.0, (1.0, 1.2, 0.5, 0.6)),     # reaches the slope-line crossing
    (3.0, -6.0, (1.0, 1.2, 0.5, 0.6)),     # straddles it
])
def test_closed_form_matches_simulated_eq_2_2(A, c, params):
    closed = sw.backlash_harmonics(A, c, *params)
    simulated = _harmonics_by_simulation(A, c, *params)
    scale = params[0] * A
    np.testing.assert_allclose(closed, simulated, rtol=0, atol=2e-4 * scale)


@pytest.mark.parametrize('params', [NORMALISED, (1.0, 1.2, 0.5, 0.6),
                                    (2.0, 0.7, 0.2, 0.5)])
def test_matches_python_control_numerical_describing_function(params):
    # python-control's own numerical DF (harmonic projection, its sign
    # conventions) applied to the centred, stepped eq. (2.2)
    F = sw.BacklashNonlinearity(*params)
    for A in (0.6, 1.5, 4.0):
        c = F.bias(A)
        oracle = _SteppedBacklash(c, *params)
        for x in A * np.sin(np.linspace(0, 2 * np.pi, 4000,
                                        endpoint=False)):
            oracle(x)                                    # reach steady state
        numeric = ct.describing_function(oracle, A, num_points=4000,
                                         try_method=False)
        np.testing.assert_allclose(F.describing_function(A), numeric,
                                   rtol=2e-3)


@pytest.mark.parametrize('params', [NORMALISED, (3.6, 3.0, 0.4, 1 / 3)])
@pytest.mark.parametrize('mean', [0.0, 1.5, -2.0])
def test_centring_gives_the_requested_output_mean(params, mean):
    F = sw.BacklashNonlinearity(*params, output_mean=mean)
    for A in (0.8, 2.0, 6.0):
        c = F.bias(A)
        a0, _, _ = sw.backlash_harmonics(A, c, *params)
        np.testing.assert_allclose(a0, mean, rtol=0, atol=1e-10)
        np.testing.assert_allclose(_harmonics_by_simulation(A, c, *params)[0],
                                   mean, rtol=0, atol=1e-3)


def test_inside_the_band_the_output_is_constant():
    m1, m2, D1, D2 = NORMALISED
    F = sw.BacklashNonlinearity(*NORMALISED)
    half_band = 0.5 * (D1 + D2)                  # band width at v = 0
    assert F.describing_function(half_band * 0.99) == 0
    assert F.describing_function(0.0) == 0
    assert abs(F.describing_function(half_band * 1.01)) > 0
    a0, b1, a1 = sw.backlash_harmonics(0.1, 0.0, *NORMALISED)
    assert np.isnan(a0) and b1 == 0 and a1 == 0


def test_works_with_python_control_response_and_plot():
    # python-control's own example loop, with our nonlinearity
    H = ct.tf([8], [1, 2, 2, 1])
    F = sw.BacklashNonlinearity(1.0, 1.5, 0.1, 0.2)
    A = np.geomspace(0.1501, 5, 200)          # band half-width 0.15 at v = 0
    resp = ct.describing_function_response(H, F, A, warn_nyquist=False)
    assert len(resp.intersections) == 1
    a, w = resp.intersections[0]
    N = F.describing_function(a)
    np.testing.assert_allclose(1 + H(1j * w) * N, 0, atol=1e-4)
    cplt = ct.describing_function_plot(H, F, A, warn_nyquist=False)
    assert len(cplt.lines) == 2
    plt.close('all')


def test_unit_circle_frd_and_discrete_limit_cycles():
    H = ct.tf([0.5], [1, -0.5], 0.1)
    frd = sw.unit_circle_frd(H)
    w = np.array([0.3, 3.0, 20.0])
    np.testing.assert_allclose(frd(1j * w), H(np.exp(1j * w * 0.1)),
                               rtol=1e-6)
    with pytest.raises(ValueError, match="discrete-time"):
        sw.unit_circle_frd(ct.tf([1], [1, 1]))
    with pytest.raises(ValueError, match="omega must lie"):
        sw.unit_circle_frd(H, omega=[0.1, 40.0])


def _lowpass_integrator(k=0.5, p=0.9):
    """Integral controller with a first-order low-pass filter."""
    return ct.tf([k * (1 - p), 0], np.polymul([1, -1], [1, -p]), 1)


def test_limit_cycle_prediction_matches_simulation():
    # The paper's plant (normalised, so x is in the model's units) under an
    # integral controller with a low-pass: the linearised loop is stable,
    # but the describing function predicts a limit cycle, and simulation
    # of eq. (2.2) confirms its amplitude and frequency within 10 %.
    plant = sw.examples.paper_plant().normalized()
    C = _lowpass_integrator()
    linear = ct.feedback(C * plant.L2 * plant.L1 * 3.3, 1)
    assert np.max(np.abs(linear.poles())) < 1
    resp = sw.sandwich_limit_cycles(plant, C)
    amp_sim, w_sim, _ = sw.simulate_limit_cycle(plant, C)
    amp, w = max(resp.intersections)              # the stable, larger one
    np.testing.assert_allclose(amp, amp_sim, rtol=0.1)
    np.testing.assert_allclose(w, w_sim, rtol=0.1)
    np.testing.assert_allclose([amp, w], [1.1678, 0.18632], rtol=1e-3)
    axes = resp.plot().axes
    assert axes.shape == (1, 1)
    plt.close('all')


def test_first_harmonic_of_a_sampled_sine():
    k = np.arange(3000)
    x = 0.3 + 1.7 * np.sin(0.25 * k + 1.0) + 0.2 * np.sin(0.75 * k)
    amp, w, mean = sw.first_harmonic(x, dt=0.5)
    np.testing.assert_allclose([amp, w, mean], [1.7, 0.5, 0.3], rtol=2e-3,
                               atol=2e-3)
    with pytest.raises(ValueError, match="crosses its mean"):
        sw.first_harmonic(np.linspace(0, 1, 100))


@pytest.mark.parametrize('call, error, match', [
    (lambda: sw.BacklashNonlinearity(0, 1, 0.5, 0.5), ValueError,
     'm1 must be a finite number > 0'),
    (lambda: sw.BacklashNonlinearity(1, -2, 0.5, 0.5), ValueError,
     'm2 must be a finite number > 0'),
    (lambda: sw.BacklashNonlinearity(1, 1, 0.5, 0.5).describing_function(-1),
     ValueError, 'A must be a finite number >= 0'),
    (lambda: sw.BacklashNonlinearity(1, 1, 0.5, 0.5)(0.3), TypeError,
     'memory'),
    (lambda: sw.backlash_nonlinearity(sw.examples.paper_plant()), TypeError,
     'Backlash'),
    (lambda: sw.sandwich_limit_cycles(sw.Backlash(1, 1, 0, 0),
                                      ct.tf([1], [1, -1], 1)), TypeError,
     'SandwichSystem'),
])
def test_bad_input(call, error, match):
    with pytest.raises(error, match=match):
        call()


def test_a_refined_crossing_outside_the_amplitudes_scanned_is_not_kept():
    """A helper's review: with C = 0.2 z / ((z - 1)(z - 0.9)) on the
    paper's plant the refinement moved a crossing to amplitude -0.488.
    The crossing of the scan stands there, and the loop around mbar L1 C
    L2, unstable, is warned about; its simulation diverges and says so
    instead of reporting a cycle of amplitude 7e65."""
    model = sw.examples.paper_plant().normalized()
    C = ct.tf([0.2, 0], np.polymul([1, -1], [1, -0.9]), 1)
    with pytest.warns(sw.SimulationWarning, match='unstable'):
        fine = sw.sandwich_limit_cycles(model, C)
    with pytest.warns(sw.SimulationWarning, match='unstable'):
        rough = sw.sandwich_limit_cycles(model, C, refine=False)
    assert all(a > 0 for a, _ in fine.intersections)
    assert len(fine.intersections) == len(rough.intersections) == 2
    assert fine.intersections[0] == rough.intersections[0]
    with pytest.warns(sw.SimulationWarning, match='diverges'):
        amp, w, _ = sw.simulate_limit_cycle(model, C, n=3000, kick=0.5)
    assert amp == np.inf and np.isnan(w)


def test_a_loop_at_rest_has_no_limit_cycle():
    """x settled to within 1e-16: rounding noise crossed its mean and was
    reported as a cycle of amplitude 3e-17."""
    model = sw.examples.paper_plant().normalized()
    amp, w, _ = sw.simulate_limit_cycle(model, ct.tf([0.3], [1], 1),
                                        n=6000, kick=2.0)
    assert amp == 0.0 and np.isnan(w)


@pytest.mark.parametrize('refine', [True, False])
def test_amplitudes_inside_the_band_are_left_out_of_the_scan(refine):
    """A grid of A that starts inside the play (N(A) = 0, -1/N infinite)
    gave thousands of (nan, nan) intersections and RuntimeWarnings, or,
    refined, an error about a NaN amplitude the user never gave: those
    amplitudes are left out, and the crossing beyond them is found."""
    plant = sw.examples.paper_plant()
    C = ct.tf([0.1], [1, -1], 1)
    with warnings.catch_warnings():
        warnings.simplefilter('error', RuntimeWarning)
        # this loop is unstable around mbar L1 C L2, and says so
        warnings.simplefilter('ignore', sw.SimulationWarning)
        resp = sw.sandwich_limit_cycles(plant, C, A=np.linspace(0.3, 2, 20),
                                        refine=refine)
    pts = np.array(resp.intersections, dtype=float)
    assert pts.shape == (1, 2) and np.all(np.isfinite(pts))
    assert 1.7 < pts[0, 0] < 1.9
    bl = sw.backlash_nonlinearity(sw.Backlash(1.0, 1.0, 0.5, 0.5))
    with pytest.raises(ValueError, match="dead band"):
        sw.limit_cycles(ct.tf([0.5], [1, -0.5], 1), bl, A=[0.1, 0.2, 0.4])
    # a plain function is a nonlinearity too (its describing function
    # comes back as an array of one)
    sat = sw.limit_cycles(ct.tf([3], [1, 2, 1, 0]),
                          lambda x: np.clip(x, -1, 1),
                          A=np.linspace(0.5, 5, 30), refine=False)
    assert len(sat.intersections) == 1
    assert sat.intersections[0][1] == pytest.approx(1.0, abs=1e-3)
