"""export_c: the exported C compiles warning-free and steps like Python.

Every controller of `SERVOS` and compensator of `COMPENSATORS` is
exported in double and in float, compiled with the system C compiler
under the issue's flags (one call for all) and loaded with ctypes. The
closed loops run the Python controller against its model as plant
(`servo_loop`, 5,000+ samples); the C controller and ``ctrl.step`` are
then fed the same (r_ahead, y) sequence.

Measured on x86-64 with gcc 12 (``-std=c99 -O2``): the double C step is
bit for bit the Python step on every case (asserted); the float step
stays within `FLOAT_BOUND` of the peak |u| without smoothing and within
`FLOAT_BOUND_SMOOTHED` with it (worst cases measured: see the constants).
"""

import ctypes
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import control as ct
import pytest

import sandwichctl as sw
from sandwichctl.design.loop import servo_loop
from sandwichctl.design._servo_kernel import EARLY, IX

GCC = shutil.which('gcc')
FLAGS = ['-std=c99', '-Wall', '-Wextra', '-Werror', '-pedantic', '-O2',
         '-shared', '-fPIC']
pytestmark = pytest.mark.skipif(
    GCC is None, reason="no C compiler: gcc is not on the PATH, so the "
                        "exported C cannot be compiled and compared")

#: double C against Python: relative to the peak |u| of the run
DOUBLE_TOL = 1e-9
#: float C against double C, relative to the peak |u| of the run, with
#: the worst case measured (gcc 12, x86-64): without smoothing, the float
#: rounding of r, y, the coefficients and the states, 6.8e-5 (SLOW, in the
#: realization export_c picks for float)
FLOAT_BOUND = 1e-4
#: with a smoothed backlash inverse, whose memory adds up the steps of
#: v_d smaller than the smoothing width, differently quantised in float:
#: 1.6e-4 (the NMP-L2 ZPETC design while its feedforward settles; 2.7e-3
#: when first measured)
FLOAT_BOUND_SMOOTHED = 5e-3

DT = 1e-3
BL = sw.Backlash(1.0, 1.2, 0.05, 0.06)
PAPER = sw.examples.paper_plant()
INTEGRATING = sw.SandwichSystem(ct.tf([0.1], [1, -1], DT), BL,
                                ct.tf([0.4, 0], [1, -0.6], DT))
NMP_L1 = sw.SandwichSystem(ct.tf([0.3, 0.5], [1, -0.5, 0.06], DT), BL,
                           ct.tf([0.5], [1, -0.5], DT))     # zero -1.67
NMP_L2 = sw.SandwichSystem(ct.tf([1.0], [1, -0.5], DT), BL,
                           ct.tf([-0.2, 0.5], [1, -0.7, 0.1], DT))  # 2.5
LINEAR = ct.tf([0.5, 0.2], [1, -1.1, 0.3], 1)
LINEAR_INT = ct.tf([0.02, 0.01], np.polymul([1, -1], [1, -0.6]), DT)
#: the servo tutorial's identified linear model of the position drive
#: (poles 0.93 +- 0.11j, 0.975, 0.9935; zeros 0.9936, 0.878): its inverse's
#: output is the small difference of terms 200 times larger, and in float
#: its canonical realization erred by 20 % of the peak of u (a balanced
#: one is exported)
SLOW = ct.tf([5.371508800893353e-06, -1.0053921149621163e-05,
              4.68660262081113e-06, 0.0],
             [1.0, -3.8373176829349696, 5.53276211255521,
              -3.5530357058280644, 0.8575939246699845], DT)
#: the tutorial's identified sandwich of the same drive: its design's
#: linear feedforward had 13 states (two poles, the rest delays for the
#: band jump's lead), whose float canonical form erred by 13 % of the peak
#: of u; the delays are now read from the reference's delay line
SLOW_SANDWICH = sw.SandwichSystem.from_coefficients(
    a=[-1.8768489029989401, 0.8799092871335403], b=[1.0, -0.9493643669108316],
    c=[-1.8281921553733513, 0.8301581478730197], d=[1.0, -0.98807530794234],
    q1=1, q2=0, m1=1.5889863773096116e-05, m2=1.5853399046339028e-05,
    D1=1.2031384604261963, D2=1.1977831168054225, dt=DT)

