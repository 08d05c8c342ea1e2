"""Bad input gets a clear error, at once, from every public entry point.

Each row calls one public function or class with one bad argument and
states the exception type and a pattern that the message must match; the
pattern names the argument (or, for a file, the file and the field), so a
user knows what to fix. Every call must fail within `TIME_LIMIT` seconds:
a huge order such as ``q1=10**6`` must be refused before any work.

Rows marked ``xfail(strict=True)`` are known gaps in modules maintained
elsewhere; a fix turns them into XPASS, which fails, so that the mark is
removed with the fix.
"""

import json
import time

import numpy as np
import control as ct
import pytest

import sandwichctl as sw

TIME_LIMIT = 2.0                      # seconds for a call to fail

PLANT = sw.examples.paper_plant()
BL = sw.Backlash(1, 1.2, 0.5, 0.6, dt=1)
L1, L2 = PLANT.L1, PLANT.L2
COMP = sw.sandwich_compensator(PLANT)
CTRL = sw.tracking_controller(COMP.design_plant)
N = 50
U = np.linspace(-1, 1, N)
Y = PLANT.simulate(U).outputs
UL = sw.examples.paper_input(400, seed=0)      # enough to identify from
YL = PLANT.simulate(UL).outputs
NF = sw.backlash_nonlinearity(BL)
C_PI = ct.tf([0.3, -0.2], [1, -1], 1)
BIG = 10 ** 6
ORD = dict(na=2, nb=0, nc=2, nd=1)
NEG = PLANT.copy_with(d=-PLANT.coefficients['d'])     # negative gain
U2K = sw.examples.paper_input(2000, seed=0)
Y2K = PLANT.simulate(U2K).outputs


class _NanPlant:
    """A user plant whose sensor fails: its second reading is NaN."""

    def __init__(self):
        self.k = 0

    def step(self, u):
        self.k += 1
        return np.nan if self.k == 2 else 0.0


class _OddPlant:
    """A user plant whose step returns `value` and whose read returns
    `first` (0.0 by default)."""

    def __init__(self, value, first=0.0):
        self.value, self.first = value, first

    def read(self):
        return self.first

    def step(self, u):
        return self.value


def _nan_at(k, n=N):
    x = np.ones(n)
    x[k] = np.nan
    return x


def _steps_to_overflow():
    """Steps the paper plant's controller with inputs near the largest
    float until its output overflows (the third step)."""
    ctrl = sw.servo_controller(PLANT)
    for _ in range(4):
        ctrl.step(1e308, -1e308)


def _file(tmp, name, content):
    path = tmp / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    return path


def _model_json(**changes):
    buf = __import__('io').StringIO()
    sw.save_model(PLANT, buf)
    data = json.loads(buf.getvalue())
    data.update(changes)
    return json.dumps(data)


def _npy(tmp):
    path = tmp / 'array.npy'
    np.save(path, np.arange(10.0))
    return path


def _resp(t):
    u = sw.examples.paper_input(t.size, seed=1)
    return ct.TimeResponseData(t, PLANT.simulate(u).outputs, inputs=u)


def other(reason):
    """Mark a row failing in a module maintained elsewhere."""
    return pytest.mark.xfail(strict=True, reason=reason)


