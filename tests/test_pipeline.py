"""Trustworthy identification (issue 12): units, orders, sign, the linear
baseline it nests, integrators, degenerate data and an honest verdict.

Seeds here differ from the robustness benchmark's family (seed 0 and 1 of
`benchmarks/bench_robustness.py`)."""

import warnings

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.data import random_case


@pytest.fixture(scope='module')
def paper_noisy():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(3000, seed=21)
    y = sw.examples.add_noise(plant.simulate(u).outputs, 100, seed=22)
    return plant, u, y


@pytest.mark.parametrize('su, sy', [(1e-4, 1e-4), (1.0, 1e4), (1e-3, 1e3),
                                    (1e4, 1e-4), (1e4, 1e4)])
def test_units_do_not_matter(paper_noisy, su, sy):
    """u and y scaled independently by 1e-4..1e4: the same fit, and the
    model in the data's units (slopes scale by sy/su, widths by su)."""
    plant, u, y = paper_noisy
    ref = sw.identify(u, y, **plant.orders)
    res = sw.identify(u * su, y * sy, **plant.orders)
    assert res.success and ref.success
    assert res.fit == pytest.approx(ref.fit, abs=1e-6)
    assert res.model.orders == plant.orders
    im = 4                                        # nc + na
    expected = ref.theta.copy()
    expected[im:im + 2] *= sy / su
    expected[im + 2:im + 4] *= su
    np.testing.assert_allclose(res.theta, expected, rtol=1e-6, atol=0)
    y_hat = res.model.simulate(u * su).outputs
    assert sw.fit_percent(y * sy, y_hat) == pytest.approx(res.fit, abs=1e-9)


def test_scaled_data_are_the_same_bits_in_any_units():
    """The optimiser's data: u / su rounded to 2**-30, the same numbers
    whatever the units, and within half a step of the exact quotient."""
    from sandwichctl.identification._data import scale, scaled
    x = 3.3 * np.random.default_rng(7).standard_normal(5000) + 0.2
    ref = scaled(x, scale(x))
    for k in (1e-4, 3.7e-3, 1.0, 12.5, 1e4):
        np.testing.assert_array_equal(scaled(x * k, scale(x * k)), ref)
    assert np.max(np.abs(ref - x / scale(x))) <= 2.0 ** -31


def test_units_do_not_steer_a_sensitive_search():
    """A random plant (family 7, square wave plus sine, SNR 5) whose
    search ended 3.7 validation points apart under scalings of 1e-4 and
    1e4 before the scaled data were rounded: now the same model."""
    from sandwichctl.data import family_specs
    spec = {s['seed']: s for s in family_specs(80, seed=7)}[1828830875]
    case = random_case(**spec)
    u_val = np.std(case.u) * np.random.default_rng(5).standard_normal(2000)
    fits, models = [], []
    for su, sy in [(1.0, 1.0), (1e4, 1e-4), (1e-4, 1e4)]:
        # a hard case (SNR 5): the identifier flags its weak parameters;
        # without the integrating searches they ask for (the same rounded
        # data go into them), to keep the test short
        with pytest.warns(sw.IdentificationWarning, match='poorly determined'):
            res = sw.identify(case.u * su, case.y * sy, **case.orders,
                              integrators=0)
        y_val = res.model.simulate(u_val * su).outputs / sy
        fits.append(sw.fit_percent(case.plant.simulate(u_val).outputs,
                                   y_val))
        models.append(res)
    assert max(fits) - min(fits) < 1e-9
    for res in models[1:]:
        assert res.fit == pytest.approx(models[0].fit, abs=1e-9)


def test_negative_gain_identified_as_well_as_positive(paper_noisy):
    plant, u, y = paper_noisy
    pos = sw.identify(u, y, **plant.orders)
    neg = sw.identify(u, -y, **plant.orders)
    assert neg.success and neg.model.gain_sign == -1
    assert neg.model.coefficients['d'][0] == -1.0
    assert neg.fit == pytest.approx(pos.fit, abs=1e-6)
    assert sw.parameter_error(neg.theta, plant.theta) == pytest.approx(
        sw.parameter_error(pos.theta, plant.theta), abs=1e-6)
    np.testing.assert_allclose(neg.model.simulate(u).outputs,
                               -pos.model.simulate(u).outputs, atol=1e-9)