#: name: (model the loop runs on, controller)
SERVOS = {
    'linear': lambda: (LINEAR, sw.servo_controller(LINEAR)),
    'linear_integrating': lambda: (LINEAR_INT,
                                   sw.servo_controller(LINEAR_INT)),
    'feedback_only': lambda: (LINEAR, sw.servo_controller(
        LINEAR, feedforward=None)),
    'slow_feedforward': lambda: (SLOW, sw.servo_controller(SLOW)),
    'sandwich': lambda: (PAPER, sw.servo_controller(PAPER)),
    'sandwich_exact': lambda: (PAPER, sw.servo_controller(PAPER,
                                                          smoothing=0.0)),
    'sandwich_jump': lambda: (PAPER, sw.servo_controller(
        PAPER, jump_samples=5, band_fraction=0.9)),
    'integrating_L1': lambda: (INTEGRATING,
                               sw.servo_controller(INTEGRATING)),
    'nmp_L1': lambda: (NMP_L1, sw.servo_controller(NMP_L1)),
    'nmp_L2': lambda: (NMP_L2, sw.servo_controller(NMP_L2, smoothing=0.0,
                                                   jump_samples=3)),
    'nmp_L2_zpetc': lambda: (NMP_L2, sw.servo_controller(
        NMP_L2, feedforward='zpetc')),
    'sandwich_adapt': lambda: (PAPER, sw.servo_controller(_identified())),
    'slow_sandwich': lambda: (SLOW_SANDWICH, sw.servo_controller(
        _result(SLOW_SANDWICH, SLOW))),
    'guarded': lambda: (PAPER, sw.servo_controller(_identified(),
                                                   hunting=0.05)),
}
COMPENSATORS = {
    'comp': lambda: sw.sandwich_compensator(PAPER),
    'comp_smooth': lambda: sw.sandwich_compensator(PAPER, smoothing=0.05,
                                                   band_fraction=0.9),
    'comp_nmp': lambda: sw.sandwich_compensator(NMP_L1, approximate=True),
    'comp_integrating': lambda: sw.sandwich_compensator(INTEGRATING,
                                                        smoothing=0.01),
}


def _result(model, baseline):
    """An identification-like result: its design estimates the band's
    gain online and inverts the sandwich's own mbar L1 L2."""
    import types
    return types.SimpleNamespace(model=model, success=True, fit=95.0,
                                 linear=dict(model=baseline, fit=90.0))


def _identified():
    """An identification-like result around the paper's plant with half
    its band."""
    co = PAPER.coefficients
    half = sw.SandwichSystem.from_coefficients(
        **{**co, 'D1': 0.5 * co['D1'], 'D2': 0.5 * co['D2']}, dt=PAPER.dt)
    return _result(half, PAPER.L1 * PAPER.L2)


def _reference(model):
    """5,000+ samples with steps, holds, ramps, reversals and a sine."""
    travel = (2.0 if model is PAPER or model is LINEAR else
              1e-3 if model is SLOW or model is SLOW_SANDWICH else 0.5)
    return sw.servo_reference(DT, travel)[:6000]


@pytest.fixture(scope='module')
def built(tmp_path_factory):
    """Every case exported in both dtypes, compiled into one library."""
    folder = tmp_path_factory.mktemp('export')
    objects, sources = {}, []
    for name, make in {**SERVOS, **COMPENSATORS}.items():
        objects[name] = make()
        for dtype in ('double', 'float'):
            obj = objects[name][1] if name in SERVOS else objects[name]
            c_name = f"{name}_{dtype[0]}"
            sources.append(sw.export_c(obj, folder, c_name, dtype)[1])
    lib = folder / 'libexport.so'
    out = subprocess.run([GCC, *FLAGS, '-o', str(lib)] + [str(s) for s in
                                                          sources],
                         capture_output=True, text=True)
    assert out.returncode == 0 and not out.stderr, out.stderr
    return folder, ctypes.CDLL(str(lib)), objects