TE, VE = TypeError, ValueError
ROWS = [
    # ------------------------------------------------------------------
    # model: Backlash, backlash_response
    ('Backlash-bool', lambda t: sw.Backlash(True, 1, 0.5, 0.5), TE, 'm1'),
    ('Backlash-None', lambda t: sw.Backlash(1, None, 0.5, 0.5), TE, 'm2'),
    ('Backlash-str', lambda t: sw.Backlash(1, 1, '0.5', 0.5), TE, 'D1'),
    ('Backlash-complex', lambda t: sw.Backlash(1, 1, 0.5, 0.5j), TE, 'D2'),
    ('Backlash-nan', lambda t: sw.Backlash(np.nan, 1, 0.5, 0.5), VE, 'm1'),
    ('Backlash-inf', lambda t: sw.Backlash(1, 1, np.inf, 0.5), VE, 'D1'),
    ('Backlash-negative', lambda t: sw.Backlash(1, 1, 0.5, -1), VE, 'D2'),
    ('Backlash-array', lambda t: sw.Backlash([1, 2], 1, 0.5, 0.5), TE, 'm1'),
    ('Backlash-dt-inf', lambda t: sw.Backlash(1, 1, 0, 0, dt=np.inf), VE,
     'dt'),
    ('Backlash-dt-nan', lambda t: sw.Backlash(1, 1, 0, 0, dt=np.nan), VE,
     'dt'),
    ('Backlash-dt-0', lambda t: sw.Backlash(1, 1, 0, 0, dt=0), VE, 'dt'),
    ('Backlash-dt-str', lambda t: sw.Backlash(1, 1, 0, 0, dt='1'), TE, 'dt'),
    ('Backlash-dt-None', lambda t: sw.Backlash(1, 1, 0, 0, dt=None), TE,
     'dt'),
    ('Backlash-dt-False', lambda t: sw.Backlash(1, 1, 0, 0, dt=False), TE,
     'dt'),
    ('Backlash-name', lambda t: sw.Backlash(1, 1, 0, 0, name=123), TE,
     'name'),
    ('Backlash-two-inputs',
     lambda t: sw.Backlash(1, 1, 0, 0, inputs=['a', 'b']), VE, 'inputs'),
    ('Backlash-outputs-int', lambda t: sw.Backlash(1, 1, 0, 0, outputs=3),
     TE, 'outputs'),
    ('Backlash-states', lambda t: sw.Backlash(1, 1, 0, 0, states=['s']), VE,
     'states'),
    ('Backlash.copy_with', lambda t: BL.copy_with(m3=1), TE, 'm3'),
    ('backlash_response-complex',
     lambda t: sw.backlash_response(U + 1j, 1, 1, 0, 0), TE, 'x'),
    ('backlash_response-bool',
     lambda t: sw.backlash_response(U > 0, 1, 1, 0, 0), TE, 'x'),
    ('backlash_response-2d',
     lambda t: sw.backlash_response(np.ones((2, 5)), 1, 1, 0, 0), VE, 'x'),
    ('backlash_response-nan',
     lambda t: sw.backlash_response(_nan_at(3), 1, 1, 0, 0), VE,
     'x must be finite; sample 3'),
    ('backlash_response-None',
     lambda t: sw.backlash_response(None, 1, 1, 0, 0), TE, 'x'),
    ('backlash_response-str',
     lambda t: sw.backlash_response('abc', 1, 1, 0, 0), TE, 'x'),
    ('backlash_response-scalar',
     lambda t: sw.backlash_response(1.0, 1, 1, 0, 0), VE, 'x'),
    ('backlash_response-x_prev',
     lambda t: sw.backlash_response(U, 1, 1, 0, 0, x_prev=np.nan), VE,
     'x_prev'),
    ('backlash_response-return_zones',
     lambda t: sw.backlash_response(U, 1, 1, 0, 0, return_zones='yes'), TE,
     'return_zones'),
    # ------------------------------------------------------------------
    # model: SandwichSystem
    ('Sandwich-L1-type', lambda t: sw.SandwichSystem('L1', BL, L2), TE,
     'L1'),
    ('Sandwich-L1-ss', lambda t: sw.SandwichSystem(ct.ss(L1), BL, L2), TE,
     'L1'),
    ('Sandwich-L2-continuous',
     lambda t: sw.SandwichSystem(L1, BL, ct.tf([1], [1, 1])), VE, 'L2'),
    ('Sandwich-L1-dt-inf',
     lambda t: sw.SandwichSystem(ct.tf([1], [1, 0.5], np.inf), BL, L2), VE,
     'L1'),
    ('Sandwich-L1-MIMO',
     lambda t: sw.SandwichSystem(ct.tf([[[1], [1]]], [[[1, 0.5], [1, 0.5]]],
                                       1), BL, L2), VE, 'L1'),
    ('Sandwich-L1-nan',
     lambda t: sw.SandwichSystem(ct.tf([np.nan], [1, 0.5], 1), BL, L2), VE,
     'L1'),
    ('Sandwich-L1-improper',
     lambda t: sw.SandwichSystem(ct.tf([1, 0, 0], [1, 0.5], 1), BL, L2), VE,
     'L1'),
    ('Sandwich-dt-mismatch',
     lambda t: sw.SandwichSystem(L1, BL, ct.tf([1], [1, 0.5], 0.1)), VE,
     'sampling time'),
    ('Sandwich-backlash', lambda t: sw.SandwichSystem(L1, 'bl', L2), TE,
     'backlash'),
    ('Sandwich-name', lambda t: sw.SandwichSystem(L1, BL, L2, name=123), TE,
     'name'),
    ('Sandwich-two-inputs',
     lambda t: sw.SandwichSystem(L1, BL, L2, inputs=['u1', 'u2']), VE,
     'inputs'),
    ('Sandwich-outputs-None',
     lambda t: sw.SandwichSystem(L1, BL, L2, outputs=None), TE, 'outputs'),
    ('Sandwich-orders-type',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders=[2, 0]), TE, 'orders'),
    ('Sandwich-orders-key',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'nx': 2}), VE,
     'orders'),
    ('Sandwich-orders-float',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'na': 2.0}), TE, 'na'),
    ('Sandwich-orders-bool',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'nb': True}), TE, 'nb'),
    ('Sandwich-orders-negative',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'nc': -1}), VE, 'nc'),
    ('Sandwich-orders-huge',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'nd': BIG}), VE, 'nd'),
    ('Sandwich-orders-smaller',
     lambda t: sw.SandwichSystem(L1, BL, L2, orders={'na': 1}), VE, 'na'),
    ('from_coefficients-q1-huge',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, q1=BIG), VE, 'q1'),
    ('from_coefficients-q2-float',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, q2=1.0), TE, 'q2'),
    ('from_coefficients-q1-bool',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, q1=True), TE, 'q1'),
    ('from_coefficients-q1-negative',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, q1=-1), VE, 'q1'),
    ('from_coefficients-a-huge',
     lambda t: sw.SandwichSystem.from_coefficients(
         np.zeros(BIG), [1], [0.5], [1], 1, 1, 0, 0), VE, 'a'),
    ('from_coefficients-a-nan',
     lambda t: sw.SandwichSystem.from_coefficients(
         [np.nan], [1], [0.5], [1], 1, 1, 0, 0), VE, 'a'),
    ('from_coefficients-b-complex',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1j], [0.5], [1], 1, 1, 0, 0), TE, 'b'),
    ('from_coefficients-c-None',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], None, [1], 1, 1, 0, 0), TE, 'c'),
    ('from_coefficients-d-str',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], 'd', 1, 1, 0, 0), TE, 'd'),
    ('from_coefficients-d-2d',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [[1, 2], [3, 4]], 1, 1, 0, 0), VE, 'd'),
    ('from_coefficients-b-empty',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [], [0.5], [1], 1, 1, 0, 0), VE, 'b'),
    ('from_coefficients-b0-zero',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [0, 1], [0.5], [1], 1, 1, 0, 0), VE, 'b'),
    ('from_coefficients-m1-bool',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], True, 1, 0, 0), TE, 'm1'),
    ('from_coefficients-dt-inf',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, dt=np.inf), VE, 'dt'),
    ('from_coefficients-dt-0',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, dt=0), VE, 'dt'),
    ('from_coefficients-name',
     lambda t: sw.SandwichSystem.from_coefficients(
         [0.5], [1], [0.5], [1], 1, 1, 0, 0, name=1.5), TE, 'name'),
    ('from_theta-sign',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta, **ORD, sign=2), VE,
     'sign must be one of 1, -1'),
    ('from_theta-sign-bool',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta, **ORD, sign=True),
     VE, 'sign'),
    ('from_theta-na-float',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta, na=2.0, nb=0, nc=2,
                                            nd=1), TE, 'na'),
    ('from_theta-na-huge',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta, na=BIG, nb=0, nc=2,
                                            nd=1), VE, 'na'),
    ('from_theta-length',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta[:-1], **ORD), VE,
     'theta'),
    ('from_theta-nan',
     lambda t: sw.SandwichSystem.from_theta(PLANT.theta * np.nan, **ORD), VE,
     'theta'),
    ('from_theta-sign-conflict',
     lambda t: sw.SandwichSystem.from_theta(NEG.theta, **ORD, sign=1), VE,
     'sign=1 but theta comes from a system whose gain has sign -1'),
    ('SandwichSystem.copy_with-unknown', lambda t: PLANT.copy_with(m3=1), TE,
     'm3'),
    ('SandwichSystem.copy_with-block-and-coefficients',
     lambda t: PLANT.copy_with(L1=L1, a=[0.1]), VE,
     r"blocks \['L1'\] and coefficients \['a'\]"),
    ('SandwichSystem.copy_with-D1', lambda t: PLANT.copy_with(D1=-1), VE,
     'D1'),
    ('SandwichSystem.copy_with-backlash',
     lambda t: PLANT.copy_with(backlash=L1), TE, 'backlash'),
    ('simulate-states-not-stored', lambda t: PLANT.simulate(U).states,
     AttributeError, 'return_states=True.*final_state.*internal=True'),
    ('theta_labels-float', lambda t: sw.theta_labels(2.5, 0, 2, 1), TE,
     'na'),
    ('theta_labels-negative', lambda t: sw.theta_labels(2, -1, 2, 1), VE,
     'nb'),
    ('simulate-complex', lambda t: PLANT.simulate(U * 1j), TE, 'inputs'),
    ('simulate-2d', lambda t: PLANT.simulate(np.ones((2, N))), VE,
     'inputs'),
    ('simulate-nan', lambda t: PLANT.simulate(_nan_at(7)), VE,
     'inputs must be finite; sample 7'),
    ('simulate-inf', lambda t: PLANT.simulate(np.full(N, np.inf)), VE,
     'inputs'),
    ('simulate-None', lambda t: PLANT.simulate(None), TE, 'inputs'),
    ('simulate-bool', lambda t: PLANT.simulate(U > 0), TE, 'inputs'),
    ('simulate-response',
     lambda t: PLANT.simulate(_resp(np.arange(N))), TE, 'inputs'),
    ('simulate-initial_state-length',
     lambda t: PLANT.simulate(U, initial_state=np.zeros(3)), VE,
     'initial_state'),
    ('simulate-initial_state-nan',
     lambda t: PLANT.simulate(U, initial_state=np.full(PLANT.nstates,
                                                       np.nan)), VE,
     'initial_state'),
    ('simulate-initial_state-str',
     lambda t: PLANT.simulate(U, initial_state='zero'), TE, 'initial_state'),
    ('simulate-timepts-uneven',
     lambda t: PLANT.simulate(U, timepts=np.arange(N) ** 1.5), VE,
     'timepts'),
    ('simulate-timepts-spacing',
     lambda t: PLANT.simulate(U, timepts=0.5 * np.arange(N)), VE,
     'timepts has spacing 0.5'),
    ('simulate-timepts-length',
     lambda t: PLANT.simulate(U, timepts=np.arange(N + 1)), VE, 'timepts'),
    ('simulate-timepts-decreasing',
     lambda t: PLANT.simulate(U, timepts=-np.arange(N)), VE, 'timepts'),
    ('simulate-internal', lambda t: PLANT.simulate(U, internal='yes'), TE,
     'internal'),
    ('simulate_batch-inputs-nan',
     lambda t: PLANT.simulate_batch(np.stack([U, _nan_at(3)])), VE,
     r'inputs\[1\] must be finite; sample 3'),
    ('simulate_batch-inputs-3d',
     lambda t: PLANT.simulate_batch(np.ones((2, 2, N))), VE, 'inputs'),
    ('simulate_batch-thetas-length',
     lambda t: PLANT.simulate_batch(U, np.ones((2, 3))), VE,
     r'thetas\[0\]'),
    ('simulate_batch-thetas-m2',
     lambda t: PLANT.simulate_batch(
         U, np.r_[PLANT.theta[:5], -1.0, PLANT.theta[6:]]), VE,
     r'thetas\[0\] \(m2\)'),
    ('simulate_batch-pairing',
     lambda t: PLANT.simulate_batch(np.ones((3, N)), [PLANT.theta] * 2), VE,
     'inputs has 3 signals but thetas 2'),
    ('step_response-sys', lambda t: sw.step_response('plant'), TE, 'sys'),
    ('step_response-continuous',
     lambda t: sw.step_response(ct.tf([1], [1, 1])), VE, 'sys'),
    ('step_response-amplitude-nan',
     lambda t: sw.step_response(PLANT, amplitude=np.nan), VE, 'amplitude'),
    ('step_response-amplitude-None',
     lambda t: sw.step_response(PLANT, amplitude=None), TE, 'amplitude'),
    ('step_response-timepts',
     lambda t: sw.step_response(PLANT, timepts=[0, 1, 3]), VE, 'timepts'),
    # ------------------------------------------------------------------
    # tools: files
    ('save_model-model', lambda t: sw.save_model(BL, t / 'm.json'), TE,
     'model'),
    ('save_model-path', lambda t: sw.save_model(PLANT, 123), TE, 'path'),
    ('save_model-metadata',
     lambda t: sw.save_model(PLANT, t / 'm.json', metadata=[1]), TE,
     'metadata'),
    ('save_model-metadata-nan',
     lambda t: sw.save_model(PLANT, t / 'm.json', metadata={'x': np.nan}),
     VE, 'metadata'),
    ('save_model-directory', lambda t: sw.save_model(PLANT, t),
     IsADirectoryError, 'path is a directory.*a .json file to write'),
    ('save_model-missing-folder',
     lambda t: sw.save_model(PLANT, t / 'no' / 'm.json'), FileNotFoundError,
     'folder that does not exist.*os.makedirs'),
    ('load_model-path', lambda t: sw.load_model(None), TE, 'path'),
    ('load_model-missing-file', lambda t: sw.load_model(t / 'nope.json'),
     FileNotFoundError, 'path names no file.*nope.json'),
    ('load_model-directory', lambda t: sw.load_model(t), IsADirectoryError,
     'path is a directory'),
    ('load_model-binary',
     lambda t: sw.load_model(_file(t, 'garbage.json',
                                   bytes(range(256)) * 4)), VE,
     'garbage.json.*binary'),
    ('load_model-npy', lambda t: sw.load_model(_npy(t)), VE,
     r'array.npy.*not a sandwichctl model'),
    ('load_model-text', lambda t: sw.load_model(_file(t, 'a.txt', 'hello')),
     VE, 'a.txt.*not valid JSON'),
    ('load_model-list', lambda t: sw.load_model(_file(t, 'l.json', '[1]')),
     VE, "l.json.*format"),
    ('load_model-q1-huge',
     lambda t: sw.load_model(_file(t, 'q.json', _model_json(q1=BIG))), VE,
     "q.json.*'q1'"),
    ('load_model-q1-float',
     lambda t: sw.load_model(_file(t, 'q.json', _model_json(q1=1.0))), VE,
     "q.json.*'q1'"),
    ('load_model-a-huge',
     lambda t: sw.load_model(_file(t, 'a.json',
                                   _model_json(a=[0.0] * BIG))), VE,
     "a.json.*'a'"),
    ('load_model-a-str',
     lambda t: sw.load_model(_file(t, 'a.json', _model_json(a=['x']))), VE,
     r"a.json.*'a\[0\]'"),
    ('load_model-m1-str',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(m1='1'))), VE,
     "m.json.*'m1'"),
    ('load_model-m2-bool',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(m2=True))), VE,
     "m.json.*'m2'"),
    ('load_model-D1-nan',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(D1=np.nan))),
     VE, "m.json.*'D1'"),
    ('load_model-dt-inf',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(dt=np.inf))),
     VE, "m.json.*'dt'"),
    ('load_model-name',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(name=123))), VE,
     "m.json.*'name'"),
    ('load_model-inputs',
     lambda t: sw.load_model(_file(t, 'm.json',
                                   _model_json(inputs=['u1', 'u2']))), VE,
     "m.json.*'inputs'"),
    ('load_model-version',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json(version='1'))),
     VE, "m.json.*version"),
    ('load_model-missing',
     lambda t: sw.load_model(_file(t, 'm.json', json.dumps(
         {'format': 'sandwichctl.SandwichSystem', 'version': 1}))), VE,
     "m.json.*missing"),
    ('load_model-return_metadata',
     lambda t: sw.load_model(_file(t, 'm.json', _model_json()),
                             return_metadata='yes'), TE, 'return_metadata'),
    # ------------------------------------------------------------------
    # tools: plotting
    ('plot_hysteresis-model', lambda t: sw.plot_hysteresis('model'), TE,
     'model_or_backlash'),
    ('plot_hysteresis-true', lambda t: sw.plot_hysteresis(BL, true=3), TE,
     'true'),
    ('plot_hysteresis-x', lambda t: sw.plot_hysteresis(BL, x=_nan_at(2)),
     VE, 'x'),
    ('plot_hysteresis-ax', lambda t: sw.plot_hysteresis(BL, ax='x'), TE,
     'ax must be a matplotlib Axes'),
    # ------------------------------------------------------------------
    # design: inverses
    ('BacklashInverse-bool', lambda t: sw.BacklashInverse(1, True, 0, 0), TE,
     'm2'),
    ('BacklashInverse-smoothing',
     lambda t: sw.BacklashInverse(1, 1, 0, 0, smoothing=-1), VE,
     'smoothing'),
    ('BacklashInverse-dt', lambda t: sw.BacklashInverse(1, 1, 0, 0,
                                                        dt=np.nan), VE, 'dt'),
    ('BacklashInverse-name',
     lambda t: sw.BacklashInverse(1, 1, 0, 0, name=1), TE, 'name'),
    ('BacklashInverse-two-outputs',
     lambda t: sw.BacklashInverse(1, 1, 0, 0, outputs=('a', 'b')), VE,
     'outputs'),
    ('backlash_inverse-type', lambda t: sw.backlash_inverse(PLANT), TE,
     'backlash'),
    ('backlash_inverse-smoothing',
     lambda t: sw.backlash_inverse(BL, smoothing=np.nan), VE, 'smoothing'),
    ('backlash_inverse-dt', lambda t: sw.backlash_inverse(BL, dt=np.inf), VE,
     'dt'),
    ('backlash_inverse_response-complex',
     lambda t: sw.backlash_inverse_response(U * 1j, 1, 1, 0, 0), TE, 'v_d'),
    ('backlash_inverse_response-x_prev',
     lambda t: sw.backlash_inverse_response(U, 1, 1, 0, 0, x_prev='0'), TE,
     'x_prev'),
    ('causal_inverse-type', lambda t: sw.causal_inverse(PLANT), TE, 'sys'),
    ('causal_inverse-approximate',
     lambda t: sw.causal_inverse(L1, approximate='yes'), TE, 'approximate'),
    ('causal_inverse-name', lambda t: sw.causal_inverse(L1, name=1), TE,
     'name'),
    ('causal_inverse-nmp',
     lambda t: sw.causal_inverse(ct.tf([1, -2], [1, 0.5], 1)), VE,
     'approximate=True'),
    # design: compensator
    ('sandwich_compensator-model', lambda t: sw.sandwich_compensator(BL), TE,
     'model'),
    ('sandwich_compensator-band_fraction',
     lambda t: sw.sandwich_compensator(PLANT, band_fraction=2), VE,
     'band_fraction'),
    ('sandwich_compensator-band_fraction-bool',
     lambda t: sw.sandwich_compensator(PLANT, band_fraction=True), TE,
     'band_fraction'),
    ('sandwich_compensator-smoothing',
     lambda t: sw.sandwich_compensator(PLANT, smoothing=-0.1), VE,
     'smoothing'),
    ('sandwich_compensator-approximate',
     lambda t: sw.sandwich_compensator(PLANT, approximate=1), TE,
     'approximate'),
    ('sandwich_compensator-name',
     lambda t: sw.sandwich_compensator(PLANT, name=['c']), TE, 'name'),
    ('sandwich_compensator-inputs',
     lambda t: sw.sandwich_compensator(PLANT, inputs=['a', 'b']), VE,
     'inputs'),
    ('SandwichCompensator.simulate-nan',
     lambda t: COMP.simulate(_nan_at(0)), VE, 'inputs'),
    ('SandwichCompensator.simulate-initial_state',
     lambda t: COMP.simulate(U, initial_state=[0, 0]), VE, 'initial_state'),
    ('SandwichCompensator.simulate-timepts',
     lambda t: COMP.simulate(U, timepts=np.arange(N) * 2), VE, 'timepts'),
    ('linearized_plant-model', lambda t: sw.linearized_plant(L1), TE,
     'model'),
    # design: closed loop
    ('tracking_controller-sys', lambda t: sw.tracking_controller(PLANT), TE,
     'sys'),
    ('tracking_controller-margin',
     lambda t: sw.tracking_controller(L2, modulus_margin=2), VE,
     'modulus_margin'),
    ('tracking_controller-margin-str',
     lambda t: sw.tracking_controller(L2, modulus_margin='0.5'), TE,
     'modulus_margin'),
    ('tracking_controller-feedforward',
     lambda t: sw.tracking_controller(L2, feedforward='no'), TE,
     'feedforward'),
    ('tracking_controller-unstable',
     lambda t: sw.tracking_controller(ct.tf([1], [1, -2], 1)), VE, 'sys'),
    ('TrackingController.from_feedback-C',
     lambda t: sw.TrackingController.from_feedback(0.5), TE, 'C'),
    ('TrackingController.from_feedback-design_plant',
     lambda t: sw.TrackingController.from_feedback(C_PI, design_plant=PLANT),
     TE, 'design_plant'),
    ('closed_loop_response-plant',
     lambda t: sw.closed_loop_response(L2, U, CTRL), TE, 'plant'),
    ('closed_loop_response-reference',
     lambda t: sw.closed_loop_response(PLANT, _nan_at(4), CTRL), VE,
     'reference'),
    ('closed_loop_response-controller',
     lambda t: sw.closed_loop_response(PLANT, U, C_PI), TE, 'controller'),
    ('closed_loop_response-compensator',
     lambda t: sw.closed_loop_response(PLANT, U, CTRL, compensator=BL), TE,
     'compensator'),
    ('closed_loop_system-name',
     lambda t: sw.closed_loop_system(PLANT, CTRL, name=5), TE, 'name'),
    ('steps_and_sines-n-float', lambda t: sw.steps_and_sines(100.0), TE,
     'n'),
    ('steps_and_sines-n-bool', lambda t: sw.steps_and_sines(True), TE, 'n'),
    ('steps_and_sines-n-small', lambda t: sw.steps_and_sines(1), VE, 'n'),
    ('steps_and_sines-periods',
     lambda t: sw.steps_and_sines(100, periods=(0, 10)), VE, 'periods'),
    ('steps_and_sines-levels',
     lambda t: sw.steps_and_sines(100, levels=(0, np.nan)), VE, 'levels'),
    ('servo_controller-model', lambda t: sw.servo_controller(BL), TE,
     'model'),
    ('servo_controller-unstable',
     lambda t: sw.servo_controller(ct.tf([1], [1, -1.5], 1)), VE, 'stable'),
    ('servo_controller-modulus_margin',
     lambda t: sw.servo_controller(L2 * L1, modulus_margin=0), VE,
     'modulus_margin'),
    ('servo_controller-feedforward',
     lambda t: sw.servo_controller(PLANT, feedforward='exact'), VE,
     'feedforward'),
    ('servo_controller-band_fraction',
     lambda t: sw.servo_controller(PLANT, band_fraction=-0.1), VE,
     'band_fraction'),
    ('servo_controller-adapt',
     lambda t: sw.servo_controller(PLANT, adapt='yes'), VE, 'adapt'),
    ('servo_controller-feedback_from',
     lambda t: sw.servo_controller(PLANT, feedback_from='plant'), VE,
     'feedback_from'),
    ('servo_controller-feedback_from-no-baseline',
     lambda t: sw.servo_controller(PLANT, feedback_from='baseline'), VE,
     'linear baseline'),
    ('servo_controller-feedforward_from-list',
     lambda t: sw.servo_controller(PLANT, feedforward_from=['auto']), VE,
     'feedforward_from'),
    ('servo_controller-adapt-known-model',
     lambda t: sw.servo_controller(PLANT, adapt=True), VE,
     'identification result'),
    ('servo_controller-jump_samples',
     lambda t: sw.servo_controller(PLANT, jump_samples=0), VE,
     'jump_samples'),
    ('servo_controller-operating_point',
     lambda t: sw.servo_controller(PLANT, operating_point=(1.0,)), VE,
     'operating_point'),
    ('servo_controller-feedforward-array',
     lambda t: sw.servo_controller(PLANT, feedforward=np.ones(2)), VE,
     'feedforward'),
    ('servo_controller-feedforward_from',
     lambda t: sw.servo_controller(L2 * L1, feedforward_from='bogus'), VE,
     'feedforward_from'),
    ('servo_controller-adapt-array',
     lambda t: sw.servo_controller(PLANT, adapt=np.ones(2)), VE, 'adapt'),
    ('servo_controller-jump_samples-huge',
     lambda t: sw.servo_controller(PLANT, jump_samples=BIG), VE,
     'jump_samples'),
    ('servo_controller-max_preview-huge',
     lambda t: sw.servo_controller(PLANT, max_preview=BIG), VE,
     'max_preview'),
    ('servo_controller-feedback_scale-huge',
     lambda t: sw.servo_controller(PLANT, feedback_scale=1e308), VE,
     'feedback_scale.*smaller'),
    ('servo_controller-feedback_scale-tiny',
     lambda t: sw.servo_controller(PLANT, feedback_scale=1e-30), VE,
     'feedback_scale.*closer to 1'),
    ('servo_controller-gain-huge',
     lambda t: sw.servo_controller(ct.tf([1e300], [1, -0.5], 1)), VE,
     'model has a gain of order 1.0e\\+300.*rescale'),
    ('servo_controller-slopes-huge',
     lambda t: sw.servo_controller(PLANT.copy_with(m1=1e300, m2=1e300)),
     VE, 'design plant has a gain'),
    ('ServoController-step-str',
     lambda t: sw.servo_controller(PLANT).step('0.5', 0.0), TE, 'r_ahead'),
    ('ServoController-step-array',
     lambda t: sw.servo_controller(PLANT).step(0.0, np.ones(2)), TE, 'y'),
    ('ServoController-step-bool',
     lambda t: sw.servo_controller(PLANT).step(True, 0.0), TE, 'r_ahead'),
    ('closed_loop_response-servo-plant-returns-array',
     lambda t: sw.closed_loop_response(_OddPlant(np.ones(2)), U,
                                       sw.servo_controller(PLANT)), TE,
     r'plant.step\(u\) must return.*ndarray.*sample 1'),
    ('closed_loop_response-servo-plant-read-None',
     lambda t: sw.closed_loop_response(_OddPlant(0.0, None), U,
                                       sw.servo_controller(PLANT)), TE,
     r'plant.read\(\) must return.*NoneType'),
    ('ServoController-reset',
     lambda t: sw.servo_controller(PLANT).reset(y=np.nan), VE, 'y'),
    ('ServoController-run',
     lambda t: sw.servo_controller(PLANT).run(U, U[:3]), VE, 'y'),
    ('ServoController-step',
     lambda t: sw.servo_controller(PLANT).step(0.0, np.nan), VE, 'finite'),
    ('ServoController-step-overflow',
     lambda t: _steps_to_overflow(), OverflowError, 'reset'),
    ('ServoController-run-overflow',
     lambda t: sw.servo_controller(PLANT).run([1e308] * 4, [-1e308] * 4),
     OverflowError, 'sample 2'),
    ('closed_loop_response-servo-plant-nan',
     lambda t: sw.closed_loop_response(_NanPlant(), U,
                                       sw.servo_controller(PLANT)), VE,
     'plant returned'),
    ('closed_loop_response-servo-plant',
     lambda t: sw.closed_loop_response(BL, U, sw.servo_controller(PLANT)),
     TE, 'plant'),
    ('closed_loop_response-servo-compensator',
     lambda t: sw.closed_loop_response(PLANT, U, sw.servo_controller(PLANT),
                                       COMP), VE, 'compensator'),
    ('export_c-obj', lambda t: sw.export_c(PLANT, t), TE, 'obj'),
    ('export_c-directory',
     lambda t: sw.export_c(COMP, _file(t, 'f.txt', '')), VE, 'directory'),
    ('export_c-name', lambda t: sw.export_c(COMP, t, name='1st'), VE,
     'name'),
    ('export_c-name-long', lambda t: sw.export_c(COMP, t, name='x' * 300),
     VE, 'name must be at most 200'),
    ('export_c-dtype', lambda t: sw.export_c(COMP, t, dtype='half'), VE,
     'dtype'),
    ('servo_reference-dt', lambda t: sw.servo_reference(0, 1.0), VE, 'dt'),
    ('servo_reference-travel',
     lambda t: sw.servo_reference(1e-3, np.nan), VE, 'travel'),
    ('servo_reference-hold',
     lambda t: sw.servo_reference(1e-3, 1.0, hold=1e308), VE, 'samples'),
    ('servo_reference-tiny-dt',
     lambda t: sw.servo_reference(1e-300, 1.0), VE, 'samples'),
    ('servo_reference-dt-huge',
     lambda t: sw.servo_reference(1e308, 1.0), VE, 'dt must be at most'),
    ('servo_reference-total',
     lambda t: sw.servo_reference(2e-8, 1.0), VE, 'samples'),
    ('servo_metrics-window', lambda t: sw.servo_metrics(U, U, U, 1e-3,
                                                        window=np.inf), VE,
     'window'),
    ('servo_metrics-hold', lambda t: sw.servo_metrics(U, U, U, 1e-3,
                                                      hold='0.3'), TE,
     'hold'),
    ('servo_metrics-y', lambda t: sw.servo_metrics(U, U[:5], U, 1e-3), VE,
     'y'),
    ('servo_metrics-deadband',
     lambda t: sw.servo_metrics(U, U, U, 1e-3, deadband=-1), VE,
     'deadband'),
    ('closed_loop_demo-plant', lambda t: sw.closed_loop_demo(BL, PLANT), TE,
     'plant'),
    ('closed_loop_demo-model', lambda t: sw.closed_loop_demo(PLANT, L1), TE,
     'model'),
    ('closed_loop_demo-reference',
     lambda t: sw.closed_loop_demo(PLANT, PLANT, reference=U + 1j), TE,
     'reference'),
    ('closed_loop_demo-smoothing',
     lambda t: sw.closed_loop_demo(PLANT, PLANT, smoothing=np.nan), VE,
     'smoothing'),
    # design: describing function
    ('BacklashNonlinearity-bool',
     lambda t: sw.BacklashNonlinearity(1, 1, False, 0), TE, 'D1'),
    ('BacklashNonlinearity-output_mean',
     lambda t: sw.BacklashNonlinearity(1, 1, 0, 0, output_mean=np.nan), VE,
     'output_mean'),
    ('BacklashNonlinearity-input_bias',
     lambda t: sw.BacklashNonlinearity(1, 1, 0, 0, input_bias='0'), TE,
     'input_bias'),
    ('describing_function-A', lambda t: NF.describing_function('1'), TE,
     'A'),
    ('describing_function-A-nan',
     lambda t: NF.describing_function(np.nan), VE, 'A'),
    ('backlash_nonlinearity-type', lambda t: sw.backlash_nonlinearity(1), TE,
     'backlash'),
    ('backlash_harmonics-A', lambda t: sw.backlash_harmonics(-1, 0, 1, 1, 0,
                                                             0), VE, 'A'),
    ('backlash_harmonics-bias',
     lambda t: sw.backlash_harmonics(1, None, 1, 1, 0, 0), TE, 'bias'),
    ('unit_circle_frd-continuous',
     lambda t: sw.unit_circle_frd(ct.tf([1], [1, 1])), VE, 'sys'),
    ('unit_circle_frd-omega',
     lambda t: sw.unit_circle_frd(L2, omega=[0.1, 4.0]), VE, 'omega'),
    ('unit_circle_frd-name', lambda t: sw.unit_circle_frd(L2, name=2), TE,
     'name'),
    ('limit_cycles-H', lambda t: sw.limit_cycles('H', NF, [1.0]), TE, 'H'),
    ('limit_cycles-F', lambda t: sw.limit_cycles(L2, 3, [1.0]), TE, 'F'),
    ('limit_cycles-A', lambda t: sw.limit_cycles(L2, NF, [-1.0, 1.0]), VE,
     'A'),
    ('sandwich_limit_cycles-C',
     lambda t: sw.sandwich_limit_cycles(PLANT, 0.5), TE, 'C'),
    ('sandwich_limit_cycles-output_mean',
     lambda t: sw.sandwich_limit_cycles(PLANT, C_PI, output_mean=np.inf), VE,
     'output_mean'),
    ('simulate_limit_cycle-n',
     lambda t: sw.simulate_limit_cycle(PLANT, C_PI, n=100.5), TE, 'n'),
    ('simulate_limit_cycle-kick',
     lambda t: sw.simulate_limit_cycle(PLANT, C_PI, kick=np.nan), VE,
     'kick'),
    ('simulate_limit_cycle-settle',
     lambda t: sw.simulate_limit_cycle(PLANT, C_PI, n=100, settle=200), VE,
     'settle'),
    ('first_harmonic-signal', lambda t: sw.first_harmonic(U * 1j), TE,
     'signal'),
    ('first_harmonic-dt', lambda t: sw.first_harmonic(U, dt=True), TE, 'dt'),
    # ------------------------------------------------------------------
    # identification and validation (maintained elsewhere)
    ('identify-complex', lambda t: sw.identify(U + 1j, Y, **ORD), TE, 'u'),
    ('identify-2d', lambda t: sw.identify(np.ones((2, N)), Y, **ORD), VE,
     'u'),
    ('identify-nan', lambda t: sw.identify(U, _nan_at(5), **ORD), VE, 'y'),
    ('identify-length', lambda t: sw.identify(U, Y[:-1], **ORD), VE, 'y'),
    ('identify-order-float',
     lambda t: sw.identify(U, Y, na=2.0, nb=0, nc=2, nd=1), TE, 'na'),
    ('identify-order-bool',
     lambda t: sw.identify(U, Y, na=2, nb=True, nc=2, nd=1), TE, 'nb'),
    ('identify-order-negative',
     lambda t: sw.identify(U, Y, na=2, nb=0, nc=-2, nd=1), VE, 'nc'),
    ('identify-q1-huge', lambda t: sw.identify(UL, YL, **ORD, q1=BIG), VE,
     'q1'),
    ('identify-method',
     lambda t: sw.identify(U, Y, **ORD, method='nope'), VE,
     "method.*'oe'"),
    ('identify-dt-inf', lambda t: sw.identify(U, Y, **ORD, dt=np.inf), VE,
     'dt'),
    ('identify-dt-0', lambda t: sw.identify(U, Y, **ORD, dt=0), VE, 'dt'),
    ('identify-name', lambda t: sw.identify(U, Y, **ORD, name=123), TE,
     'name'),
    ('identify-theta0',
     lambda t: sw.identify(UL, YL, **ORD, method='bundle', theta0=[1, 2]),
     VE,
     'theta0'),
    ('identify-u-None', lambda t: sw.identify(None, Y, **ORD), TE, 'u'),
    ('identify-orders-against-N',
     lambda t: sw.identify(U2K, Y2K, na=40, nb=0, nc=40, nd=1), VE,
     r'p = 85 parameters.*N = 2000 samples.*at most 44'),
    ('identify-y-overflow', lambda t: sw.identify(UL, YL * 1e200, **ORD), VE,
     r'y has peak magnitude.*overflow.*rescale y'),
    ('identify-u-underflow', lambda t: sw.identify(UL * 1e-200, YL, **ORD),
     VE, r'u has peak magnitude.*underflow.*rescale u'),
    ('identify-response-spacing',
     lambda t: sw.identify(_resp(0.5 * np.arange(400)), **ORD, dt=1), VE,
     'dt'),
    ('identify-response-uneven',
     lambda t: sw.identify(_resp(np.arange(N) ** 1.2), **ORD), VE,
     'evenly'),
    ('RecursiveIdentifier-method',
     lambda t: sw.RecursiveIdentifier(**ORD, method='nope'), VE,
     "method.*'bundle'"),
    ('RecursiveIdentifier-na', lambda t: sw.RecursiveIdentifier(
        na=1.5, nb=0, nc=2, nd=1), TE, 'na'),
    ('RecursiveIdentifier-q1-huge',
     lambda t: sw.RecursiveIdentifier(**ORD, q1=BIG), VE, 'q1'),
    ('refine-model', lambda t: sw.refine(L1, U, Y), TE, 'model'),
    ('refine-u-nan', lambda t: sw.refine(PLANT, _nan_at(1), Y), VE, 'u'),
    ('refine-max_iter', lambda t: sw.refine(PLANT, U, Y, max_iter=0), VE,
     'max_iter'),
    ('refine-tol', lambda t: sw.refine(PLANT, U, Y, tol=-1), VE, 'tol'),
    ('identify_linear-nb', lambda t: sw.identify_linear(U, Y, nb=1.5, nf=2),
     TE, 'nb'),
    ('identify_linear-nf', lambda t: sw.identify_linear(U, Y, nb=1, nf=-1),
     VE, 'nf'),
    ('identify_linear-nk-huge',
     lambda t: sw.identify_linear(U, Y, nb=1, nf=2, nk=BIG), VE, 'nk'),
    ('identify_linear-dt',
     lambda t: sw.identify_linear(U, Y, nb=1, nf=2, dt=np.nan), VE, 'dt'),
    ('identify_linear-offsets',
     lambda t: sw.identify_linear(U, Y, nb=1, nf=2, offsets='bogus'), VE,
     'offsets'),
    ('identify_linear-complex',
     lambda t: sw.identify_linear(U * 1j, Y, nb=1, nf=2), TE, 'u'),
    ('identify_linear-y-overflow',
     lambda t: sw.identify_linear(UL, YL * 1e200, nb=1, nf=2), VE,
     r'y has peak magnitude.*overflow'),
    ('compare-model', lambda t: sw.compare('model', U, Y, plot=False), TE,
     'model'),
    ('compare-ax', lambda t: sw.compare(PLANT, U, Y, ax='x'), TE,
     "ax must be a matplotlib Axes.*got str 'x'"),
    ('compare-u-nan', lambda t: sw.compare(PLANT, _nan_at(2), Y,
                                           plot=False), VE, 'u'),
    ('compare-length', lambda t: sw.compare(PLANT, U, Y[:-2], plot=False),
     VE, 'y'),
    ('compare-timepts-uneven',
     lambda t: sw.compare(PLANT, U, Y, timepts=np.arange(N) ** 1.5,
                          plot=False), VE, 'timepts'),
    ('compare-timepts-spacing',
     lambda t: sw.compare(PLANT, U, Y, timepts=0.5 * np.arange(N),
                          plot=False), VE, 'timepts'),
    ('compare-response-spacing',
     lambda t: sw.compare(PLANT, _resp(0.5 * np.arange(N)), plot=False), VE,
     'dt'),
    ('nrmse-nan', lambda t: sw.nrmse(Y, _nan_at(1)), VE, 'yhat'),
    ('residuals-model', lambda t: sw.residuals('m', (UL, YL), plot=False),
     TE, 'model'),
    ('residuals-lags', lambda t: sw.residuals(PLANT, (UL, YL), lags=-1,
                                              plot=False), VE, 'lags'),
    ('as_experiments-dt', lambda t: sw.as_experiments(U, Y, dt=np.inf), VE,
     'dt'),
    ('as_experiments-response-dt',
     lambda t: sw.as_experiments(_resp(0.5 * np.arange(N)), dt=1), VE, 'dt'),
    ('identify_linear-response-dt',
     lambda t: sw.identify_linear(_resp(0.5 * np.arange(400)), nb=1, nf=2,
                                  dt=1), VE, 'dt'),
    ('as_experiments-length', lambda t: sw.as_experiments(U, Y[:-1]), VE,
     'y'),
    ('as_experiments-response-uneven',
     lambda t: sw.as_experiments(_resp(np.arange(N) ** 1.2)), VE, 'evenly'),
    ('select_structure-criterion',
     lambda t: sw.select_structure((UL, YL), criterion='bogus'), VE,
     'criterion'),
    ('select_structure-orders',
     lambda t: sw.select_structure((UL, YL), orders=[(1.5, 0, 1, 1)]),
     (TE, VE), 'na'),
    ('select_structure-minimum_phase',
     lambda t: sw.select_structure((UL, YL), minimum_phase='L2'), VE,
     'minimum_phase'),
    ('select_structure-integrators',
     lambda t: sw.select_structure((UL, YL), integrators='x'), VE,
     'integrators'),
    ('select_structure-option-unknown',
     lambda t: sw.select_structure((UL, YL), bogus=1), TE, 'bogus'),
    ('select_structure-option-method',
     lambda t: sw.select_structure((UL, YL), method='bundle',
                                   integrators=1), TE, 'integrators'),
    ('identify-tol-huge',
     lambda t: sw.identify(UL, YL, **ORD, tol=1e308), VE, 'tol'),
    ('identify_linear-tol-one',
     lambda t: sw.identify_linear(UL, YL, nb=1, nf=2, tol=1.0), VE, 'tol'),
    ('refine-tol-huge', lambda t: sw.refine(PLANT, U, Y, tol=1e308), VE,
     'tol'),
    ('identify-minimum_phase',
     lambda t: sw.identify(UL, YL, **ORD, minimum_phase=True), VE,
     'minimum_phase'),
    ('identify-minimum_phase-recursive',
     lambda t: sw.identify(UL, YL, **ORD, method='rpem',
                           minimum_phase='L1'), TE, 'minimum_phase'),
    ('identify-integrators-array',
     lambda t: sw.identify(UL, YL, **ORD, integrators=np.ones(2)), VE,
     'integrators'),
    ('identify-integrator_block',
     lambda t: sw.identify(UL, YL, **ORD, integrator_block='L3'), VE,
     'integrator_block'),
    ('identify-integrator_block-type',
     lambda t: sw.identify(UL, YL, **ORD, integrator_block=['L1']), VE,
     'integrator_block'),
    ('identify_many-datasets', lambda t: sw.identify_many(5, **ORD), TE,
     'datasets'),
    ('identify_many-errors',
     lambda t: sw.identify_many([(UL, YL)], **ORD, errors='bogus'), VE,
     'errors'),
    ('fit_percent-complex', lambda t: sw.fit_percent(Y * 1j, Y), TE, 'y'),
    ('fit_percent-length', lambda t: sw.fit_percent(Y, Y[:-1]), VE, 'yhat'),
    ('max_relative_error-scale',
     lambda t: sw.max_relative_error(Y, Y, scale='bogus'), VE, 'scale'),
    ('parameter_error-length',
     lambda t: sw.parameter_error([1, 2], [1, 2, 3]), VE, 'theta'),
    ('parameter_error-zero',
     lambda t: sw.parameter_error([1, 2], [0, 0]), VE,
     'theta_true is zero.*absolute error'),
    ('parameter_error-nan',
     lambda t: sw.parameter_error([1, 2], [np.nan, 1]), VE,
     'theta_true must be finite'),
    # the paper's examples (maintained elsewhere)
    ('examples.paper_input-n', lambda t: sw.examples.paper_input(100.5), TE,
     'n'),
    ('examples.paper_plant-dt', lambda t: sw.examples.paper_plant(dt=np.inf),
     VE, 'dt'),
    ('examples.add_noise-snr',
     lambda t: sw.examples.add_noise(Y, snr=np.nan), VE, 'snr'),
    ('examples.add_noise-complex',
     lambda t: sw.examples.add_noise(Y + 1j, snr=10), TE, 'y'),
    # data room (maintained elsewhere)
    ('data.excitation-kind',
     lambda t: sw.data.excitation('bogus', 100), VE, 'kind'),
    ('data.excitation-n', lambda t: sw.data.excitation('white', 100.5), TE,
     'n'),
    ('data.servo_drive-loop',
     lambda t: sw.data.servo_drive(U, loop='bogus'), VE, 'loop'),
    ('data.servo_drive-reference',
     lambda t: sw.data.servo_drive(_nan_at(3)), VE, 'reference'),
    ('data.servo_drive-contact',
     lambda t: sw.data.servo_drive(U, contact=0.5), VE, 'contact'),
    ('data.random_case-integrating',
     lambda t: sw.data.random_case(0, integrating='L3'), TE, 'integrating'),
    ('data.ServoDrive-loop', lambda t: sw.data.ServoDrive('torque'), VE,
     'loop'),
    ('data.ServoDrive-n', lambda t: sw.data.ServoDrive(n=0), VE, 'n'),
    ('data.ServoDrive-param', lambda t: sw.data.ServoDrive(mass=3), TE,
     'parameter'),
    ('data.servo_drive-loop-array',
     lambda t: sw.data.servo_drive(U, loop=np.ones(2)), VE, 'loop'),
    ('data.servo_drive-seed',
     lambda t: sw.data.servo_drive(U, seed=2.5), TE, 'seed'),
    ('data.servo_drive-substeps',
     lambda t: sw.data.servo_drive(U, substeps=10 ** 9), VE, 'substeps'),
    ('data.servo_drive-friction-huge',
     lambda t: sw.data.servo_drive(U, Fc=1e308), VE, 'Fc'),
    ('data.ServoDrive-mass-tiny',
     lambda t: sw.data.ServoDrive(M=1e-300), VE, 'M'),
    ('data.ServoDrive-n-huge', lambda t: sw.data.ServoDrive(n=BIG ** 2), VE,
     'n'),
    ('data.ServoDrive-seed', lambda t: sw.data.ServoDrive(seed=-1), VE,
     'seed'),
    ('data.drive_reference-n-huge',
     lambda t: sw.data.drive_reference(BIG ** 2), VE, 'n'),
    ('data.drive_reference-rng',
     lambda t: sw.data.drive_reference(100, rng='a'), TE, 'rng'),
    ('data.drive_reference-dt',
     lambda t: sw.data.drive_reference(100, dt=1e-308), VE, 'dt'),
    ('data.drive_case-n_val-huge',
     lambda t: sw.data.drive_case(0, n=100, n_val=BIG ** 2), VE, 'n_val'),
    ('data.random_drive-seed', lambda t: sw.data.random_drive(-1), VE,
     'seed'),
    ('data.drive_reference-n',
     lambda t: sw.data.drive_reference(-5), VE, 'n'),
]


