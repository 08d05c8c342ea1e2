"""Tests of the JSON model format: exact round trips and clear errors."""

import io
import json
import warnings

import numpy as np
import pytest

import sandwichctl as sw


def _models():
    rng = np.random.default_rng(11)
    yield sw.examples.paper_plant()
    # digits that do not survive a round trip through few-digit decimals
    yield sw.SandwichSystem.from_coefficients(
        a=rng.uniform(-0.3, 0.3, 3), b=rng.uniform(0.5, 2, 2),
        c=[0.5 / 3], d=rng.uniform(0.5, 2, 3), m1=np.pi, m2=np.e,
        D1=1 / 3, D2=2 ** -40, q1=2, q2=0, dt=0.001, name='random')
    yield sw.SandwichSystem.from_coefficients(
        a=[], b=[-1.7], c=[], d=[-0.3], m1=1.0, m2=2.0, D1=0.0, D2=0.1,
        q1=0, q2=3, dt=True)


@pytest.mark.parametrize('model', list(_models()))
def test_round_trip_is_bitwise(model, tmp_path):
    path = tmp_path / 'model.json'
    sw.save_model(model, path)
    loaded = sw.load_model(path)
    assert isinstance(loaded, sw.SandwichSystem)
    saved_co, loaded_co = model.coefficients, loaded.coefficients
    assert saved_co.keys() == loaded_co.keys()
    for key in saved_co:
        np.testing.assert_array_equal(loaded_co[key], saved_co[key])
        assert (np.asarray(loaded_co[key]).tobytes()
                == np.asarray(saved_co[key]).tobytes())
    assert loaded.theta.tobytes() == model.theta.tobytes()
    assert loaded.orders == model.orders
    assert loaded.dt == model.dt and type(loaded.dt) is type(model.dt)
    u = sw.examples.paper_input(500, seed=12)
    assert (loaded.simulate(u, internal=True).outputs.tobytes()
            == model.simulate(u, internal=True).outputs.tobytes())


def test_round_trip_from_transfer_functions(tmp_path):
    import control as ct
    model = sw.SandwichSystem(
        ct.tf([0.7, 0.2, 0], [1, -0.3, 0.02, 0], 0.01),
        sw.Backlash(0.9, 1.1, 0.05, 0.07), ct.tf([1.3], [1, 0.4], 0.01),
        name='motor', inputs='voltage', outputs='speed')
    sw.save_model(model, tmp_path / 'm.json')
    loaded = sw.load_model(tmp_path / 'm.json')
    assert loaded.name == 'motor'
    assert loaded.input_labels == ['voltage']
    assert loaded.output_labels == ['speed']
    assert loaded.theta.tobytes() == model.theta.tobytes()
    u = sw.examples.paper_input(300, seed=13)
    assert (loaded.simulate(u).outputs.tobytes()
            == model.simulate(u).outputs.tobytes())


def test_format_on_disk(tmp_path):
    path = tmp_path / 'paper.json'
    sw.save_model(sw.examples.paper_plant(), path,
                  metadata={'source': 'Section 5', 'seed': np.int64(3),
                            'theta0': sw.examples.PAPER_THETA0})
    data = json.loads(path.read_text())
    assert data == {
        'format': 'sandwichctl.SandwichSystem', 'version': 1,
        'name': 'paper', 'dt': 1, 'inputs': 'u', 'outputs': 'y',
        'a': [0.1, 0.2], 'b': [1.5], 'q1': 1, 'c': [1.2, 0.32],
        'd': [2.0, -0.1], 'q2': 1, 'm1': 1.0, 'm2': 1.2, 'D1': 0.5,
        'D2': 0.6,
        'metadata': {'source': 'Section 5', 'seed': 3,
                     'theta0': [0, 0, 0, 0, 0.1, 0.1, 0.1, 0.1, 0.0]}}
    _, meta = sw.load_model(path, return_metadata=True)
    assert meta == data['metadata']


def test_dt_true_and_generic_name(tmp_path):
    model = sw.SandwichSystem.from_theta(sw.examples.PAPER_THETA0 + 0.5,
                                         na=2, nb=0, nc=2, nd=1)
    assert model.dt is True
    buffer = io.StringIO()
    sw.save_model(model, buffer)
    data = json.loads(buffer.getvalue())
    assert data['dt'] is True
    assert data['name'] is None              # 'sys[i]' is not kept
    loaded = sw.load_model(io.StringIO(buffer.getvalue()))
    assert loaded.dt is True
    assert loaded.name != model.name and loaded.name.startswith('sys[')


def _valid():
    buffer = io.StringIO()
    sw.save_model(sw.examples.paper_plant(), buffer)
    return json.loads(buffer.getvalue())


def _load(data):
    return sw.load_model(io.StringIO(json.dumps(data)))


@pytest.mark.parametrize('version, hint', [
    (2, 'upgrade sandwichctl'), (0, 'damaged'), ('1', 'damaged'),
    (None, 'damaged')])
