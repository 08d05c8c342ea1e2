"""Record the identified models, to check a refactoring bit for bit.

Runs ``sw.identify`` on the cases of the six robustness families
(`bench_robustness.py --cases 80 --seed 0..5`; the reference
``sw.refine(case.plant, u, y)`` too), on the drive cases
(`bench_drive.py --seeds 3`: ``identify`` and ``identify_linear``) and on
the paper's example (`bench_identify_speed.py` (a): 'oe' noise-free and at
SNR 46.5, and the bundle recursion), and saves every model's coefficients,
``success``, ``message`` and cost with full precision in one ``.npz``.
``--compare`` runs them again and lists every array that differs (exact
equality, NaN equal to NaN); nothing listed means bit for bit.

Run: python benchmarks/record_models.py --save before.npz [--families 6]
     python benchmarks/record_models.py --compare before.npz
"""

import os

for _var in ('OMP_NUM_THREADS', 'OPENBLAS_NUM_THREADS', 'MKL_NUM_THREADS',
             'NUMBA_NUM_THREADS'):
    os.environ.setdefault(_var, '1')

import argparse                                            # noqa: E402
import multiprocessing                                     # noqa: E402
import sys                                                 # noqa: E402
import warnings                                            # noqa: E402

import numpy as np                                         # noqa: E402

import sandwichctl as sw                                   # noqa: E402
from sandwichctl.data import random_case, family_specs     # noqa: E402

ORDERS = dict(na=2, nb=1, nc=2, nd=1, q1=1, q2=0)


def _model_arrays(prefix, res):
    """{name: array} of one result (model coefficients and verdict)."""
    out = {}
    if isinstance(res, Exception):
        out[prefix + 'error'] = np.array(f"{type(res).__name__}: {res}")
        return out
    m = res.model
    if hasattr(m, 'L1'):
        for blk in ('L1', 'L2'):
            sys_ = getattr(m, blk)
            out[f'{prefix}{blk}.num'] = np.asarray(sys_.num[0][0], float)
            out[f'{prefix}{blk}.den'] = np.asarray(sys_.den[0][0], float)
        out[prefix + 'backlash'] = np.asarray(m.backlash._values, float)
        out[prefix + 'theta'] = np.asarray(res.theta, float)
    else:
        out[prefix + 'num'] = np.asarray(m.num[0][0], float)
        out[prefix + 'den'] = np.asarray(m.den[0][0], float)
    for key in ('success', 'message', 'cost', 'fit'):
        if res.get(key) is not None:
            out[prefix + key] = np.array(res[key])
    return out


def _run(job):
    kind, args = job
    with warnings.catch_warnings(), np.errstate(all='ignore'):
        warnings.simplefilter('ignore')
        if kind == 'family':
            spec = args
            case = random_case(**spec)
            tag = f"family/{spec['seed']}/"
            out = {}
            for name, call in (
                    ('identify/', lambda: sw.identify(case.u, case.y,
                                                      **case.orders)),
                    ('refine/', lambda: sw.refine(case.plant, case.u,
                                                  case.y))):
                try:
                    res = call()
                except Exception as exc:                 # noqa: BLE001
                    res = exc
                out.update(_model_arrays(tag + name, res))
            return out
        if kind == 'drive':
            loop, seed, play = args
            case = sw.data.drive_case(seed, loop=loop, play=play)
            tag = f"drive/{loop}/{seed}/{play}/"
            res = sw.identify(case.u, case.y, **ORDERS, dt=case.dt)
            lin = sw.identify_linear(
                case.u, case.y, nb=3, nf=4, nk=1, dt=case.dt,
                integrators=res.linear['integrators'])
            return {**_model_arrays(tag + 'identify/', res),
                    **_model_arrays(tag + 'linear/', lin)}
        plant = sw.examples.paper_plant()
        u = sw.examples.paper_input(5000, seed=1)
        y = plant.simulate(u).outputs
        out = {}
        for snr in (None, 46.5):
            yy = y if snr is None else sw.examples.add_noise(y, snr,
                                                             seed=1001)
            res = sw.identify(u, yy, **plant.orders)
            out.update(_model_arrays(f'paper/{snr}/identify/', res))
        res = sw.identify(u, y, **plant.orders, method='bundle')
        out.update(_model_arrays('paper/bundle/', res))
        return out


def jobs(families):
    out = [('paper', None)]
    out += [('drive', (loop, seed, play)) for loop in ('position', 'speed')
            for seed in range(3) for play in (0.0, 12e-6, 200e-6)]
    for seed in range(families):
        out += [('family', dict(spec)) for spec in family_specs(80,
                                                                seed=seed)]
    return out


def record(families, processes):
    arrays = {}
    with multiprocessing.Pool(processes) as pool:
        for i, out in enumerate(pool.imap_unordered(_run, jobs(families))):
            arrays.update(out)
            sys.stderr.write(f"\r{i + 1} jobs")
    sys.stderr.write("\n")
    return arrays


def compare(old, new):
    """Names of the arrays that differ (or are in one record only)."""
    diff = sorted(set(old) ^ set(new))
    for key in sorted(set(old) & set(new)):
        a, b = old[key], new[key]
        same = (a.shape == b.shape and a.dtype == b.dtype
                and (np.array_equal(a, b, equal_nan=True)
                     if a.dtype.kind == 'f' else np.array_equal(a, b)))
        if not same:
            diff.append(key)
    return diff


def main():
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--save')
    ap.add_argument('--compare')
    ap.add_argument('--families', type=int, default=6)
    ap.add_argument('--processes', type=int, default=2)
    args = ap.parse_args()
    arrays = record(args.families, args.processes)
    if args.save:
        np.savez(args.save, **arrays)
    if args.compare:
        old = dict(np.load(args.compare))
        if args.families < 6:       # only the families that were run
            old = {k: v for k, v in old.items() if not k.startswith(
                'family/') or k in arrays}
        for key in compare(old, arrays):
            print(key)


if __name__ == '__main__':
    main()
