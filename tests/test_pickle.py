"""Every public object survives pickle and copy.deepcopy, names included.

After the round trip a system simulates bit for bit like the original
(``np.array_equal``, not allclose) and keeps its name, its signal and
state names and its declared orders. Names also survive the
transformations: `normalized`, `copy_with`, and save/load.
"""

import copy
import io
import pickle
import subprocess
import sys

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

U = sw.examples.paper_input(300, seed=3)


def _plant():
    L1 = ct.tf([1.5, 0], [1, 0.1, 0.2], 0.01)
    L2 = ct.tf([2, -0.1], [1, 1.2, 0.32], 0.01)
    return sw.SandwichSystem(L1, sw.Backlash(1, 1.2, 0.5, 0.6), L2,
                             name='axis_x', inputs='u_x', outputs='y_x',
                             orders={'na': 3, 'nd': 2})


def _roundtrips(obj):
    """The pickled-and-loaded copy and the deep copy of `obj`."""
    return [pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj)]


def _names(sys):
    return (sys.name, sys.input_labels, sys.output_labels, sys.state_labels,
            sys.dt)


def test_backlash():
    bl = sw.Backlash(1, 1.2, 0.5, 0.6, dt=0.1, name='gear', inputs='x_in',
                     outputs='v_out', states=['xp', 'vp'])
    x = np.cumsum(U)
    for other in _roundtrips(bl):
        assert type(other) is sw.Backlash
        assert _names(other) == _names(bl)
        assert (other.m1, other.m2, other.D1, other.D2) == (1, 1.2, 0.5, 0.6)
        assert np.array_equal(other.response(x), bl.response(x))
        resp = ct.input_output_response(other, 0.1 * np.arange(20), x[:20])
        ref = ct.input_output_response(bl, 0.1 * np.arange(20), x[:20])
        assert np.array_equal(resp.outputs, ref.outputs)


def test_sandwich_system():
    plant = _plant()
    x0 = np.linspace(-0.3, 0.3, plant.nstates)
    for other in _roundtrips(plant):
        assert type(other) is sw.SandwichSystem
        assert _names(other) == _names(plant)
        assert other.orders == plant.orders == {
            'na': 3, 'nb': 0, 'nc': 2, 'nd': 2, 'q1': 1, 'q2': 1}
        assert np.array_equal(other.theta, plant.theta)
        a = other.simulate(U, initial_state=x0, internal=True)
        b = plant.simulate(U, initial_state=x0, internal=True)
        assert np.array_equal(a.outputs, b.outputs)
        assert np.array_equal(a.final_state, b.final_state)
    # and python-control's own simulation of the copy
    other = pickle.loads(pickle.dumps(plant))
    t = 0.01 * np.arange(40)
    assert np.array_equal(
        ct.input_output_response(other, t, U[:40]).outputs,
        ct.input_output_response(plant, t, U[:40]).outputs)


def test_identification_result():
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(400, seed=0)
    y = plant.simulate(u).outputs
    res = sw.identify(u, y, **plant.orders)
    for other in _roundtrips(res):
        assert type(other) is type(res)
        assert _names(other.model) == _names(res.model)
        assert other.model.orders == res.model.orders
        assert np.array_equal(other.theta, res.theta)
        assert other.message == res.message
        assert np.array_equal(other.model.simulate(u).outputs,
                              res.model.simulate(u).outputs)


def test_linear_identification_result():
    L = ct.tf([1.5, 0], [1, 0.1, 0.2], 1)
    y = ct.forced_response(L, inputs=U).outputs
    res = sw.identify_linear(U, y, nb=1, nf=2, nk=1, dt=1, name='lin')
    for other in _roundtrips(res):
        assert other.model.name == 'lin'
        assert np.array_equal(other.model.num[0][0], res.model.num[0][0])
        assert np.array_equal(other.model.den[0][0], res.model.den[0][0])
        assert other.fit == res.fit