class CStep:
    """ctypes access to one exported controller."""

    def __init__(self, lib, name, dtype, inputs=2):
        c = ctypes.c_double if dtype == 'double' else ctypes.c_float
        self.size = getattr(lib, f"{name}_state_size")
        self.size.restype = ctypes.c_size_t
        self.state = ctypes.create_string_buffer(self.size())
        self._reset = getattr(lib, f"{name}_reset")
        self._reset.argtypes = [ctypes.c_void_p]
        self._reset.restype = None
        self.step = getattr(lib, f"{name}_step")
        self.step.argtypes = [ctypes.c_void_p] + [c] * inputs
        self.step.restype = c
        if inputs == 2:
            self._reset_at = getattr(lib, f"{name}_reset_at")
            self._reset_at.argtypes = [ctypes.c_void_p, c, c]
            self._reset_at.restype = None
        self.reset()

    def reset(self, y=None, u=None):
        if y is None:
            self._reset(self.state)
        else:
            self._reset_at(self.state, y, u)

    def run(self, *signals):
        return np.array([self.step(self.state, *values)
                         for values in zip(*signals)])


def _loop(model, ctrl):
    """The Python closed loop: (r_ahead, y, u) of 5,000+ samples."""
    r = _reference(model)
    y, u = servo_loop(model, r, ctrl)
    d = ctrl.preview
    r_ahead = np.concatenate([r[d:], np.full(d, r[-1])])
    return r_ahead, y, u


def _python(ctrl, r_ahead, y):
    ctrl.reset()
    return np.array([ctrl.step(a, b) for a, b in zip(r_ahead, y)])


@pytest.mark.parametrize('case', list(SERVOS))
def test_servo_c_is_the_python_step_in_a_closed_loop(built, case):
    folder, lib, objects = built
    model, ctrl = objects[case]
    r_ahead, y, u_loop = _loop(model, ctrl)
    assert r_ahead.size >= 5000
    u_py = _python(ctrl, r_ahead, y)
    np.testing.assert_array_equal(u_py, u_loop)        # the same controller
    u_c = CStep(lib, f"{case}_d", 'double').run(r_ahead, y)
    peak = np.max(np.abs(u_py))
    np.testing.assert_allclose(u_c, u_py, rtol=DOUBLE_TOL,
                               atol=DOUBLE_TOL * peak)
    # same operations in the same order: the same doubles (gcc -std=c99
    # fuses no multiply-add, and neither does numba without fastmath)
    np.testing.assert_array_equal(u_c, u_py)
    u_f = CStep(lib, f"{case}_f", 'float').run(r_ahead, y)
    bound = FLOAT_BOUND_SMOOTHED if ctrl.smoothing > 0 else FLOAT_BOUND
    assert np.max(np.abs(u_f - u_c)) <= bound * peak


def test_the_cases_cover_what_the_issue_asks(built):
    _, _, objects = built
    ctrls = {k: objects[k][1] for k in SERVOS}
    assert not ctrls['linear'].compensates
    assert ctrls['sandwich'].smoothing > 0
    assert ctrls['sandwich_exact'].smoothing == 0
    assert ctrls['sandwich_jump'].jump_samples == 5          # rate-limited
    assert ctrls['sandwich_jump']._p[ctrls['sandwich_jump']._ix[9] + 6] > 0
    assert ctrls['integrating_L1'].compensates
    assert np.any(np.abs(INTEGRATING.L1.poles() - 1) < 1e-12)
    for model, block in ((NMP_L1, 'L1'), (NMP_L2, 'L2')):
        assert np.any(np.abs(getattr(model, block).zeros()) > 1)
    assert ctrls['nmp_L2'].preview >= 5
    adapting = ctrls['sandwich_adapt']
    assert adapting.adapts and not any(
        c.adapts for k, c in ctrls.items()
        if k not in ('sandwich_adapt', 'guarded', 'slow_sandwich'))
    slow = ctrls['slow_sandwich']          # a late linear feedforward
    at = dict(zip(IX, slow._ix))
    assert slow.adapts and at['d_lin'] > 5 and at['d_other'] > 5
    assert ctrls['guarded'].hunting and not any(
        c.hunting for k, c in ctrls.items() if k != 'guarded')
    _loop(PAPER, adapting)
    assert abs(adapting.band_gain - 1.0) > 0.05     # the estimate moves
    # the smoothed branch of the inverse is taken (steps of its input
    # smaller than the width) and so are the exact one and holds
    ctrl = ctrls['sandwich']
    r_ahead = _loop(PAPER, ctrl)[0]
    off, n = ctrl._ix[7], ctrl._ix[3]                  # the pre block
    A, B, C, D = np.split(ctrl._p[off:off + n * n + 2 * n + 1],
                          np.cumsum([n * n, n, n]))
    s, w_ahead = np.zeros(n), np.empty(r_ahead.size)
    for k, r in enumerate(r_ahead):
        w_ahead[k] = D[0] * r + C @ s
        s = A.reshape(n, n) @ s + B * r
    m1, m2, D1, D2, width = ctrl._p[ctrl._ix[9]:ctrl._ix[9] + 5]
    _, v_hat = sw.backlash_inverse_response(w_ahead, m1, m2, D1, D2,
                                            smoothing=width,
                                            return_expected=True)
    dv = np.abs(w_ahead - np.r_[0.0, v_hat[:-1]])
    assert np.sum((dv > 0) & (dv < width)) > 100
    assert np.sum(dv >= width) > 100 and np.sum(dv == 0) > 100