def test_orders_are_never_trimmed():
    """A structure larger than the plant's: the returned model keeps every
    asked-for coefficient, even where the data would allow fewer."""
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(2000, seed=23)
    y = plant.simulate(u).outputs
    orders = dict(na=3, nb=1, nc=2, nd=2, q1=1, q2=1)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        res = sw.identify(u, y, **orders)
    assert res.model.orders == orders
    assert res.theta.size == 3 + 1 + 2 + 2 + 4


def test_structure_that_cannot_be_estimated_raises():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(120, seed=24)
    y = plant.simulate(u).outputs
    with pytest.raises(ValueError, match='too few'):
        sw.identify(u, y, na=3, nb=3, nc=3, nd=3)


@pytest.mark.parametrize('seed', [101, 102, 103, 104])
def test_never_worse_than_the_linear_baseline(seed):
    """The sandwich nests the linear model of the same total orders: its
    estimation cost is at most the linear output-error fit's, and the
    library's own identify_linear agrees with the baseline it reports."""
    case = random_case(seed, n=2000, snr=20)
    o = case.orders
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        res = sw.identify(case.u, case.y, **o, integrators=0)
    lin = sw.identify_linear(case.u, case.y, nb=o['nb'] + o['nd'] + 1,
                             nf=o['na'] + o['nc'], nk=o['q1'] + o['q2'])
    assert res.cost <= res.linear['cost'] * (1 + 1e-9)
    assert res.fit >= res.linear['fit'] - 1e-9
    assert res.linear['fit'] == pytest.approx(lin.fit, abs=0.5)
    assert np.all(np.abs(res.model.L1.poles()) < 1)
    assert np.all(np.abs(res.model.L2.poles()) < 1)


def test_integrating_plant():
    """A pole at z = 1 in L1 (a speed command in, a position out): found by
    'auto' and declared, exactly at 1, and the model simulates."""
    case = random_case(105, n=4000, snr=100, integrating=True)
    o = case.orders
    for integrators in ('auto', 1):
        with warnings.catch_warnings():
            warnings.simplefilter('ignore', RuntimeWarning)
            res = sw.identify(case.u, case.y, **o, integrators=integrators)
        assert res.integrators == {'L1': 1, 'L2': 0}
        den = res.model.L1.den[0][0]
        assert abs(np.polyval(den, 1.0)) < 1e-12 * np.sum(np.abs(den))
        assert res.fit > res.linear['fit'] - 1e-9 and res.fit > 80
        y_hat = res.model.simulate(case.u).outputs
        assert sw.fit_percent(case.y, y_hat) == pytest.approx(res.fit,
                                                               abs=1e-6)


def test_auto_does_not_give_an_ordinary_plant_an_integrator():
    """A noise-free ordinary plant with a slow pole (0.94; family 5 of
    the robustness benchmark): the fit without an integrator stalled
    above the fit with one, which 'auto' then chose. Restarted from the
    integrating model, it ends below it, and the plant keeps no pole at
    z = 1."""
    from sandwichctl.data import family_specs
    spec = {s['seed']: s for s in family_specs(80, seed=5)}[288195210]
    case = random_case(**spec)
    o = case.orders
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        res = sw.identify(case.u, case.y, **o)
        one = sw.identify(case.u, case.y, **o, integrators=1)
    assert res.integrators == {'L1': 0, 'L2': 0}
    assert np.max(np.abs(np.r_[res.model.L1.poles(),
                               res.model.L2.poles()])) < 0.999
    assert res.cost < one.cost
    assert res.cost <= res.linear['cost'] * (1 + 1e-9)


def test_an_integrator_after_the_play_is_found_by_default():
    """A pole at z = 1 in L2 (a valve with play driving a cylinder):
    the default integrator_block='auto' searches both blocks and keeps
    the integrator in L2; so does integrators=1, and the message says
    where it went. The block L1 alone fits worse."""
    case = random_case(0, n=3000, snr=100, integrating='L2')
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        res = sw.identify(case.u, case.y, **case.orders)
        one = sw.identify(case.u, case.y, **case.orders, integrators=1)
        l1 = sw.identify(case.u, case.y, **case.orders,
                         integrator_block='L1')
    assert res.integrators == {'L1': 0, 'L2': 1}
    assert "integrators='auto' chose 1 in L2" in res.message
    assert "integrator_block='auto' chose 1 in L2" in one.message
    np.testing.assert_array_equal(one.theta, res.theta)
    den = res.model.L2.den[0][0]
    assert abs(np.polyval(den, 1.0)) < 1e-12 * np.sum(np.abs(den))
    assert res.success and res.cost <= res.linear['cost'] * (1 + 1e-9)
    assert l1.integrators == {'L1': 1, 'L2': 0}
    assert res.cost < l1.cost