def test_wrong_version(version, hint):
    data = _valid()
    data['version'] = version
    with pytest.raises(ValueError, match=rf"format version {version!r}, but"
                                         rf" this sandwichctl reads version "
                                         rf"1; .*{hint}"):
        _load(data)


@pytest.mark.parametrize('key', ['version', 'dt', 'a', 'd', 'q2', 'D1',
                                 'name'])
def test_missing_key(key):
    data = _valid()
    del data[key]
    with pytest.raises(ValueError, match=rf"missing the key\(s\) "
                                         rf"\['{key}'\]"):
        _load(data)


def test_optional_keys_may_be_absent():
    data = _valid()
    for key in ('inputs', 'outputs', 'metadata'):
        del data[key]
    model, meta = sw.load_model(io.StringIO(json.dumps(data)),
                                return_metadata=True)
    assert meta == {} and model.input_labels == ['u']


def test_not_a_model_file(tmp_path):
    with pytest.raises(ValueError, match=r"not a sandwichctl model file"):
        _load({'hello': 1})
    with pytest.raises(ValueError, match=r"not a sandwichctl model file"):
        _load([1, 2])
    path = tmp_path / 'bad.json'
    path.write_text('{"format": ')
    with pytest.raises(ValueError, match=r"bad.json' is not valid JSON"):
        sw.load_model(path)


@pytest.mark.parametrize('key, value, message', [
    ('b', [0.0, 1.0], r"b\[0\] is 0"),
    ('m1', -1.0, r"m1 must be a finite number > 0"),
    ('a', 0.1, r"'a' must be a list of numbers"),
    ('dt', 'fast', r"'dt' must be a positive number or true"),
    ('dt', -1, r"'dt' must be a positive number or true"),
    ('q1', 1.5, r"'q1' must be an integer"),
    ('metadata', [1], r"'metadata' must be a JSON object"),
])
def test_invalid_contents(key, value, message):
    data = _valid()
    data[key] = value
    with pytest.raises(ValueError, match=message):
        _load(data)


def test_save_errors(tmp_path):
    plant = sw.examples.paper_plant()
    with pytest.raises(TypeError, match=r"model must be a sandwichctl."
                                        r"SandwichSystem .*; got Backlash"):
        sw.save_model(sw.Backlash(1, 1, 0.5, 0.5), tmp_path / 'x.json')
    with pytest.raises(TypeError, match=r"metadata must be a dict; got "
                                        r"list"):
        sw.save_model(plant, tmp_path / 'x.json', metadata=[1])
    with pytest.raises(TypeError, match=r"JSON-serialisable .* got object"):
        sw.save_model(plant, tmp_path / 'x.json', metadata={'x': object()})
    with pytest.raises(ValueError, match=r"NaN or infinity"):
        sw.save_model(plant, tmp_path / 'x.json',
                      metadata={'x': float('nan')})


@pytest.mark.parametrize('design', [sw.sandwich_compensator,
                                    sw.servo_controller])
def test_a_controller_is_not_saved_as_its_plant(design, tmp_path):
    # it was: the file held the plant and a made-up failed identification
    ctrl = design(sw.examples.paper_plant())
    path = tmp_path / 'c.json'
    with pytest.raises(TypeError, match=r"got " + type(ctrl).__name__
                       + r" \(save its \.model"):
        sw.save_model(ctrl, path)
    assert not path.exists()


def test_a_result_is_saved_with_its_verdict_and_offsets():
    """save_model of an identification result saves its model, and its
    verdict, fits and offsets under metadata['identification'] (the
    operating point a controller of the loaded model needs); a user key
    of that name is refused rather than overwritten."""
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(2000, seed=0)
    res = sw.identify(u, plant.simulate(u).outputs - 1.5,
                      **plant.orders, offsets='estimate')
    buffer = io.StringIO()
    sw.save_model(res, buffer, metadata={'axis': 'x'})
    model, meta = sw.load_model(io.StringIO(buffer.getvalue()),
                                return_metadata=True)
    assert np.array_equal(model.theta, res.model.theta)
    got = meta['identification']
    assert meta['axis'] == 'x' and got['success'] is True
    assert got['fit'] == res.fit and got['linear_fit'] == res.linear['fit']
    assert got['offsets'] == {'method': 'estimate',
                              'u': list(res.offsets['u']),
                              'y': list(res.offsets['y'])}
    with pytest.raises(ValueError, match="key 'identification'"):
        sw.save_model(res, io.StringIO(), metadata={'identification': 1})


def test_a_streamed_result_is_saved_without_fits():
    """A RecursiveIdentifier's result has no fit: it is saved all the
    same, its fits stored as None."""
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(300, seed=2)
    est = sw.RecursiveIdentifier(**plant.orders)
    est.update_many(u, plant.simulate(u).outputs)
    buffer = io.StringIO()
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        sw.save_model(est.result(), buffer)
    model, meta = sw.load_model(io.StringIO(buffer.getvalue()),
                                return_metadata=True)
    assert np.array_equal(model.theta, est.theta)
    assert meta['identification']['fit'] is None
