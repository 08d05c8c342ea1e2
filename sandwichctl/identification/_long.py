"""Long records: the search on the leading samples, the refinement on all
(private).

A drive that logs at 1 to 10 kHz gives millions of samples in an hour.
The search of `_search` (steps 1 to 12) refines several starts to
convergence, polishes the best and hops around it, all on the whole
record: about 25 s on a million samples of the paper's plant, and over a
minute for larger orders. Its job is to find the basin of the best
model, and a leading part of the record finds the same basin; only the
last descent needs every sample, for the statistical precision of the
estimate. So a record of more than `LONG_RECORD` samples is identified
in two stages:

1. the whole search (steps 1 to 12, the integrator decision included)
   on the leading `LONG_HEAD` samples (each experiment in proportion to
   its length, from its own start, so its initial conditions are the
   same);
2. on all the samples: the linear baseline of the chosen integrator
   count (its Levenberg-Marquardt started from the leading samples'
   fit), Levenberg-Marquardt to convergence from the model of stage 1
   (the same tolerance as the search's, ``tol``), and the
   never-worse-than-linear floor (step 12) against that baseline.

The result says so in its message and in ``res.long_record``.
"""

import numpy as np

from ._linear import fit_oe
from ._problem import integrator_poly
from ._search import Search, Task, _head, search, step1_units

__all__ = []

#: Records of more samples than this take the long-record path. Below it
#: the search runs on every sample as it always did (the identified
#: models of shorter records are unchanged); at 200,000 samples that
#: search takes a few seconds, the long-record path about two.
LONG_RECORD = 200_000
#: Leading samples the search of a long record runs on (stage 1).
LONG_HEAD = 50_000


def is_long(task):
    """Whether `task` (a `_search.Task`) takes the long-record path."""
    return sum(part.size for part in task.u) > LONG_RECORD


def long_search(task):
    """Stages 1 and 2 on `task`: (problem, best `lm` output, linear
    baseline), as `_search.search` returns them, on all the samples."""
    head = Task(_head(task.u, LONG_HEAD), _head(task.y, LONG_HEAD),
                task.orders, task.opt, dt=task.dt, name=task.name,
                progress=task.progress, offsets=task.offsets)
    prob_h, best_h, linear_h = search(head)
    k = prob_h.st.i1 + prob_h.st.i2
    full = Search(task, _linear_fit(task, k, linear_h['model']), k)
    sign = best_h['sign']
    if sign not in full.probs:
        full.probs[sign] = task.problem(k, sign)
    prob = full.probs[sign]
    prob.st.zero_radius = prob_h.st.zero_radius
    best = {'cost': np.inf}                 # step 12 on all: the fallback
    if not best_h.get('fallback'):
        best = full.converge(sign, _carried(prob_h, prob, best_h['phi']))
    best = full.step12_never_worse_than_linear(best)
    n, n_head = prob.n_samples, prob_h.n_samples
    best['n_starts'] = best_h['n_starts']
    best['long_record'] = {'samples': n, 'head': n_head}
    best['message'] += (f"; long record: the search ran on the leading "
                        f"{n_head:,} of {n:,} samples, the refinement on "
                        f"all of them")
    linear = full.baseline()
    _, auto, text = linear_h['message'].partition("; integrators=")
    linear['message'] += auto + text
    return full.probs[best['sign']], best, linear


def _linear_fit(task, k, model):
    """The linear output-error fit with k integrators on all the samples
    (scaled as step 1 scales them), started from `model`, the leading
    samples' fit in the user's units (``res.linear['model']``)."""
    scaled = step1_units(task)
    nb, nf, nk = task.shape
    num, den = model.num[0][0], model.den[0][0]
    num = np.r_[np.zeros(den.size - num.size), num]  # the leading zeros
    B = num[nk:nk + nb] * scaled.su / scaled.sy
    Ff = np.polydiv(den[:nf + 1], integrator_poly(k))[0]
    return fit_oe(scaled.u, scaled.y, task.shape, k,
                  max_iter=task.opt.max_iter, tol=task.opt.tol,
                  offsets=task.offsets, start=(B, Ff))


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