def test_integrator_block_l2():
    case = random_case(105, n=3000, snr=100, integrating=True)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        res = sw.identify(case.u, case.y, **case.orders, integrators=1,
                          integrator_block='L2')
    assert res.integrators == {'L1': 0, 'L2': 1}
    den = res.model.L2.den[0][0]
    assert abs(np.polyval(den, 1.0)) < 1e-12 * np.sum(np.abs(den))
    assert res.cost <= res.linear['cost'] * (1 + 1e-9)


@pytest.mark.parametrize('y, match', [
    (np.zeros(2000), 'y is constant'), (np.full(2000, 3.0), 'y is constant'),
])
def test_constant_output_is_refused(y, match):
    u = sw.examples.paper_input(2000, seed=25)
    with pytest.raises(ValueError, match=match):
        sw.identify(u, y, na=2, nb=0, nc=2, nd=1)


def test_output_unrelated_to_input_is_not_a_success():
    rng = np.random.default_rng(26)
    u, y = rng.standard_normal(3000), rng.standard_normal(3000)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', RuntimeWarning)
        res = sw.identify(u, y, na=2, nb=0, nc=2, nd=1)
    assert not res.success
    assert 'does not explain the data' in res.message


def test_recursive_method_with_unstable_estimate_is_not_a_success():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(500, seed=27)
    y = plant.simulate(u).outputs
    theta0 = plant.theta.copy()
    theta0[:2] = [0.0, 1.5]                # L2 poles at +-1.22j: unstable
    res = sw.identify(u, y, **plant.orders, method='gradient', mu=1e-12,
                      theta0=theta0)
    assert not res.success
    assert 'unstable' in res.message


def test_a_zero_on_the_search_bound_is_not_a_success():
    """A zero pressed against |z| = zero_radius marks a degenerate optimum
    (the zero trades against the slope and the width): success=False,
    and the message says which block; the same model a little inside is
    judged normally."""
    from sandwichctl.identification._lm import lm
    from sandwichctl.identification._problem import Problem
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.6], b=[0.3, 0.1], c=[-0.5], d=[0.2, 0.05], m1=1.0, m2=1.0,
        D1=0.1, D2=0.1, dt=1)
    u = sw.examples.paper_input(800, seed=4)
    y = plant.simulate(u).outputs
    prob = Problem(u, y, plant.orders)
    st = prob.st
    phi = prob.phi_of_model(plant)
    verdicts = {}
    for radius in (st.zero_radius * 0.995, st.zero_radius * 0.5):
        far = phi.copy()
        far[st.im + 4] = -radius            # L1: 1 - r q^-1, zero at r
        out = lm(st, far, prob.u, prob.y, max_iter=0)
        out['converged'] = True
        with warnings.catch_warnings():
            # the degenerate optimum is poorly determined too; this test
            # is about the verdict, not that warning
            warnings.simplefilter('ignore', sw.IdentificationWarning)
            verdicts[radius] = prob.result(out, 'oe')
    at_bound, inside = verdicts.values()
    assert not at_bound.success
    assert 'zero of L1 ended on the search bound' in at_bound.message
    assert 'search bound' not in inside.message


def test_result_shows_the_verdict_at_a_glance(paper_noisy):
    plant, u, y = paper_noisy
    res = sw.identify(u, y, **plant.orders, name='stage')
    text = str(res)
    for part in ('fit on the estimation data', 'linear output-error baseline',
                 'backlash significance', 'Ljung-Box', '+-'):
        assert part in text
    assert res.significance['p_value'] < 1e-6      # the backlash matters
    assert res.model.name == 'stage'
    assert np.all(np.isfinite(res.std)) and np.all(res.std > 0)