def test_recursive_identifier_continues_identically():
    plant = sw.examples.paper_plant()
    y = plant.simulate(U).outputs
    est = sw.RecursiveIdentifier(**plant.orders)
    est.update_many(U[:150], y[:150])
    other = pickle.loads(pickle.dumps(est))
    est.update_many(U[150:], y[150:])
    other.update_many(U[150:], y[150:])
    assert np.array_equal(est.theta, other.theta)


def test_compensator_and_inverse():
    plant = _plant()
    comp = sw.sandwich_compensator(plant, smoothing=0.05, band_fraction=0.9,
                                   name='comp', inputs='r', outputs='u_cmd')
    inv = sw.backlash_inverse(plant.backlash, smoothing=0.1, name='inv',
                              inputs='v_want', outputs='x_cmd')
    for other in _roundtrips(comp):
        assert type(other) is sw.SandwichCompensator
        assert _names(other) == _names(comp)
        assert (other.smoothing, other.band_fraction) == (0.05, 0.9)
        assert _names(other.model) == _names(plant)
        assert other.L1_inverse.name == comp.L1_inverse.name == 'L1_inverse'
        assert other.design_plant.name == comp.design_plant.name
        assert np.array_equal(other.simulate(U, internal=True).outputs,
                              comp.simulate(U, internal=True).outputs)
    for other in _roundtrips(inv):
        assert type(other) is sw.BacklashInverse
        assert _names(other) == _names(inv)
        assert other.smoothing == 0.1
        assert np.array_equal(other.response(U), inv.response(U))


def test_controller_and_demo():
    plant = sw.examples.paper_plant()
    demo = sw.closed_loop_demo(plant, plant, reference=sw.steps_and_sines(300))
    ctrl = demo.controller_with
    for other in _roundtrips(ctrl):
        assert repr(other) == repr(ctrl)
        assert np.array_equal(other.feedback.num[0][0],
                              ctrl.feedback.num[0][0])
    for other in _roundtrips(demo):
        assert repr(other) == repr(demo)
        again = sw.closed_loop_response(plant, other.reference,
                                        other.controller_with,
                                        other.compensator)
        assert np.array_equal(again.outputs, demo.with_compensation.outputs)


@pytest.mark.parametrize('compensate', [True, False])
def test_closed_loop_system(compensate):
    """The python-control interconnection pickles (python-control's own
    state-space blocks do not) and simulates identically afterwards."""
    plant = sw.examples.paper_plant()
    comp = sw.sandwich_compensator(plant) if compensate else None
    design = comp.design_plant if compensate else sw.linearized_plant(plant)
    ctrl = sw.tracking_controller(design)
    loop = sw.closed_loop_system(plant, ctrl, comp, name='loop')
    loop.set_outputs(['position', 'command'])         # changed after
    r = sw.steps_and_sines(40, levels=(0, 1.0, -0.5), periods=(13, 7))
    ref = ct.input_output_response(loop, np.arange(r.size), r).outputs
    for other in _roundtrips(loop):
        assert isinstance(other, ct.InterconnectedSystem)
        assert other.name == 'loop'
        assert other.output_labels == ['position', 'command']
        assert other.state_labels == loop.state_labels
        out = ct.input_output_response(other, np.arange(r.size), r).outputs
        assert np.array_equal(out, ref)


def test_describing_function_objects():
    model = sw.examples.paper_plant().normalized()
    F = sw.backlash_nonlinearity(model.backlash, output_mean=0.1)
    A = np.array([0.5, 1.0, 2.0])
    for other in _roundtrips(F):
        assert repr(other) == repr(F)
        assert np.array_equal(ct.describing_function(other, A),
                              ct.describing_function(F, A))
    C = ct.tf([0.05, 0], np.polymul([1, -1], [1, -0.9]), 1)
    resp = sw.sandwich_limit_cycles(model, C)
    for other in _roundtrips(resp):
        assert np.array_equal(np.asarray(other.intersections),
                              np.asarray(resp.intersections))


