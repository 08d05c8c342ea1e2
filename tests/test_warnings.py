"""Warnings have their own categories, point at the user's line, and
speak the user's language.

A warning issued deep inside the package must be reported at the line of
the user's code that called the package (``warning.filename`` is this
file), so that a notebook shows the cell line that caused it; it must be
filterable by category (``sw.SandwichWarning`` and its subclasses); and
its message must not mention private names.
"""

import inspect
import re
import warnings

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

UNSTABLE = sw.SandwichSystem(ct.tf([1, 0], [1, -3], 1),
                             sw.Backlash(1, 1, 0.1, 0.1),
                             ct.tf([1, 0], [1, 0.5], 1), name='unstable')


def _line():
    """Line number of the caller's next line."""
    return inspect.currentframe().f_back.f_lineno + 1




def test_categories_are_public_and_filterable():
    assert issubclass(sw.SandwichWarning, UserWarning)
    assert issubclass(sw.IdentificationWarning, sw.SandwichWarning)
    assert issubclass(sw.ExcitationWarning, sw.IdentificationWarning)
    assert issubclass(sw.SimulationWarning, sw.SandwichWarning)
    assert issubclass(sw.SimulationWarning, RuntimeWarning)
    for name in ('SandwichWarning', 'IdentificationWarning',
                 'ExcitationWarning', 'SimulationWarning'):
        assert name in sw.__all__


def test_divergence_warns_once_at_the_users_line():
    u = np.ones(2000)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        line = _line()
        resp = UNSTABLE.simulate(u)
    assert len(caught) == 1
    w = caught[0]
    assert w.category is sw.SimulationWarning
    assert w.filename == __file__ and w.lineno == line
    first = int(np.flatnonzero(~np.isfinite(resp.outputs))[0])
    assert f"from sample {first} " in str(w.message)
    assert 'unstable' in str(w.message)
    assert not re.search(r"\b_\w+", str(w.message))     # no private names


def test_an_overflowing_backlash_or_inverse_warns():
    # both returned infinities in silence (found by a fuzz of the API)
    x = np.linspace(-3, 3, 500)
    with pytest.warns(sw.SimulationWarning, match='from sample 0 on'):
        v = sw.backlash_response(x, 1e308, 1e308, 0, 0)
    assert not np.all(np.isfinite(v))
    with pytest.warns(sw.SimulationWarning, match="inverse's output"):
        sw.backlash_inverse_response(np.full(10, 1e308), 1e-10, 1e-10, 0.1,
                                     0.1)
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        sw.backlash_response(x, 1, 1, 0.1, 0.1)
        sw.backlash_inverse_response(x, 1, 1, 0.1, 0.1)


def test_no_warning_for_a_stable_simulation():
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        sw.examples.paper_plant().simulate(np.ones(2000))


def test_users_can_silence_or_raise_by_category():
    with warnings.catch_warnings():
        warnings.simplefilter('error')
        warnings.simplefilter('ignore', sw.SandwichWarning)
        UNSTABLE.simulate(np.ones(2000))
    with warnings.catch_warnings():
        warnings.simplefilter('error', sw.SimulationWarning)
        with pytest.raises(sw.SimulationWarning, match='diverged'):
            UNSTABLE.simulate(np.ones(2000))


def test_warning_through_another_public_function_points_at_the_user():
    """compare simulates the model inside the package (and refuses the
    diverged output): any warning on the way still points at our line."""
    u = np.ones(1000)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        line = _line() + 1                  # the line after the next
        with pytest.raises(ValueError, match='not finite'):
            sw.compare(UNSTABLE, u, np.zeros(1000), plot=False)
    ours = [w for w in caught if issubclass(w.category, sw.SandwichWarning)]
    assert all((w.filename, w.lineno) == (__file__, line) for w in ours)


def test_step_response_through_to_the_simulation():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        line = _line()
        sw.step_response(UNSTABLE, timepts=np.arange(1000))
    assert [(w.category, w.filename, w.lineno) for w in caught] == [
        (sw.SimulationWarning, __file__, line)]


def test_identification_warnings_use_the_categories():
    plant = sw.examples.paper_plant()
    u = 0.05 * sw.examples.paper_input(400, seed=0)   # inside the dead band
    rng = np.random.default_rng(0)
    y = plant.simulate(u).outputs + 1e-3 * rng.standard_normal(u.size)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        line = _line()
        sw.identify(u, y, **plant.orders)
    assert caught
    for w in caught:
        assert issubclass(w.category, sw.IdentificationWarning), w
        assert (w.filename, w.lineno) == (__file__, line), w


def test_unstable_closed_loop_warns_at_the_users_line():
    plant = sw.examples.paper_plant()
    ctrl = sw.TrackingController.from_feedback(ct.tf([5.0, 0], [1, -1], 1))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        line = _line()
        sw.closed_loop_response(plant, np.ones(3000), ctrl)
    assert [(w.category, w.filename, w.lineno) for w in caught] == [
        (sw.SimulationWarning, __file__, line)]
    assert 'closed loop of paper diverged' in str(caught[0].message)
