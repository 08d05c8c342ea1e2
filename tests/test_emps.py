"""The EMPS data shipped with the package: `sw.data.load_emps` gives the two
experiments as python-control records, as described in its module."""

import sys
from importlib import resources
from pathlib import Path

import control as ct
import numpy as np
import pytest

import sandwichctl as sw

if sys.version_info >= (3, 11):
    import tomllib
else:                                          # pragma: no cover
    tomllib = None


@pytest.fixture(scope='module')
def emps():
    return sw.data.load_emps()


def test_two_records_of_4969_samples(emps):
    est, val, note = emps                      # unpacks like a tuple
    for rec in (est, val):
        assert isinstance(rec, ct.TimeResponseData)
        assert rec.ninputs == 1 and rec.noutputs == 1
        assert rec.time.shape == rec.inputs.shape == rec.outputs.shape \
            == (4969,)
        assert np.all(np.isfinite(rec.inputs))
        assert np.all(np.isfinite(rec.outputs))
        np.testing.assert_allclose(np.diff(rec.time), 0.005, rtol=1e-9)
        assert rec.time[0] == 0
        assert rec.input_labels == ['force [V]']
        assert rec.output_labels == ['velocity [m/s]']
    assert emps.dt == 0.005
    assert 'EMPS' in note and 'No mean removal' in note
    assert not np.allclose(est.inputs, val.inputs)


def test_data_as_measured(emps):
    """No mean removal, no scaling: the force reference keeps its offset."""
    est, val, _ = emps
    assert est.inputs.mean() == pytest.approx(-0.0922, abs=1e-3)
    assert est.inputs.std() == pytest.approx(1.537, abs=1e-2)
    assert np.abs(est.outputs).max() < 0.5             # m/s
    data = sw.as_experiments([est, val])
    assert len(data) == 2 and data.dt == pytest.approx(0.005)
    np.testing.assert_array_equal(data.u[1], val.inputs)


def test_file_ships_with_the_package():
    path = resources.files('sandwichctl.data').joinpath('emps.npz')
    assert path.is_file()
    pyproject = Path(__file__).resolve().parents[1] / 'pyproject.toml'
    if tomllib is None:
        pytest.skip('tomllib needs Python 3.11')
    config = tomllib.loads(pyproject.read_text())
    patterns = config['tool']['setuptools']['package-data']['sandwichctl']
    assert any(Path('data/emps.npz').match(p) for p in patterns)


def test_repr_is_short(emps):
    text = repr(emps)
    assert text == ("EmpsData: estimation (4969 samples) and validation "
                    "(4969 samples) experiments, dt = 0.005 s; input "
                    "'force [V]', output 'velocity [m/s]'")
