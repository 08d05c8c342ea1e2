"""Each method's options (`_options`): one frozen dataclass per method with
its defaults and checks, and an option or argument of `identify` that
does not apply to the chosen method raises, naming the method."""

import dataclasses

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.identification._options import (
    OEOptions, BundleOptions, GradientOptions, RPEMOptions, method_options)
from sandwichctl.identification.recursive import DEFAULTS


@pytest.fixture(scope='module')
def data():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(800, seed=2)
    return plant, u, plant.simulate(u).outputs


@pytest.mark.parametrize('method, kwargs, exc', [
    ('bundle', dict(integrators=1), TypeError),
    ('rpem', dict(integrators='auto'), TypeError),
    ('gradient', dict(integrator_block='L2'), TypeError),
    ('bundle', dict(initial_state='estimate'), TypeError),
    ('rpem', dict(offsets='estimate'), ValueError),
    ('oe', dict(theta0=np.ones(9)), TypeError),
    ('oe', dict(refine=True), TypeError),
    ('oe', dict(eta0=0.1), TypeError),
    ('bundle', dict(hops=2), TypeError),
    ('rpem', dict(k1=3), TypeError),
])
def test_an_option_that_does_not_apply_raises(data, method, kwargs, exc):
    plant, u, y = data
    with pytest.raises(exc, match=f"method='{method}'"):
        sw.identify(u, y, **plant.orders, method=method, **kwargs)


def test_options_are_frozen_and_checked():
    opt = OEOptions()
    with pytest.raises(dataclasses.FrozenInstanceError):
        opt.hops = 2
    assert OEOptions(widths=[0.1]).widths == (0.1,)
    with pytest.raises(ValueError, match='integrator_block'):
        OEOptions(integrator_block='L3')
    assert OEOptions().integrator_block == 'auto'
    assert {OEOptions(integrator_block=b).integrator_block
            for b in ('auto', 'L1', 'L2')} == {'auto', 'L1', 'L2'}
    with pytest.raises(ValueError, match='eta0'):
        BundleOptions(eta0=2.0)
    with pytest.raises(ValueError, match='lam0'):
        RPEMOptions(lam0=1.5)
    with pytest.raises(ValueError, match='nonsmooth'):
        GradientOptions(nonsmooth='skip', skip_nonsmooth=False)
    assert GradientOptions(skip_nonsmooth=False).nonsmooth == 'subgradient'


def test_one_source_of_defaults():
    """The recursive identifier's defaults are the dataclasses' and the
    options a result reports are those of the search."""
    for method, cls in (('bundle', BundleOptions),
                        ('gradient', GradientOptions),
                        ('rpem', RPEMOptions)):
        fields = {f.name: f.default for f in dataclasses.fields(cls)}
        assert DEFAULTS[method] == fields
    assert method_options('oe', {}) == OEOptions()
    search = OEOptions().search()
    assert list(search)[:2] == ['widths', 'screen_iter']
    assert not set(search) & set(OEOptions.ARGUMENTS)