def test_the_hunting_guard_steps_the_same_in_c(built):
    # y swinging in the holds of the reference fires the guard: in C as
    # in Python, bit for bit in double
    _, lib, objects = built
    model, ctrl = objects['guarded']
    r_ahead, y, _ = _loop(model, ctrl)
    rng = np.random.default_rng(3)
    y = y + 0.2 * np.sign(np.sin(np.arange(y.size) / 7.0)) \
        + 0.01 * rng.standard_normal(y.size)
    u_py = _python(ctrl, r_ahead, y)
    assert ctrl.feedback_gain == ctrl.hunting['floor']
    u_c = CStep(lib, 'guarded_d', 'double').run(r_ahead, y)
    np.testing.assert_array_equal(u_c, u_py)
    u_f = CStep(lib, 'guarded_f', 'float').run(r_ahead, y)
    assert np.max(np.abs(u_f - u_c)) <= FLOAT_BOUND_SMOOTHED * \
        np.max(np.abs(u_c))
    # y swinging only while the reference moves fires it too (the error's
    # reversals in a move)
    _, y, _ = _loop(model, ctrl)
    moving = np.r_[False, np.diff(r_ahead) != 0]
    y = y + 0.2 * moving * np.sign(np.sin(np.arange(y.size) / 3.0))
    u_py = _python(ctrl, r_ahead, y)
    assert ctrl.feedback_gain < 1.0
    u_c = CStep(lib, 'guarded_d', 'double').run(r_ahead, y)
    np.testing.assert_array_equal(u_c, u_py)
    # ... and y swinging only in the holds' early windows (from EARLY
    # settle samples in, before the settle)
    _, y, _ = _loop(model, ctrl)
    r_now = np.r_[np.zeros(ctrl.preview), r_ahead][:r_ahead.size]
    held, t, last = np.zeros(y.size), 0, 0.0     # r(-1) is taken as 0
    for k, r in enumerate(r_now):
        t, last = (t + 1 if r == last else 0), r
        held[k] = t
    settle = ctrl.hunting['settle']
    early = (held >= EARLY * settle) & (held < settle - 1)
    y = y + 0.2 * early * np.sign(np.sin(np.arange(y.size) / 3.0))
    u_py = _python(ctrl, r_ahead, y)
    assert ctrl.feedback_gain < 1.0
    u_c = CStep(lib, 'guarded_d', 'double').run(r_ahead, y)
    np.testing.assert_array_equal(u_c, u_py)


@pytest.mark.parametrize('case', list(COMPENSATORS))
def test_compensator_c_is_the_compiled_compensator(built, case):
    """v_d with ramps, reversals, holds and steps smaller than the
    smoothing width: C against `SandwichCompensator.simulate`."""
    _, lib, objects = built
    comp = objects[case]
    rng = np.random.default_rng(26)
    steps = rng.normal(0, 0.05, 6000) * (rng.random(6000) < 0.7)
    v_d = np.cumsum(steps) + 0.5 * np.sin(np.arange(6000) / 300)
    u_py = comp.simulate(v_d).outputs
    u_c = CStep(lib, f"{case}_d", 'double', inputs=1).run(v_d)
    np.testing.assert_array_equal(u_c, u_py)
    u_f = CStep(lib, f"{case}_f", 'float', inputs=1).run(v_d)
    bound = FLOAT_BOUND_SMOOTHED if comp.smoothing > 0 else FLOAT_BOUND
    assert np.max(np.abs(u_f - u_c)) <= bound * np.max(np.abs(u_c))


