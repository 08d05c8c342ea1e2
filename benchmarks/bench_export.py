"""Cost of one step of an exported controller: C, C through ctypes, Python.

For a few servo designs (`sw.servo_controller`) and a compensator, this
exports the C (`sw.export_c`, double and float), compiles it with the
issue's flags plus a small timing harness (a C loop calling ``step`` for
a whole recorded closed loop, so only the step is timed), and prints the
nanoseconds per step of

- the compiled C step, called in a C loop (double and float);
- the same C step called from Python through ctypes, one call a sample;
- the Python ``ctrl.step`` (the compiled numba kernel);

with the ratios side by side. Each figure is the median of repeats.
Targets of the issue: C <= 1 us, ctypes <= 5 us.

Run: python benchmarks/bench_export.py [--repeat 7]
"""

import argparse
import ctypes
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import types

import numpy as np
import control as ct

sys.path.insert(0, os.path.dirname(__file__))
import sandwichctl as sw                                   # noqa: E402
from sandwichctl.design.loop import servo_loop            # noqa: E402
from _timing import median_time, print_table               # noqa: E402

FLAGS = ['-std=c99', '-Wall', '-Wextra', '-Werror', '-pedantic', '-O2',
         '-shared', '-fPIC']
DT = 1e-3
N_C = 200_000          # steps of one timed C loop
N_PY = 20_000          # steps of one timed Python loop


def cases():
    """name: (plant for the recorded loop, controller or compensator)."""
    bl = sw.Backlash(1.0, 1.2, 0.05, 0.06)
    paper = sw.examples.paper_plant()
    nmp = sw.SandwichSystem(ct.tf([1.0], [1, -0.5], DT), bl,
                            ct.tf([-0.2, 0.5], [1, -0.7, 0.1], DT))
    linear = ct.tf([0.02, 0.01], np.polymul([1, -1], [1, -0.6]), DT)
    # an identification result of the paper's plant with half its band:
    # the design estimates the band's gain online
    co = paper.coefficients
    half = sw.SandwichSystem.from_coefficients(
        **{**co, 'D1': 0.5 * co['D1'], 'D2': 0.5 * co['D2']}, dt=paper.dt)
    result = types.SimpleNamespace(model=half, success=True, fit=95.0,
                                   linear=dict(model=paper.L1 * paper.L2,
                                               fit=90.0))
    return {
        'linear, type 1': (linear, sw.servo_controller(linear)),
        'sandwich (paper)': (paper, sw.servo_controller(paper)),
        'sandwich, jump 5': (paper, sw.servo_controller(paper,
                                                         jump_samples=5)),
        'sandwich, NMP L2': (nmp, sw.servo_controller(nmp)),
        'sandwich, band online': (paper, sw.servo_controller(result)),
        'compensator': (paper, sw.sandwich_compensator(paper,
                                                       smoothing=0.05)),
    }


HARNESS = """\
#include "{n}.h"
/* Time the step alone: run it over recorded signals. */
{T} {n}_bench({n}_state *s, const {T} *r, const {T} *y, {T} *u, long n)
{{
    long k;
    (void)y;                  /* a compensator has one input */
    for (k = 0; k < n; ++k)
        u[k] = {call};
    return u[n - 1];
}}
"""


def build(obj, folder, name, dtype):
    """Export, compile with the harness, load: the ctypes library."""
    T = dtype
    call = (f"{name}_step(s, r[k], y[k])"
            if isinstance(obj, sw.ServoController) else
            f"{name}_step(s, r[k])")
    _, source = sw.export_c(obj, folder, name, dtype)
    harness = os.path.join(folder, f"{name}_bench.c")
    with open(harness, 'w') as f:
        f.write(HARNESS.format(n=name, T=T, call=call))
    lib = os.path.join(folder, f"lib{name}.so")
    subprocess.run(['gcc', *FLAGS, '-o', lib, str(source), harness],
                   check=True)
    return ctypes.CDLL(lib)


def signals(plant, obj):
    """(r_ahead, y) of a recorded closed loop (v_d for a compensator)."""
    r = sw.servo_reference(DT, 0.5)
    if isinstance(obj, sw.ServoController):
        y, _ = servo_loop(plant, r, obj)
        d = obj.preview
        return np.concatenate([r[d:], np.full(d, r[-1])]), y
    return r, None