def test_identify_linear_is_the_reported_baseline_model(paper_noisy):
    plant, u, y = paper_noisy
    res = sw.identify(u, y, **plant.orders)
    import control as ct
    y_lin = ct.forced_response(res.linear['model'], inputs=u).outputs
    assert sw.fit_percent(y, y_lin) == pytest.approx(res.linear['fit'],
                                                     abs=1e-6)


def test_a_degenerate_best_start_is_retried_from_the_next_one():
    """A noise-free random plant (family 3 of the robustness benchmark)
    whose best converged start ends with a zero of L2 on the search bound:
    the next converged start, polished the same way, recovers the plant,
    and the result is a success with no zero on the bound."""
    from sandwichctl.data import family_specs
    from sandwichctl.identification._problem import Problem
    spec = {s['seed']: s for s in family_specs(80, seed=3)}[849571562]
    case = random_case(**spec)
    res = sw.identify(case.u, case.y, **case.orders)
    assert res.success, res.message
    prob = Problem(case.u, case.y, case.orders, sign=res.model.gain_sign)
    assert not prob.st.zeros_at_bound(prob.phi_of_model(res.model))
    yhat = res.model.simulate(case.u).outputs
    assert np.max(np.abs(yhat - case.y)) < 1e-6 * np.std(case.y)


def test_the_result_says_how_much_of_x_lies_beyond_the_crossing():
    """The crossing of the slope lines in u's units and the share of
    samples beyond it; printed when it is a tenth or more."""
    import control as ct
    case = random_case(3, snr=np.inf, n=1500, input_kind='square+sine')
    res = sw.identify(case.u, case.y, **case.orders)
    bl = res.model.backlash
    assert res.crossing['x'] == pytest.approx(bl.crossing, rel=1e-9)
    x = ct.forced_response(res.model.L1, U=case.u).outputs
    beyond = x < bl.crossing if bl.m1 < bl.m2 else x > bl.crossing
    assert res.crossing['share'] == pytest.approx(np.mean(beyond), abs=2e-3)
    assert res.crossing['share'] >= 0.1
    assert 'beyond the crossing' in str(res)
    res.crossing = dict(res.crossing, share=0.05)
    assert 'beyond the crossing' not in str(res)


@pytest.fixture(scope='module')
def readme_example():
    """The README's example: the paper's plant, N = 5,000, SNR 46.5; the
    output noise-free and noisy."""
    import control as ct
    L1 = ct.tf([1.5, 0], [1, 0.1, 0.2], 1)
    L2 = ct.tf([2, -0.1], [1, 1.2, 0.32], 1)
    plant = sw.SandwichSystem(L1, sw.Backlash(m1=1, m2=1.2, D1=0.5, D2=0.6),
                              L2)
    u = 0.7 * np.random.default_rng(0).standard_normal(5000)
    y = plant.simulate(u).outputs
    return plant, u, y, sw.examples.add_noise(y, snr=46.5, seed=1)


#: The recursive methods as the README calls the paper's one.
RECURSIVE = {'bundle': dict(eta0=0.015, k1=6), 'gradient': {}, 'rpem': {}}


@pytest.mark.parametrize('method', list(RECURSIVE))
def test_a_recursive_fit_below_the_linear_baseline_is_not_a_success(
        readme_example, method):
    """Issue 24: on the README's example each recursive method ends below
    the linear output-error fit of the same total orders (bundle 61.4 %,
    gradient 28.9 %, rpem -13.4 %, against 63.6 %). The verdict says so,
    with both fits, and points to 'oe'; the baseline is the one 'oe'
    reports (without integrators, which 'auto' does not add here)."""
    plant, u, _, y = readme_example
    res = sw.identify(u, y, **plant.orders, method=method,
                      **RECURSIVE[method])
    oe = sw.identify(u, y, **plant.orders)
    assert oe.linear['integrators'] == res.linear['integrators'] == 0
    for key in ('fit', 'cost', 'cost_scaled', 'n_params'):
        assert res.linear[key] == oe.linear[key]
    y_hat = res.model.simulate(u).outputs
    assert res.fit == pytest.approx(sw.fit_percent(y, y_hat), abs=1e-9)
    assert res.fit < res.linear['fit'] - 1
    assert not res.success
    assert (f"the fit is worse than the linear baseline ({res.fit:.3g} % < "
            f"{res.linear['fit']:.3g} %): use method='oe'") in res.message
    assert 'linear output-error baseline (same total orders): 63.62 %' \
        in str(res)
    assert oe.success and oe.fit > oe.linear['fit']     # 'oe' as before