def test_reset_and_operating_point(built, tmp_path):
    """Raw units: the C controller subtracts y0 and adds u0 like Python;
    reset restores the exported operating point, reset_at moves it like
    ``ctrl.reset(y=..., u=...)``."""
    ctrl = sw.servo_controller(PAPER, operating_point=(0.25, 1000.0))
    _, source = sw.export_c(ctrl, tmp_path, 'raw')
    lib_path = tmp_path / 'libraw.so'
    subprocess.run([GCC, *FLAGS, '-o', str(lib_path), str(source)],
                   check=True)
    c = CStep(ctypes.CDLL(str(lib_path)), 'raw', 'double')
    r_ahead, y, _ = _loop(PAPER, sw.servo_controller(PAPER))
    raw_r, raw_y = r_ahead[:800] + 1000.0, y[:800] + 1000.0
    u_py = _python(ctrl, raw_r, raw_y)
    np.testing.assert_array_equal(c.run(raw_r, raw_y), u_py)
    # at rest at the operating point, u is u0
    assert c.run([1000.0], [1000.0])[0] != 0.25            # memory kept
    c.reset()
    ctrl.reset()
    assert c.run([1000.0], [1000.0])[0] == 0.25
    # a bumpless start elsewhere
    c.reset(y=1003.0, u=0.4)
    ctrl.reset(y=1003.0, u=0.4)
    np.testing.assert_array_equal(c.run(raw_r + 3, raw_y + 3),
                                  [ctrl.step(a, b) for a, b in
                                   zip(raw_r + 3, raw_y + 3)])
    assert f"y0 = {1000.0:.17g}" in (tmp_path / 'raw.h').read_text()
    # a plain reset drops the bumpless point for the design's, in both
    c.reset()
    ctrl.reset()
    assert ctrl.operating_point == (0.25, 1000.0)
    assert c.run([1000.0], [1000.0])[0] == ctrl.step(1000.0, 1000.0) == 0.25
    # and an export after a bumpless reset carries the design's point
    ctrl.reset(y=1003.0, u=0.4)
    sw.export_c(ctrl, tmp_path, 'again')
    again = (tmp_path / 'again.h').read_text()
    assert f"y0 = {1000.0:.17g}" in again and 'u0 = 0.25' in again


def test_the_code_is_plain_c99_and_documented(built):
    folder, _, objects = built
    header = (folder / 'sandwich_d.h').read_text()
    source = (folder / 'sandwich_d.c').read_text()
    includes = set(re.findall(r'#include\s+(\S+)', header + source))
    assert includes <= {'<math.h>', '<stddef.h>', '<string.h>',
                        '"sandwich_d.h"'}
    # no allocation, no I/O, no file-scope variable that is not const
    assert not re.search(r'malloc|calloc|free\(|printf', source)
    assert not re.search(r'^(static )?(double|float|int|size_t) \w+ *[=;[]',
                         source, re.M)
    assert re.search(r'^static const double sandwich_d_fb_A\[', source,
                     re.M)
    ctrl = objects['sandwich'][1]
    for text in ('Sample time: 1 s', f"Preview: {ctrl.preview}",
                 'u0 = 0, y0 = 0', 'SandwichSystem paper', 'm2 = 1.2',
                 'backlash inverse on the reference',
                 f"sandwichctl {sw.__version__}",
                 'double sandwich_d_step(sandwich_d_state *s, '
                 'double r_ahead, double y);',
                 'size_t sandwich_d_state_size(void);',
                 'void sandwich_d_reset(sandwich_d_state *s);'):
        assert text in header, text
    # exact coefficients: every double of the design is in the source
    p = ctrl._p[ctrl._p != 0]
    assert all(f"{v:.17g}" in source for v in p)
    flt = (folder / 'sandwich_f.c').read_text()
    assert 'double' not in flt and 'fabsf' in flt
    assert 'float sandwich_f_step(sandwich_f_state *s, float r_ahead, ' \
           'float y);' in (folder / 'sandwich_f.h').read_text()


