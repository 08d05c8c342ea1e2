"""Edge cases of the identification side met by a review of bad inputs:
data the held-out check cannot score, a model that fits exactly, a
bundle method whose QP fails at every sample, result methods asked for a
history an output-error result has not, and data helpers at their
documented limits."""

import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

PLANT = sw.examples.paper_plant()
O = PLANT.orders
U = sw.examples.paper_input(2400, seed=1)
Y = PLANT.simulate(U).outputs


def test_an_input_at_rest_for_most_of_the_record_skips_the_held_out_check():
    # the held-out refit on the leading 75 % saw a zero input: LinAlgError
    u = np.r_[np.zeros(2390), np.ones(10)]
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.ExcitationWarning)
        res = sw.identify(u, PLANT.simulate(u).outputs, **O)
    assert 'not cross-checked' in res.held_out['note']
    assert np.isfinite(res.fit)


def test_a_tiny_experiment_skips_the_held_out_check_without_numpy_noise():
    with warnings.catch_warnings():
        warnings.simplefilter('error')           # numpy's too
        res = sw.identify([(U, Y), (U[:1], Y[:1] + 5)], **O,
                          offsets='estimate')
    assert 'not cross-checked' in res.held_out['note']
    assert res.success


@pytest.mark.parametrize('u, y, orders', [
    (U, U, dict(O, q1=0, q2=0)),                   # y = u: exact
    (np.r_[np.zeros(1000), np.ones(1000)], None, O)])   # one step
def test_a_model_that_fits_exactly_is_not_worse_than_linear(u, y, orders):
    y = PLANT.simulate(u).outputs if y is None else y
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.ExcitationWarning)
        res = sw.identify(u, y, **orders)
    assert res.fit > 99.999999 and res.linear['fit'] > 99.999999
    assert res.success, res.message


def test_a_structure_without_poles_tries_no_integrator():
    # integrators='auto' fitted a linear model with one: numpy's
    # "negative dimensions" from a structure with nowhere to put it
    u = U[:600]
    y = PLANT.simulate(u).outputs
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, y, na=0, nb=1, nc=0, nd=1)
    assert res.integrators == {'L1': 0, 'L2': 0}
    assert np.isfinite(res.fit) and res.fit > 0
    with pytest.raises(ValueError, match='exceed the na . nc = 0 poles'):
        sw.identify(u, y, na=0, nb=1, nc=0, nd=1, integrators=1)


@pytest.mark.parametrize('at', [0, 3])
def test_an_impulse_from_rest_determines_a_linear_plant(at):
    # told "the input starts 24.5 of its standard deviations from zero"
    # and "a recurrence of 0 taps (as nothing does)": the impulse lay
    # before the first sample the recurrence test looked at
    G = ct.tf([0.5, 0.2], [1, -1.1, 0.3], 1)
    u = np.zeros(600)
    u[at] = 1.0
    res = sw.identify_linear(u, ct.forced_response(G, U=u).outputs, nb=2,
                             nf=2)
    assert res.success, res.message
    assert res.fit > 99.9999
    # at an operating point it is still told
    u = u + 5.0
    res = sw.identify_linear(u, ct.forced_response(G, U=u).outputs, nb=2,
                             nf=2)
    assert not res.success
    assert 'standard deviations from zero' in res.message


def test_an_impulse_through_a_sandwich_does_not_determine_it():
    # it moves the backlash in four samples: a model that fits it exactly
    # but validates at 77 % was a success
    u = np.r_[1.0, np.zeros(599)]
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.SandwichWarning)
        res = sw.identify(u, PLANT.simulate(u).outputs, **O)
    assert res.fit > 99.99
    assert not res.success
    assert "backlash moves in only 4 samples" in res.message
    assert "the 6 parameters of L1 and the backlash" in res.message


def test_bundle_qp_failures_are_told_once():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        res = sw.identify(U[:1200], 1e3 * Y[:1200], **O, method='bundle')
    told = [w for w in caught if 'bundle QP failed' in str(w.message)]
    assert len(told) == 1 and not res.success
    assert int(str(told[0].message).split(' at ')[1].split()[0]) > 100


def test_history_methods_refuse_a_result_without_history():
    res = sw.identify(U[:600], Y[:600], **O)
    for call in (lambda: res.parameter_error(PLANT.theta),
                 res.plot_convergence):
        with pytest.raises(ValueError, match='no history'):
            call()
    assert sw.parameter_error(res.theta, PLANT.theta) < 1e-3
    # a recursive result without one says why: it named the recursive
    # methods, the result's own
    est = sw.RecursiveIdentifier(**O, keep_history=False)
    est.update_many(U[:100], Y[:100])
    with pytest.raises(ValueError, match='ran with keep_history=False'):
        est.result().parameter_error(PLANT.theta)
    with pytest.raises(ValueError, match='saw no sample'):
        sw.RecursiveIdentifier(**O).result().plot_convergence()