def _params():
    out = []
    for row in ROWS:
        name, call, error, match = row[:4]
        marks = row[4] if len(row) > 4 else ()
        out.append(pytest.param(call, error, match, id=name, marks=marks))
    return out


@pytest.fixture(scope='module', autouse=True)
def _compiled_servo_step():
    """Compile the servo controller's step once, before the timed calls:
    a row whose plant fails after a few samples runs it, and numba's
    first compilation on a fresh machine (about 2 s on CI's) is not work
    done on the bad input."""
    sw.servo_controller(PLANT).step(0.0, 0.0)


@pytest.mark.parametrize('call, error, match', _params())
def test_bad_input_is_refused_with_a_clear_message(call, error, match,
                                                   tmp_path):
    start = time.perf_counter()
    with pytest.raises(error, match=match) as info:
        call(tmp_path)
    elapsed = time.perf_counter() - start
    assert elapsed < TIME_LIMIT, f"took {elapsed:.1f} s to refuse"
    # the message is for users: no private names from inside the package
    assert '_checks' not in str(info.value)


def test_every_public_callable_has_a_row():
    """A new public function or class gets rows in the table."""
    covered = {row[0].split('-')[0].split('.')[0] for row in ROWS}
    skip = {  # result classes built by the package, not by users
        'IdentificationResult', 'LinearIdentificationResult',
        'CompareResult', 'CompareResultList', 'CompensationDemo',
        'TrackingController', 'SandwichCompensator', 'SandwichSystem',
        'ResidualResult', 'StructureTable', 'Experiments', 'theta_labels',
        'ClosedLoopSystem',
    } | {n for n in sw.__all__ if n.endswith('Warning')}
    public = {n for n in sw.__all__
              if callable(getattr(sw, n)) and n not in skip}
    missing = sorted(public - covered - {'Sandwich'})
    assert not missing, f"no bad-input rows for {missing}"