def time_c_loop(lib, name, dtype, state, r, y, repeat):
    c = ctypes.c_double if dtype == 'double' else ctypes.c_float
    np_type = np.float64 if dtype == 'double' else np.float32
    reps = -(-N_C // r.size)
    r = np.ascontiguousarray(np.tile(r, reps)[:N_C], np_type)
    y = np.ascontiguousarray(np.tile(r if y is None else y, reps)[:N_C],
                             np_type)
    u = np.empty(N_C, np_type)
    bench = getattr(lib, f"{name}_bench")
    ptr = ctypes.POINTER(c)
    bench.argtypes = [ctypes.c_void_p, ptr, ptr, ptr, ctypes.c_long]
    bench.restype = c
    reset = getattr(lib, f"{name}_reset")
    reset.argtypes = [ctypes.c_void_p]

    def run():
        reset(state)
        bench(state, r.ctypes.data_as(ptr), y.ctypes.data_as(ptr),
              u.ctypes.data_as(ptr), N_C)
    return median_time(run, repeat) / N_C


def time_ctypes(lib, name, state, r, y, repeat):
    step = getattr(lib, f"{name}_step")
    step.restype = ctypes.c_double
    r, y = r[:N_PY].tolist(), None if y is None else y[:N_PY].tolist()
    if y is None:
        step.argtypes = [ctypes.c_void_p, ctypes.c_double]

        def run():
            for a in r:
                step(state, a)
    else:
        step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double]

        def run():
            for a, b in zip(r, y):
                step(state, a, b)
    return median_time(run, repeat) / len(r)


def time_python(obj, r, y, repeat):
    r = r[:N_PY].tolist()
    if y is None:                 # a compensator: its compiled kernel
        v = np.asarray(r)
        return median_time(lambda: obj.simulate(v), repeat) / len(r)
    y = y[:N_PY].tolist()
    step = obj.step

    def run():
        obj.reset()
        for a, b in zip(r, y):
            step(a, b)
    return median_time(run, repeat) / len(r)


def cpu_name():
    try:
        with open('/proc/cpuinfo') as f:
            for line in f:
                if line.startswith('model name'):
                    return line.split(':', 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or 'unknown CPU'


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--repeat', type=int, default=7)
    args = parser.parse_args()
    if shutil.which('gcc') is None:
        sys.exit("gcc is not on the PATH: nothing to compile the export with")
    gcc = subprocess.run(['gcc', '--version'], capture_output=True,
                         text=True).stdout.splitlines()[0]
    print(f"{platform.machine()}, {cpu_name()}; "
          f"{gcc}; flags {' '.join(FLAGS)}")
    print(f"ns per step, median of {args.repeat} repeats (C: loops of "
          f"{N_C} steps; ctypes and Python: {N_PY} calls)\n")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for i, (label, (plant, obj)) in enumerate(cases().items()):
            r, y = signals(plant, obj)
            libs = {d: build(obj, folder, f"c{i}{d[0]}", d)
                    for d in ('double', 'float')}
            size = getattr(libs['double'], f"c{i}d_state_size")
            size.restype = ctypes.c_size_t
            state = ctypes.create_string_buffer(size())
            c_d = time_c_loop(libs['double'], f"c{i}d", 'double', state, r,
                              y, args.repeat)
            c_f = time_c_loop(libs['float'], f"c{i}f", 'float', state, r, y,
                              args.repeat)
            getattr(libs['double'], f"c{i}d_reset")(state)
            via = time_ctypes(libs['double'], f"c{i}d", state, r, y,
                              args.repeat)
            py = time_python(obj, r, y, args.repeat)
            rows.append([label, obj.nstates, f"{c_d * 1e9:.0f}",
                         f"{c_f * 1e9:.0f}", f"{via * 1e9:.0f}",
                         f"{py * 1e9:.0f}", f"{via / c_d:.0f}x",
                         f"{py / c_d:.0f}x"])
    print_table(['case', 'states', 'C double', 'C float', 'ctypes',
                 'Python', 'ctypes/C', 'Python/C'], rows)
    print("\nPython: ctrl.step (numba kernel) per call; for the "
          "compensator, comp.simulate per sample (it has no step).")


if __name__ == '__main__':
    main()