def test_a_program_uses_the_header_alone(tmp_path):
    """A main loop as in docs/deploy.md: static state, no other file."""
    sw.export_c(sw.servo_controller(LINEAR_INT), tmp_path, 'axis', 'float')
    main = tmp_path / 'main.c'
    main.write_text(
        '#include "axis.h"\n'
        'static axis_state s;\n'
        'int main(void)\n{\n'
        '    float y = 0.0f, u = 0.0f;\n'
        '    int k;\n'
        '    axis_reset(&s);\n'
        '    for (k = 0; k < 100; ++k) {\n'
        '        u = axis_step(&s, 1.0f, y);\n'
        '        y += 0.001f * u;\n'
        '    }\n'
        '    return sizeof s == axis_state_size() && u == u ? 0 : 1;\n'
        '}\n')
    exe = tmp_path / 'main'
    subprocess.run([GCC, *FLAGS[:-2], '-o', str(exe), str(main),
                    str(tmp_path / 'axis.c')], check=True)
    assert subprocess.run([str(exe)]).returncode == 0


@pytest.mark.parametrize('kwargs, error, match', [
    (dict(obj=PAPER), TypeError, 'obj must be a ServoController'),
    (dict(name='servo-1'), ValueError, 'C identifier'),
    (dict(name='double'), ValueError, 'C keyword'),
    (dict(name=3), TypeError, 'name'),
    (dict(name='math'), ValueError, 'shadows the standard header'),
    (dict(name='Math'), ValueError, 'shadows the standard header <math'),
    (dict(dtype='float64'), ValueError, "dtype must be 'double' or 'float'"),
    (dict(directory=3.5), TypeError, 'directory'),
])
def test_bad_arguments(tmp_path, kwargs, error, match):
    args = dict(obj=sw.servo_controller(LINEAR), directory=tmp_path)
    args.update(kwargs)
    with pytest.raises(error, match=match):
        sw.export_c(**args)


def test_directory_must_be_a_writable_folder(tmp_path):
    ctrl = sw.servo_controller(LINEAR)
    (tmp_path / 'file').write_text('')
    with pytest.raises(ValueError, match='is a file'):
        sw.export_c(ctrl, tmp_path / 'file')
    with pytest.raises(ValueError, match='cannot be created'):
        sw.export_c(ctrl, tmp_path / 'file' / 'sub')
    made = sw.export_c(ctrl, tmp_path / 'new' / 'dir')
    assert all(p.exists() for p in made)


def test_the_deploy_page_compiles_and_runs(tmp_path, monkeypatch):
    """docs/deploy.md: its Python example runs, and its main loop compiles
    against the header it exports (with a stub hardware layer)."""
    page = (Path(__file__).resolve().parents[1] / 'docs' / 'deploy.md')
    text = page.read_text()
    python = re.findall(r'```python\n(.*?)```', text, re.S)[0]
    monkeypatch.setattr('tempfile.mkdtemp', lambda: str(tmp_path))
    exec(python, {})
    main = re.findall(r'```c\n(#include "axis.h".*?)```', text, re.S)[0]
    (tmp_path / 'main.c').write_text(
        main + 'long encoder_read(void) { return 3; }\n'
        'float trajectory_next(void) { return 4.0f; }\n'
        'static float last;\n'
        'void drive_write(float u) { last = u; }\n'
        'int main(void)\n{\n    control_init();\n    control_tick();\n'
        '    return last == last ? 0 : 1;\n}\n')
    exe = tmp_path / 'main'
    subprocess.run([GCC, *FLAGS[:-2], '-o', str(exe),
                    str(tmp_path / 'main.c'), str(tmp_path / 'axis.c')],
                   check=True)
    assert subprocess.run([str(exe)]).returncode == 0


def test_any_model_name_gives_a_valid_comment(tmp_path):
    """Names end up in the header's comment: no comment end, no trigraph,
    ASCII only."""
    model = sw.SandwichSystem(PAPER.L1, PAPER.backlash, PAPER.L2,
                              name='µ-axis */ ??= ??/')
    header, source = sw.export_c(sw.sandwich_compensator(model), tmp_path,
                                 'odd')
    text = header.read_text(encoding='ascii')
    assert '*/ ?' not in text and '??' not in text
    subprocess.run([GCC, *FLAGS, '-o', str(tmp_path / 'odd.so'),
                    str(source)], check=True)


def test_a_directory_under_the_home_is_expanded(tmp_path, monkeypatch):
    # '~/fw' made a folder literally named '~' in the working directory
    monkeypatch.setenv('HOME', str(tmp_path))
    monkeypatch.chdir(tmp_path)
    sw.export_c(sw.servo_controller(ct.tf([0.1], [1, -0.9], 0.01)), '~/fw',
                name='axis')
    assert (tmp_path / 'fw' / 'axis.c').is_file()
    assert not (tmp_path / '~').exists()
