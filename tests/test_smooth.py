"""The smoothed backlash of the identifier's continuation stage: eq. (2.2)
away from tiny steps of x, continuous where eq. (2.2) makes the
output-error cost jump, and a path that crosses those jumps where the
descent on the exact cost stalls."""

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.data import random_case
from sandwichctl.identification._lm import lm
from sandwichctl.identification._predictor import smooth_output, oe_output
from sandwichctl.identification._smooth import smooth_refine, _step_spread
from sandwichctl.identification._problem import Problem


def _case(seed, n=1500):
    """A noise-free random case whose slope lines cross inside the range
    of x, its problem, the true phi and a start 5% away."""
    case = random_case(seed, snr=np.inf, n=n, input_kind='square+sine')
    prob = Problem(case.u, case.y, case.orders)
    truth = prob.phi_of_model(case.plant)
    rng = np.random.default_rng(seed)
    start = truth.copy()
    start[:prob.st.q] *= 1 + 0.05 * rng.standard_normal(prob.st.q)
    return case, prob, truth, start


@pytest.mark.parametrize('seed', [3, 19])
def test_smoothed_output_is_eq22_when_eps_is_below_every_step(seed):
    case, prob, truth, start = _case(seed)
    for phi in (truth, start):
        theta = prob.st.theta(phi)
        np.testing.assert_array_equal(
            smooth_output(theta, prob.st.o, prob.u[0], 1e-14),
            oe_output(theta, prob.st.o, prob.u[0]))


def test_the_smoothed_cost_is_continuous_where_the_exact_one_jumps():
    """Along a line in parameter space, the exact cost has a step that
    does not shrink with the grid (a discontinuity); the smoothed one
    shrinks with it."""
    case, prob, truth, start = _case(3)
    st, u, y = prob.st, prob.u[0], prob.y[0]
    crossing = case.plant.backlash.crossing
    assert crossing is not None
    eps = 0.1 * _step_spread(st, truth, prob.u)

    def costs(ts, smooth):
        out = []
        for t in ts:
            theta = st.theta((1 - t) * truth + t * start)
            yhat = (smooth_output(theta, st.o, u, eps) if smooth
                    else oe_output(theta, st.o, u))
            out.append(0.5 * float((y - yhat) @ (y - yhat)))
        return np.array(out)

    ts = np.linspace(0, 1, 201)
    i = int(np.argmax(np.abs(np.diff(costs(ts, False)))))
    fine = np.linspace(ts[i], ts[i + 1], 101)

    def concentration(values):
        """Share of the interval's total variation in its largest step:
        about 1/100 for a smooth function on this grid, large at a jump."""
        steps = np.abs(np.diff(values))
        return steps.max() / steps.sum()

    assert concentration(costs(fine, False)) > 0.2
    assert concentration(costs(fine, True)) < 0.05


@pytest.mark.parametrize('seed', [3, 13, 19])
def test_the_smoothing_path_crosses_jumps_where_descent_stalls(seed):
    """Noise-free, 5% from the truth: Levenberg-Marquardt on the exact
    cost stops on a piece of it; the path through smoothed costs followed
    by the same refinement recovers the plant exactly."""
    case, prob, truth, start = _case(seed)
    st = prob.st
    energy = 0.5 * float(prob.y[0] @ prob.y[0])
    stalled = lm(st, start, prob.u, prob.y, 200)
    assert stalled['cost'] > 1e-6 * energy
    out = smooth_refine(st, start, prob.u, prob.y)
    # exact up to the rounding of the scaled data (2**-30, `_data.scaled`)
    assert out['cost'] < 1e-16 * energy
    np.testing.assert_allclose(out['phi'], truth, atol=1e-7)


def test_identify_can_skip_the_smoothing_stage():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(600, seed=2)
    y = plant.simulate(u).outputs
    res = sw.identify(u, y, **plant.orders, smooth=False, hops=0)
    assert res.options['smooth'] is False
    with pytest.raises(TypeError, match='smooth'):
        sw.identify(u, y, **plant.orders, smooth='yes')


@pytest.mark.parametrize('seed', [3, 19])
def test_the_path_on_leading_samples_then_the_exact_cost_on_all(seed):
    """The smoothed problems on the leading third of the record (as a long
    record's stage 1 runs them) still lead to the plant: the exact
    refinement on every sample ends there."""
    case, prob, truth, start = _case(seed)
    st, u, y = prob.st, prob.u, prob.y
    energy = 0.5 * float(y[0] @ y[0])
    out = smooth_refine(st, start, u, y, path=([u[0][:500]], [y[0][:500]]))
    assert out['cost'] < 1e-16 * energy
    assert out['cost'] == pytest.approx(st.cost(out['phi'], u, y))
    np.testing.assert_allclose(out['phi'], truth, atol=1e-7)