def test_plot_convergence_checks_its_arguments():
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    res = sw.identify(U[:300], Y[:300], **O, method='gradient')
    with pytest.raises(ValueError, match='9 parameters'):
        res.plot_convergence(true_theta=[1, 2])
    for axes in (5, plt.subplots()[1], plt.subplots(1, 2)[1]):
        with pytest.raises(ValueError, match='9 matplotlib Axes'):
            res.plot_convergence(axes=axes)
    axes = res.plot_convergence(true_theta=PLANT.theta)
    assert res.plot_convergence(axes=axes) is not None
    plt.close('all')


def test_a_recursive_estimator_without_data_is_no_success():
    res = sw.RecursiveIdentifier(**O).result()
    assert not res.success and 'no samples' in res.message


@pytest.mark.parametrize('n', [2, 3, 4, 5])
def test_square_and_sine_is_drawn_at_its_shortest(n):
    for seed in range(20):
        s = sw.data.excitation('square+sine', n, seed)
        assert s.size == n and np.ptp(s) > 0


def test_square_and_sine_of_a_usual_length_is_unchanged():
    # the sine's amplitude is set from the square's spread as before
    # wherever the square switches (any record longer than 91 samples)
    s = sw.data.excitation('square+sine', 500, 3)
    rng = np.random.default_rng(3)
    raw = sw.data.synthetic._GENERATORS['square+sine'](500, rng)
    np.testing.assert_array_equal(s, sw.data.synthetic._unit(raw))


def test_a_drive_case_at_a_random_drive_sample_time():
    d = sw.data.random_drive(3)
    case = sw.data.drive_case(0, d['loop'], d['play'], n=400, dt=d['dt'],
                              **d['params'])
    assert case.dt == d['dt']
    default = sw.data.drive_case(0, n=400)
    assert default.dt == sw.data.DRIVE_DT


def test_an_input_offset_with_estimated_offsets_fails_without_a_crash():
    # J'J of an enormous range: numpy's SVD did not converge inside the
    # standard errors, and identify raised LinAlgError
    case = sw.data.random_case(2, n=3000, snr=20)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(case.u + 500, case.y, **case.plant.orders,
                          offsets='estimate')
    assert not res.success


def test_a_refine_dict_is_checked_before_the_recursive_run():
    """A key sw.refine does not take failed only after the whole recursive
    run, with refine()'s bare TypeError."""
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(300, seed=0)
    y = plant.simulate(u).outputs
    with pytest.raises(TypeError, match="refine=.*'foo'.*max_iter"):
        sw.identify(u, y, **plant.orders, method='rpem', refine={'foo': 1})


def test_the_coefficients_an_input_can_determine():
    from sandwichctl.identification._data import excitation_order
    t = np.arange(2000)
    sines = [np.sin(2 * np.pi * t / p) for p in (97.0, 31.0, 11.0)]
    assert excitation_order([sines[0]], 6) == 2
    assert excitation_order([sines[0] + 0.3], 6) == 3   # and a constant
    assert excitation_order([sum(sines) + 500], 8) == 7
    assert excitation_order([np.ones(2000)], 6) == 1
    assert excitation_order([np.zeros(2000)], 6) == 0
    step = np.r_[np.zeros(100), np.ones(1900)]          # its edge: all
    assert excitation_order([step], 6) == 6
    noise = np.random.default_rng(0).standard_normal(2000)
    assert excitation_order([noise], 10) == 10
    # a record at rest past the leading samples checked first
    assert excitation_order([np.r_[np.zeros(30000), noise]], 10) == 10
    # a sinusoid switched on from rest: its switch is a step's transient
    assert excitation_order([np.r_[np.zeros(100), sines[0]]], 6) == 6
    # in any units (no overflow nor underflow at the float's ends)
    assert excitation_order([noise * 1e300], 10) == 10
    assert excitation_order([sines[0] * 1e-300], 6) == 2
    # every experiment must satisfy the recurrence: one sinusoid in each
    # of three is three
    assert excitation_order([s[:500] for s in sines], 8) == 6


