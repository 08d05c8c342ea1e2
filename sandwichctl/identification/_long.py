"""Long records: the search on the leading samples, the refinement on all
(private).

A drive that logs at 1 to 10 kHz gives millions of samples in an hour.
The search of `_search` (steps 1 to 13) refines several starts to
convergence, polishes the best and hops around it, all on the whole
record: about 25 s on a million samples of the paper's plant, and over a
minute for larger orders. Its job is to find the basin of the best
model, and a leading part of the record finds the same basin; only the
last descent needs every sample, for the statistical precision of the
estimate. So a record of more than `LONG_RECORD` samples is identified
in two stages:

1. the whole search (steps 1 to 13, the integrator decision, its block
   and the held-out check included) on the leading `LONG_HEAD` samples
   (each experiment in proportion to its length, from its own start, so
   its initial conditions are the same; step 8's smoothed path, only a
   way to a start, on the first `PATH_SAMPLES` of them); a backlash
   closed by the held-out check stays closed;
2. on all the samples, with the integrators where stage 1 put them: the
   linear baseline of their count, from stage 1's linear fit (from the
   ARX start, the fit of a million samples took up to 104 iterations on
   random plants, most of them on a plateau; from the leading samples'
   fit 2 to 13 on seven of eight, table (c) of
   benchmarks/bench_long_records.py; it can end in another optimum than
   the ARX start does: a better one on one of the eight, 40 % below),
   Levenberg-Marquardt to convergence from the model of stage 1 (the
   search's ``tol``), and the never-worse-than-linear floor (step 12)
   against that baseline.

The result says so in its message and in ``res.long_record``. The
leading samples must excite the plant: when the input or output of an
experiment is constant there, the whole record is searched as before.
"""

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ._data import leading
from ._search import (Search, Task, search, step1_units,
                      step2_linear_baseline)

__all__ = []

#: Records of more samples than this take the long-record path. Below it
#: the search runs on every sample as it always did (the identified
#: models of shorter records are unchanged). On 200,000 samples of the
#: paper's plant that search takes about 5 s, as long as the long-record
#: path on a million (benchmarks/bench_identify_speed.py, table (b)).
LONG_RECORD = 200_000
#: Leading samples the search of a long record runs on (stage 1): 25
#: times the 2,000 it screens on by default, five times the longest record
#: the search was tuned on.
LONG_HEAD = 50_000
#: Leading samples of stage 1's smoothed path (step 8: a way to a start,
#: which the exact cost then refines on all `LONG_HEAD`). Its finite
#: difference Jacobians and their SVDs cost half of stage 1 on 50,000
#: samples of random plants. On 20,000 stage 1 ends in the same basin or
#: a better one (benchmarks/bench_long_records.py --whole-path-repeat).
PATH_SAMPLES = 20_000
#: Threads of the long-record path: stage 2's linear baseline beside
#: stage 1, and in stage 1 the starts of step 6, the relocations of step
#: 9 and the finite differences of step 8 side by side
#: (`_threads.ordered_map`); so up to three busy threads at a time. One in
#: a process limited to one thread (`threads`).
WORKERS = 2


def threads():
    """`WORKERS`, or 1 in a process whose ``OMP_NUM_THREADS`` is 1: the
    workers of `identify_many`, and dask workers started by a nanny, are
    single-threaded, one identification per core."""
    return 1 if os.environ.get('OMP_NUM_THREADS') == '1' else WORKERS


def is_long(task):
    """Whether `task` (a `_search.Task`) takes the long-record path."""
    return sum(part.size for part in task.u) > LONG_RECORD


def long_search(task):
    """Stages 1 and 2 on `task`: (problem, best `lm` output, linear
    baseline), as `_search.search` returns them, on all the samples."""
    workers = threads()
    head = Task(leading(task.u, LONG_HEAD), leading(task.y, LONG_HEAD),
                task.orders, task.opt, dt=task.dt, name=task.name,
                progress=task.progress, offsets=task.offsets,
                workers=workers, path_samples=PATH_SAMPLES, head=True)
    if not all(np.ptp(part) > 0 for part in head.u + head.y):
        return search(task)       # a constant start: it cannot find a basin
    scaled_h, scaled = step1_units(head), step1_units(task)
    linears_h = step2_linear_baseline(head, scaled_h)
    starts = {k: _carried_linear(lin, scaled_h, scaled)
              for k, lin in linears_h.items()}
    # stage 2's linear baseline runs beside stage 1 where it is the only
    # one (with integrators='auto' and two, stage 1 chooses first): the
    # same fit as after it, in about the time of the longer
    early, stop = None, threading.Event()
    pool = (ThreadPoolExecutor(max_workers=1)
            if workers > 1 and len(starts) == 1 else None)
    try:
        if pool is not None:
            (k, start), = starts.items()
            early = (k, pool.submit(task.fit_linear, scaled, k, start=start,
                                    stop=stop))
        prob_h, best_h, linear_h = search(head, linears_h)
    except BaseException:
        stop.set()              # the fit ends at its next iteration
        raise
    finally:
        if pool is not None:
            pool.shutdown(wait=True)
    split = (prob_h.st.i1, prob_h.st.i2)
    k = sum(split)
    lin = (early[1].result() if early is not None and early[0] == k
           else task.fit_linear(scaled, k, start=starts.get(k)))
    full = Search(task, lin, split)
    sign = best_h['sign']
    if sign not in full.probs:
        full.probs[sign] = task.problem(split, sign)
    prob = full.probs[sign]
    prob.st.zero_radius = prob_h.st.zero_radius
    best = {'cost': np.inf}                 # step 12 on all: the fallback
    if not best_h.get('fallback'):
        best = full.converge(sign, _carried(prob_h, prob, best_h['phi']))
    best = full.step12_never_worse_than_linear(best)
    best['held_out'] = best_h.get('held_out')
    if best_h.get('held_out') and best_h['held_out'].get('open') is False:
        best['message'] = best_h['message']      # step 13 closed it
    n, n_head = prob.n_samples, prob_h.n_samples
    best['n_starts'] = best_h['n_starts']
    best['long_record'] = {'samples': n, 'head': n_head}
    _, auto, text = linear_h['message'].partition("; integrator")
    if task.opt.integrator_block == 'auto':
        best['message'] += auto + text
    best['message'] += (f"; long record: the search ran on the leading "
                        f"{n_head:,} of {n:,} samples, the refinement on "
                        f"all of them")
    linear = full.baseline()
    linear['message'] += auto + text
    return full.probs[best['sign']], best, linear


def _carried_linear(lin_h, scaled_h, scaled):
    """A `fit_oe` fit on the leading samples (scaled as `scaled_h`) as a
    start (B, F') on all of them (scaled as `scaled`)."""
    return (lin_h['B'] * scaled_h.sy / scaled_h.su * scaled.su / scaled.sy,
            lin_h['Ff'])


def _carried(prob_h, prob, phi_h):
    """phi_h of the problem `prob_h` (the leading samples) as the reduced
    parameters of `prob` (all of them, scaled by their own spreads): the
    model, output offsets and initial conditions in the user's units."""
    st = prob.st
    phi = st.phi(prob_h.st.theta(phi_h) * prob_h.unit / prob.unit)
    ry, rx = prob_h.sy / prob.sy, prob_h.su / prob.su
    phi[st.q:] = phi_h[st.q:] * ry
    kx = st.init_sizes[0]
    for e in range(st.n_inits):             # x in u's units, v and y in y's
        at = st.q + st.n_off + e * st.n_init
        phi[at:at + kx] = phi_h[at:at + kx] * rx
    return phi