def test_a_recursive_fit_above_the_linear_baseline_stays_a_success(
        readme_example):
    """Noise-free, the README's bundle run fits 98.5 % against the linear
    66.1 %: a success; and refined from the noisy run's estimate (61.4 %),
    the refinement passes the baseline (63.6 %) and the same check."""
    plant, u, y, y_noisy = readme_example
    res = sw.identify(u, y, **plant.orders, method='bundle',
                      **RECURSIVE['bundle'])
    assert res.success, res.message
    assert res.fit > 98 and res.linear['fit'] == pytest.approx(66.1, abs=0.1)
    with warnings.catch_warnings():
        # d1 is poorly determined at this SNR; not what this test is about
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        refined = sw.identify(u, y_noisy, **plant.orders, method='bundle',
                              refine=True, **RECURSIVE['bundle'])
    assert refined.success, refined.message
    assert refined.fit > refined.linear['fit'] + 20


def test_the_linear_check_goes_through_verdict():
    """One check for every method: a cost above the baseline's fails, at
    the same tolerance for all; a method other than 'oe' is pointed to it;
    ``min_fit=None`` leaves the fit to a verdict made before."""
    from sandwichctl.identification.result import verdict
    linear = {'fit': 63.6, 'cost_scaled': 2.0}
    assert verdict(fit=70.0, linear=linear, cost_scaled=2.0) == []
    assert verdict(fit=70.0, linear=linear,
                   cost_scaled=2.0 * (1 + 1e-10)) == []
    oe, = verdict(fit=61.4, linear=linear, cost_scaled=2.1)
    bundle, = verdict(fit=61.4, linear=linear, cost_scaled=2.1,
                      method='bundle')
    assert oe.check == bundle.check == 'linear' and oe.fatal
    assert oe.text == ("the fit is worse than the linear baseline (61.4 % < "
                       "63.6 %)")
    assert bundle.text.startswith(oe.text + ": use method='oe'")
    assert [f.check for f in verdict(fit=3.0, linear=linear, cost_scaled=9,
                                     method='rpem')] == ['fit', 'linear']
    assert [f.check for f in verdict(fit=3.0, min_fit=None, linear=linear,
                                     cost_scaled=9)] == ['linear']


def test_auto_integrators_never_below_the_integrator_free_linear_fit():
    """integrators='auto' on a record without an integrator (a slow pole
    at 0.97 makes it try one): the result is never below the linear
    output-error fit of the same orders without an integrator."""
    plant = sw.SandwichSystem.from_coefficients(
        a=[-0.97], b=[1.0], c=[-0.5], d=[1.0], m1=1.0, m2=1.0, D1=0.2,
        D2=0.2, dt=1)
    u = sw.examples.paper_input(1500, seed=3)
    y = sw.examples.add_noise(plant.simulate(u).outputs, snr=30, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, y, **plant.orders)
    o = plant.orders
    lin0 = sw.identify_linear(u, y, nb=o['nb'] + o['nd'] + 1,
                              nf=o['na'] + o['nc'], nk=o['q1'] + o['q2'],
                              integrators=0)
    assert res.fit >= lin0.fit - 1e-6


def test_an_optimiser_stopped_at_max_iter_says_how_to_let_it_run_on():
    """A search cut short by max_iter fails with the remedy in its
    message, and following it gives a converged success."""
    # SNR 20: what is left after 2 iterations of a run is several times the
    # share that counts as converged (`_lm.CONVERGED`); at SNR 100 it sits
    # near that share, on one side or the other by the machine's rounding
    case = sw.data.random_case(0, n=2000, snr=20)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        short = sw.identify(case.u, case.y, **case.plant.orders, max_iter=2,
                            tol=1e-15)
        full = sw.identify(case.u, case.y, **case.plant.orders)
    assert not short.success
    assert "did not converge (a larger max_iter lets it run on)" in \
        short.message
    assert "stopped at max_iter = 2" in short.message
    assert full.success, full.message
    assert full.fit > short.fit