def test_a_single_sinusoid_does_not_determine_a_second_order_l1():
    # L1 of the paper's plant has na + nb + 1 = 3 coefficients; one
    # sinusoid fixes its phase at one frequency only (its gain trades
    # with m and D), so the fit, however close, is no success
    u = 3 * np.sin(2 * np.pi * np.arange(2400) / 97.0)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, PLANT.simulate(u).outputs, **O)
    assert res.fit > 90 and not res.success
    assert res.message.startswith("the input satisfies a recurrence of 2 "
                                  "taps (as 1 sinusoid does), so it "
                                  "determines at most 2 of the 3 "
                                  "coefficients of L1")
    # two sinusoids can determine four: the check is silent on them
    u = u + 2 * np.sin(2 * np.pi * np.arange(2400) / 23.0)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, PLANT.simulate(u).outputs, **O)
    assert 'the input satisfies a recurrence' not in res.message


def test_a_linear_fit_needs_as_many_taps_as_coefficients():
    u = 3 * np.sin(2 * np.pi * np.arange(1000) / 97.0)
    y = np.convolve(u, [0.0, 0.5, 0.3, 0.1])[:u.size]
    first = sw.identify_linear(u, y, nb=1, nf=1)     # gain and phase
    assert 'the input satisfies a recurrence' not in first.message
    res = sw.identify_linear(u, y, nb=2, nf=2)
    assert not res.success
    assert res.message.startswith("the input satisfies a recurrence of 2 "
                                  "taps (as 1 sinusoid does), so it "
                                  "determines at most 2 of the 4 "
                                  "coefficients of the model")


def test_an_input_rounded_to_a_grid_satisfies_its_recurrence_up_to_it():
    from sandwichctl.identification._data import excitation_order, quantum
    t = np.arange(3000)
    rng = np.random.default_rng(1)

    def rounded(u, bits):
        step = np.ptp(u) / 2 ** bits
        return step * np.round(u / step)

    sine = np.sin(2 * np.pi * t / 97.0 + 0.4)
    fast = np.sin(2 * np.pi * t / 20.0 + 0.4)
    assert excitation_order([rounded(sine, 16)], 6) == 2
    for bits in (8, 12, 16):
        assert excitation_order([rounded(fast, bits)], 6) == 2
    assert excitation_order([rounded(fast + 0.3, 16) * 1e-3], 6) == 3
    # where the grid is too coarse to tell a sinusoid's curvature from
    # the rounding, the exact test stands: a slow one is not caught, and
    # a multisine of slow sinusoids is no recurrence of fewer taps
    assert excitation_order([rounded(sine, 10)], 6) == 6
    slow = sum(np.sin(2 * np.pi * t / p + rng.uniform(0, 6))
               for p in rng.uniform(200, 2000, 8))
    assert excitation_order([rounded(slow, 12)], 8) == 8
    # the grid is found in any units and with its offset; not where the
    # values are off it, nor on a grid of a few levels
    u = rounded(sine, 16)
    assert quantum(u) == pytest.approx(np.ptp(sine) / 2 ** 16, rel=1e-9)
    assert quantum(7.5 + 1e-4 * u) == pytest.approx(
        1e-4 * np.ptp(sine) / 2 ** 16, rel=1e-6)
    assert quantum(sine) == 0.0
    assert quantum(np.sign(rng.standard_normal(3000))) == 0.0
    # inputs that excite stay exciting when rounded: noise, random steps,
    # a binary sequence, a sinusoid switched on from rest
    noise = rng.standard_normal(3000)
    assert excitation_order([rounded(noise, 12)], 10) == 10
    steps = np.repeat(rng.uniform(-1, 1, 60), 50)
    assert excitation_order([rounded(steps, 16)], 10) == 10
    assert excitation_order([np.sign(noise)], 10) == 10
    switched = np.r_[np.zeros(100), np.cos(2 * np.pi * t / 97.0)]
    assert excitation_order([rounded(switched, 16)], 6) == 6


def test_a_single_sinusoid_from_a_16_bit_converter_is_no_success():
    # rounded to the converter's grid, the sinusoid satisfies its
    # recurrence only to within the rounding: it still determines two
    # coefficients of L1, not three
    u = 3 * np.sin(2 * np.pi * np.arange(2400) / 97.0)
    step = np.ptp(u) / 2 ** 16
    u = step * np.round(u / step)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore', sw.IdentificationWarning)
        res = sw.identify(u, PLANT.simulate(u).outputs, **O)
    assert not res.success
    assert res.message.startswith("the input satisfies a recurrence of 2 "
                                  "taps (as 1 sinusoid does)")