def test_unpickled_in_a_fresh_interpreter(tmp_path):
    """No hidden module state: another process simulates the same bits."""
    plant = _plant()
    path = tmp_path / 'plant.pkl'
    path.write_bytes(pickle.dumps(plant))
    np.save(tmp_path / 'u.npy', U)
    code = (
        "import pickle, sys, numpy as np\n"
        f"plant = pickle.loads(open({str(path)!r}, 'rb').read())\n"
        f"u = np.load({str(tmp_path / 'u.npy')!r})\n"
        "y = plant.simulate(u).outputs\n"
        "sys.stdout.write(y.tobytes().hex() + ' ' + plant.name + ' '\n"
        "                 + plant.input_labels[0] + ' ' + str(plant.orders))\n")
    out = subprocess.run([sys.executable, '-c', code], capture_output=True,
                         text=True, timeout=120, check=True).stdout
    hexdata, name, inp, orders = out.split(' ', 3)
    assert bytes.fromhex(hexdata) == plant.simulate(U).outputs.tobytes()
    assert (name, inp, orders) == ('axis_x', 'u_x', str(plant.orders))


# ----------------------------------------------------------------------
# Names survive transformations
# ----------------------------------------------------------------------
@pytest.mark.parametrize('negative', [False, True])
def test_normalized_keeps_names_and_orders(negative):
    plant = _plant()
    if negative:
        plant = sw.SandwichSystem(-plant.L1, plant.backlash, plant.L2,
                                  name='axis_x', inputs='u_x', outputs='y_x',
                                  orders=plant.orders)
    norm = plant.normalized()
    assert _names(norm) == _names(plant)
    assert norm.orders == plant.orders
    assert norm.gain_sign == plant.gain_sign == (-1 if negative else 1)
    np.testing.assert_allclose(norm.simulate(U).outputs,
                               plant.simulate(U).outputs, atol=1e-12)


def test_save_load_keeps_names_and_declared_orders(tmp_path):
    plant = _plant()
    path = tmp_path / 'axis_x.json'
    sw.save_model(plant, path)
    loaded = sw.load_model(path)
    assert _names(loaded) == _names(plant)
    assert loaded.orders == plant.orders
    assert np.array_equal(loaded.theta, plant.theta)
    assert np.array_equal(loaded.simulate(U).outputs,
                          plant.simulate(U).outputs)
    buf = io.StringIO()
    sw.save_model(loaded, buf)
    assert buf.getvalue() == path.read_text()


def test_copy_with_keeps_names():
    bl = sw.Backlash(1, 1, 0.5, 0.5, dt=1, name='gear', inputs='a',
                     outputs='b')
    changed = bl.copy_with(D1=0.1)
    assert _names(changed) == _names(bl) and changed.D1 == 0.1


def test_sandwich_copy_with_keeps_names():
    plant = _plant()
    changed = plant.copy_with(m2=1.5)
    assert _names(changed) == _names(plant)
    assert changed.orders == plant.orders and changed.L2 is plant.L2


def test_negative_gain_theta_survives_pickling():
    plant = _plant().copy_with(d=[-1.0, 0.2])
    theta = pickle.loads(pickle.dumps(plant.theta))
    assert theta.sign == -1
    back = sw.SandwichSystem.from_theta(theta, **plant.orders, dt=plant.dt)
    assert back.gain_sign == -1
    np.testing.assert_array_equal(back.simulate(U).outputs,
                                  plant.normalized().simulate(U).outputs)


def test_a_copied_result_is_still_a_result():
    # dict.copy gave a plain dict
    plant = sw.examples.paper_plant()
    u = sw.examples.paper_input(600, seed=1)
    y = plant.simulate(u).outputs
    for res in (sw.identify(u, y, **plant.orders, integrators=0),
                sw.identify_linear(u, y, nb=2, nf=4)):
        copied = res.copy()
        assert type(copied) is type(res) and copied is not res
        assert repr(copied) == repr(res) and copied.fit == res.fit
