"""The output-error search of ``identify(method='oe')``, step by step.

Each numbered step of docs/algorithm.md (``method="oe"``) is one function
or method here, in that order and with that number:

- `step1_units` to `step3_integrators`: the scaled data, the linear
  baseline and the integrators, once per identification (`search` runs
  them; `linear_baseline` runs steps 1 and 2 alone, the baseline the
  recursive methods are judged against);
- `Search.step4_nested_starts` to `Search.step12_never_worse_than_linear`:
  the search with the integrators in given blocks from the linear fit
  of their count (step 3 runs it for each, and chooses);
- `step13_held_out` (in `_held_out`): the chosen model's open backlash
  cross-checked on held-out tails of the record.

The starts come from `_starts`, the solver is `_lm.lm`, the problem and
its verdict from `_problem`. A new start is one function in `_starts` and
one line in the step that uses it; the progress bar counts what the steps
say they will run (`Search.planned`). Private.
"""

import dataclasses

import numpy as np
from scipy.signal import lfilter

from ._data import leading
from ._held_out import step13_held_out
from ._integrators import (drift, integrator_floor, integrator_split,
                           integrator_splits, split_label,
                           worth_integrating)
from ._lm import lm
from ._linear import fit_oe, fit_output, fit_blocks, wants_integrator
from ._predictor import oe_signals
from ._problem import Problem, STABILITY_MARGIN
from ._smooth import smooth_refine
from ._threads import ordered_map
from ._starts import (splits, opened, random_start, recursive_start,
                      reintegrated, relocations, perturb, unsplit,
                      held_starts, holds)
from .linear import oe_transfer_function
from .._checks import close_filled, progress_bar, shared_progress
from ..tools.residuals import band_errors, noise_level

__all__ = []

#: A hop is refined to convergence only if a short run (screen_iter
#: iterations) already brings it within this share of the best cost.
HOP_SLACK = 0.1
#: Relative size of a hop's perturbation (at least 0.05 absolute).
HOP_SPREAD = 0.1
#: Relocated starts refined to convergence per round.
RELOCATE_KEEP = 2
#: Iterations of the L2 re-fit of a relocated start (a start only).
RELOCATE_REFIT_ITER = 20
#: Where the integrator of a model goes when it restarts a fit without one.
UNINTEGRATED_POLE = 0.99
#: Step 5 with an integrator in L2: the pole of the filter (1 - q^-1) /
#: (1 - rho q^-1) the output is passed through, to search it without the
#: drift (the integrator of L2 becomes a pole at rho).
DRIFT_FILTER_POLE = 0.95


def search(task, linears=None):
    """Steps 1 to 13 on `task` (a `Task`): the problem, the best `lm`
    output and the linear baseline of the chosen integrator count
    (`linears`: step 2's fits, when they are already made)."""
    scaled = step1_units(task)
    if linears is None:
        linears = step2_linear_baseline(task, scaled)
    return step13_held_out(task, *step3_integrators(task, linears, scaled))


class Task:
    """What every problem of one identification shares: the data (lists of
    experiments), orders, options (`OEOptions`), and the model's dt and
    name, progress bar and estimated offsets and initial conditions."""

    def __init__(self, u, y, orders, opt, **kw):
        self.u, self.y, self.orders, self.opt = u, y, orders, opt
        self.dt, self.name = kw.get('dt', True), kw.get('name')
        self.progress = kw.get('progress', False)
        self.offsets = kw.get('offsets', False)
        self.workers = kw.get('workers', 1)     # threads of `ordered_map`
        self.path_samples = kw.get('path_samples')  # of step 8's path
        self.head = kw.get('head', False)   # a long record's leading part
        self.inits = opt.initial_state == 'estimate'
        o = orders
        self.shape = (o['nb'] + o['nd'] + 1, o['na'] + o['nc'],
                      o['q1'] + o['q2'])

    def problem(self, split, sign):
        """The scaled problem with the integrators `split` = (i1, i2) in L1
        and L2 and gain sign `sign`."""
        i1, i2 = split
        return Problem(self.u, self.y, self.orders, i1=i1, i2=i2, sign=sign,
                       dt=self.dt, name=self.name, offsets=self.offsets,
                       inits=self.inits,
                       minimum_phase=self.opt.minimum_phase)

    def filtered(self, rho):
        """The task on the outputs filtered by (1 - q^-1) / (1 - rho
        q^-1), each from rest (step 5), without a progress bar, output
        offsets (a constant is filtered out), relocations or hops (the
        model it gives goes through them on the outputs themselves)."""
        ys = [lfilter([1.0, -1.0], [1.0, -rho], part) for part in self.y]
        opt = dataclasses.replace(self.opt, relocate=0, hops=0)
        return Task(self.u, ys, self.orders, opt, dt=self.dt,
                    workers=self.workers, path_samples=self.path_samples)

    def fit_linear(self, scaled, k, start=None, **kw):
        """The linear output-error fit with k integrators on `scaled`
        (from `start`, and with `fit_oe`'s `stop`)."""
        return fit_oe(scaled.u, scaled.y, self.shape, k,
                      max_iter=self.opt.max_iter, tol=self.opt.tol,
                      offsets=self.offsets, start=start, **kw)


def step1_units(task):
    """Step 1: u and y scaled (and rounded), the sign taken out."""
    return Problem(task.u, task.y, task.orders, dt=task.dt, name=task.name)


def step2_linear_baseline(task, scaled):
    """Step 2: the linear output-error fits, {integrators: fit}: the
    declared count, or for 'auto' none and, when `wants_integrator`, one
    (step 3 chooses)."""
    k = task.opt.integrators
    nf = task.shape[1]
    if k != 'auto' and k > nf:
        raise ValueError(f"integrators = {k} exceed the na + nc = {nf} "
                         f"poles of the structure")
    if k != 'auto':
        return {k: task.fit_linear(scaled, k)}
    linears = {0: task.fit_linear(scaled, 0)}
    if wants_integrator(linears[0]['Ff']):
        linears[1] = task.fit_linear(scaled, 1)
    return linears


def linear_baseline(task):
    """Steps 1 and 2 alone, for the methods that do not search (the
    recursive ones): the linear baseline of the declared integrator count
    (``task.opt.integrators``, a number) in the user's units, the
    ``res.linear`` of `Search.baseline`."""
    (k, lin), = step2_linear_baseline(task, step1_units(task)).items()
    split = integrator_split(k, task.orders, task.opt.integrator_block)
    return Search(task, lin, split).baseline()


def step3_integrators(task, linears, scaled):
    """Step 3: the search (steps 4 to 12) from each linear fit (and from
    the one with an integrator, fitted on `scaled`, where the sandwich
    without one asks for it: `_searched`), with an
    integrator in each block `integrator_splits` allows ('auto': L1 and
    L2); without an integrator restarted from the cheapest fit with one if
    that ended cheaper; the lower AIC, above the integrator-free floor.
    An integrating fit whose pole at z = 1 a zero of the model cancels
    (`drift`) is not chosen over the integrator-free one. Returns
    (problem, best, linear baseline, the `Search` it came from)."""
    block = task.opt.integrator_block
    searches = {split: Search(task, lin, split)
                for k, lin in linears.items()
                for split in integrator_splits(k, task.orders, block)}
    fits = _searched(task, searches, linears, scaled)
    free = (0, 0)
    if free in fits and len(fits) > 1:
        cheapest = min((s for s in fits if s != free),
                       key=lambda s: fits[s][1]['cost'])
        if fits[cheapest][1]['cost'] < fits[free][1]['cost']:
            # it nests the integrating fit (a pole just inside z = 1), so
            # ending worse, it stopped in a poorer basin: restart from it
            fits[free] = _unintegrated(task, fits[free], fits[cheapest])
    n = sum(part.size for part in task.u)

    def aic(split):
        prob, out, _ = fits[split]
        return n * np.log(max(out["cost"], 1e-300)) + 2 * prob.st.size

    drifts = {split: drift(fits[split]) for split in fits if sum(split)}
    real = [split for split in fits if drifts.get(split) is None]
    chosen = min(real if free in fits else fits, key=aic)
    floor = integrator_floor(fits, chosen)
    prob, best, linear = fits[floor]
    if len(fits) > 1:
        label = split_label if block == 'auto' else sum
        who = ("integrators='auto'" if task.opt.integrators == 'auto'
               else "integrator_block='auto'")
        text = (
            f"; {who} chose {label(chosen)} by AIC of the sandwich fits ("
            + ', '.join(f"{label(j)}: {aic(j):.6g}" for j in sorted(
                fits, key=lambda j: (sum(j), -j[0]))) + ")")
        passed = [j for j in fits if drifts.get(j) is not None
                  and aic(j) < aic(chosen) and free in fits]
        if passed:
            text += ("; not " + ', '.join(
                f"{label(j)}, whose pole at z = 1 a zero at "
                f"{drifts[j]:.6g} cancels (a drift term, not an "
                f"integrator)" for j in passed))
        if floor != chosen:
            text += ("; but the integrating sandwich fits worse than the "
                     "integrator-free linear fit, so the integrator-free "
                     "one is kept")
        linear['message'] += text
        if block == 'auto':             # where it went: the model's own
            best['message'] += text
    return prob, best, linear, searches[floor]


def _searched(task, searches, linears, scaled):
    """The fits of `searches` ({split: (problem, best, linear)}); with
    integrators='auto' where the linear fit has no slow real pole to try
    an integrator for (a fit the backlash dominates), but the sandwich
    without one ends with one in L1 or L2 or with poorly determined
    parameters (`worth_integrating`), those with one too, from the linear
    fit with one on `scaled` (`searches` gains them). A structure
    without poles (na = nc = 0) has no place for one."""
    with shared_progress(task, len(searches), 'identify: starts'):
        fits = _run_all(searches, task.workers)
    if task.opt.integrators != 'auto' or 1 in linears or \
            (0, 0) not in fits or task.shape[1] < 1 or \
            not worth_integrating(fits[0, 0], flat=not task.head):
        return fits
    lin = task.fit_linear(scaled, 1)
    more = {split: Search(task, lin, split) for split in
            integrator_splits(1, task.orders, task.opt.integrator_block)}
    searches.update(more)
    with shared_progress(task, len(more), 'identify: starts'):
        return {**fits, **_run_all(more, task.workers)}


def _run_all(searches, workers):
    """{split: run} of `searches` on `workers` threads, an L2 integrator's
    first (step 5 filters its search): the same fits as on one thread."""
    order = sorted(searches, key=lambda split: -split[1])
    got = dict(zip(order, ordered_map(lambda split: searches[split].run(),
                                      order, workers)))
    return {split: got[split] for split in searches}


def _unintegrated(task, free, integrating):
    """The fit without an integrator, `free` = (problem, best, linear),
    restarted from the fit with one: its pole at z = 1 moved to
    `UNINTEGRATED_POLE`, refined and polished (steps 8 to 10); the
    cheaper of that and `free`."""
    prob1, best1, _ = integrating
    prob0, best0, linear0 = free
    sign = best1['sign']
    if prob0.sign != sign:
        prob0 = task.problem((0, 0), sign)
    st0, st1 = prob0.st, prob1.st
    theta = st1.theta(best1['phi'])
    nc, na = task.orders['nc'], task.orders['na']
    lo, n = (nc, na) if st1.i1 else (0, nc)
    roots = np.roots(np.r_[1.0, theta[lo:lo + n]])
    roots[np.argmin(np.abs(roots - 1.0))] = UNINTEGRATED_POLE
    theta[lo:lo + n] = np.real(np.poly(roots))[1:]
    phi = st0.phi(theta)
    phi[st0.q:] = best1['phi'][st1.q:]       # offsets, initial conditions
    if not st0.stable(phi):
        return free
    restart = Search(task, None, (0, 0), probs={sign: prob0})
    out = restart.polish(restart.converge(sign, phi))
    if not out['cost'] < best0['cost']:
        return free
    out['n_starts'] = best0['n_starts'] + 1
    return prob0, out, linear0


class Search:
    """The search with the integrators `split` = (i1, i2) in L1 and L2
    from the linear fit `lin` with i1 + i2 of them (steps 4 to 12); `run`
    runs them. ``probs`` maps a gain sign to its scaled `Problem`,
    ``heads`` to (parametrisation, u, y) of its leading `screen_samples`
    samples, on which the screening runs."""

    def __init__(self, task, lin, split, probs=None):
        self.task, self.opt, self.lin = task, task.opt, lin
        self.split, self.k = split, sum(split)
        if probs is None:
            self.sign = -1 if lin['B'][0] < 0 else 1
            probs = {self.sign: task.problem(split, self.sign)}
        self.probs = probs
        self.held, self.held_tried = None, False
        self.heads = {}
        self._head_all()
        self.bar = None
        self.tick = lambda: None

    def _head_all(self):
        n = self.opt.screen_samples
        self.heads = {s: (p.st, leading(p.u, n), leading(p.y, n))
                      for s, p in self.probs.items()}

    def run(self):
        """Steps 4 to 12: (problem, best `lm` output, linear baseline)."""
        groups = self.step4_nested_starts()
        self.bar = progress_bar(self.task.progress, total=self.planned(
            groups), desc='identify: starts', leave=False)
        self.tick = self.bar.update
        cands = [c for g in groups for c in g]
        screened = self.screen(cands, self.opt.screen_iter // 2)
        others = self.step5_other_basins(groups, screened)
        best, finals = self.step6_screen_and_converge(screened, others)
        polished = self.polish(best)               # steps 8 to 10
        best = self.step11_degenerate_best(polished, best, finals)
        close_filled(self.bar)
        best = self.step12_never_worse_than_linear(best)
        best['n_starts'] = len(cands) + len(others)
        return self.probs[best['sign']], best, self.baseline()

    def planned(self, groups):
        """Progress-bar total: what steps 4 to 10 say they will run."""
        opt = self.opt
        return (sum(len(g) for g in groups) + len(groups) + opt.sp_starts
                + opt.n_random + 1 + opt.keep + opt.relocate + 1 + opt.hops)

    def baseline(self):
        """The linear fit in the user's units (``res.linear``); with
        ``'held'``, the best linear model the structure holds, when it
        cannot hold the linear fit (`held_start`)."""
        lin, k = self.lin, self.k
        nb_l, nf_l, nk_l = self.task.shape
        out = dict(self._user_units(lin), cost_scaled=lin['cost'],
                   n_params=nb_l + nf_l - k, integrators=k,
                   converged=lin['converged'], message=lin['message'])
        if self.held is not None:
            held = self.held
            out['held'] = dict(self._user_units(held),
                               cost_scaled=held['cost'],
                               roots=held['roots'])
            out['held']['note'] = held_note(
                self.task.orders, self.probs[self.sign].st, held['roots'],
                out['held']['fit'])
        return out

    def _user_units(self, lin):
        """fit, cost, transfer function and its B and F (integrators
        included) in the user's units of a linear model on the scaled data
        (``B``, ``F``, ``offsets``)."""
        prob, nk_l = self.probs[self.sign], self.task.shape[2]
        y_all = np.concatenate(self.task.y)
        r_lin = y_all - prob.sy * fit_output(
            lin, [part / prob.su for part in prob.u_user], nk_l)
        denom = np.linalg.norm(y_all - y_all.mean())
        bands, relative = band_errors(r_lin, y_all - r_lin)
        return {'fit': float(100 * (1 - np.linalg.norm(r_lin) / denom)),
                'cost': 0.5 * float(r_lin @ r_lin),
                'model': oe_transfer_function(lin['B'] * prob.sy / prob.su,
                                              lin['F'], nk_l, self.task.dt),
                'B': lin['B'] * prob.sy / prob.su,
                'F': np.array(lin['F'], dtype=float),
                'error_bands': bands, 'relative_error': relative,
                'noise': noise_level(r_lin)}

    def extend(self, s, phi):
        """A model start of sign s with the linear fit's output offsets
        (and zero initial conditions)."""
        st = self.probs[s].st
        phi = st.extend(phi)
        phi[st.q:st.q + st.n_off] = s * self.lin['offsets'][:st.n_off]
        return phi

    def step4_nested_starts(self):
        """Step 4: the linear fit's splits, closed and opened: a list of
        groups [(sign, phi) closed, then opened to each width]; with many
        splits, those whose widest opening fits best."""
        sign, B, F = self.sign, self.lin['B'], self.lin['F']
        starts = [(sign, self.extend(sign, phi))
                  for phi in splits(self.probs[sign].st, sign * B, F)]
        if abs(B[0]) < 0.2 * np.max(np.abs(B)):
            # the sign of a small leading coefficient is uncertain: also
            # the other sign, from the linear fit with it flipped
            self.probs[-sign] = self.task.problem(self.split, -sign)
            self._head_all()
            flipped = B.copy()
            flipped[0] = -B[0]
            starts += [(-sign, self.extend(-sign, phi)) for phi in
                       splits(self.probs[-sign].st, -sign * flipped, F)]
        if not starts:
            o = self.task.orders
            raise ValueError(
                f"the linear fit of the total orders cannot be split into "
                f"L1 (na = {o['na']}, nb = {o['nb']}) and L2 (nc = "
                f"{o['nc']}, nd = {o['nd']})")
        groups = [[(s, phi)] + [(s, w) for w in opened(
            self.probs[s].st, phi, self.probs[s].u, self.opt.widths)]
            for s, phi in starts]
        if len(groups) > self.opt.max_splits:
            groups = sorted(groups, key=self._widest_cost)
            groups = groups[:self.opt.max_splits]
        return groups

    def held_start(self):
        """Step 12 when the structure cannot hold the linear fit (its
        roots cannot be split into L1 and L2 with complex pairs whole,
        `_starts.unsplit`): the best linear model the structure holds, a
        sandwich with a closed backlash fitted by output error
        (`_linear.fit_blocks`) from real-root starts (`held_starts`). Its
        phi, also kept in ``self.held`` (the floor of step 12 then); None
        when the structure holds the linear fit."""
        sign, prob = self.sign, self.probs[self.sign]
        st, B, F = prob.st, sign * self.lin['B'], self.lin['F']
        self.held_tried = True
        roots = unsplit(st, B, F)
        if not roots:
            return None
        best = None
        for phi in held_starts(st, B, F):
            fit = self.fit_held(prob.u, prob.y, phi)
            if best is None or fit['cost'] < best['cost']:
                best = fit
        x, phi = best['x'], best['phi']
        cost = st.cost(phi, prob.u, prob.y)
        if not (x[st.im] > 0 and np.isfinite(cost) and st.stable(phi)):
            return None
        self.held = dict(best, phi=phi, cost=cost, roots=roots,
                         B=sign * best['B'], offsets=sign * best['offsets'])
        return phi

    def fit_held(self, u, y, phi):
        """The closed-backlash model fitted by `_linear.fit_blocks` on the
        experiments u, y from phi (its first q entries): the fit, with
        ``phi`` the model (output offsets, zero initial conditions)."""
        sign, st = self.sign, self.probs[self.sign].st
        im = st.im
        fit = fit_blocks(u, y, np.delete(phi[:st.q], [im + 1, im + 2,
                                                      im + 3]),
                         (st.nc_free, st.na_free, st.o[1], st.o[3]),
                         nk=st.o[4] + st.o[5], integrators=(st.i1, st.i2),
                         offsets=bool(st.n_off), max_iter=self.opt.max_iter,
                         radius=1 - STABILITY_MARGIN)
        x = fit['x']
        out = self.extend(sign, np.insert(x, im + 1, [x[im], 0.0, 0.0]))
        out[st.q:st.q + st.n_off] = fit['offsets'][:st.n_off]
        return dict(fit, phi=st.minimum_phase_start(out))

    def from_held(self, best, held):
        """The search again from the `held` linear model (step 12): closed
        and opened (step 4), each converged with step 7, the best polished
        (steps 8 to 10); the cheaper of that and `best`."""
        s, prob = self.sign, self.probs[self.sign]
        self.tick = lambda: None              # not counted in the bar
        outs = [self.step7_refit_l2(self.converge(s, phi)) for phi in
                [held] + opened(prob.st, held, prob.u, self.opt.widths)]
        found = self.polish(min(outs, key=lambda out: out['cost']))
        ok = np.isfinite(best['cost']) and best['cost'] <= found['cost']
        return best if ok else found

    def _widest_cost(self, group):
        s, phi = group[-1]
        st, u, y = self.heads[s]
        return st.cost(phi, u, y)

    def step5_other_basins(self, groups, screened):
        """Step 5: series-parallel runs from every split opened widest,
        from the best screened starts and from random structures, the
        recursive estimator's start and, with an integrator in L2, the
        search on the output without its drift (`filtered_start`):
        [(sign, phi)]."""
        opt, sign, others = self.opt, self.sign, []
        if opt.sp_iter:
            rng = np.random.default_rng(opt.seed)
            prob = self.probs[sign]
            seeds = [g[-1] for g in groups] + [
                (out['sign'], out['phi']) for out in screened[:opt.sp_starts]]
            seeds += [(sign, random_start(prob.st, prob.u, rng))
                      for _ in range(opt.n_random)]
            for s, phi in seeds:
                st, us, ys = self.heads[s]
                out = lm(st, phi, us, ys, opt.sp_iter, sp=True)
                if st.stable(out['phi']):
                    others.append((s, out['phi']))
                self.tick()
        if not (self.k or self.task.orders['na'] == 0):
            others += recursive_start(self.probs[sign], self.task.orders)
        if self.split[1]:
            others += self.filtered_start()
        self.tick()
        return others

    def filtered_start(self):
        """Step 5 with an integrator in L2: the search (`Task.filtered`:
        steps 4 to 8, 11 and 12) on the output filtered by (1 - q^-1) /
        (1 - rho q^-1) (`DRIFT_FILTER_POLE`), on which that integrator is
        a pole at rho, and its model with that pole back at z = 1
        (`reintegrated`): [(sign, phi)] or []."""
        rho = DRIFT_FILTER_POLE
        sub = self.task.filtered(rho)
        i1, i2 = self.split
        lin = sub.fit_linear(step1_units(sub), self.k - 1)
        prob_f, best_f, _ = Search(sub, lin, (i1, i2 - 1)).run()
        s = best_f['sign']
        if s not in self.probs:
            self.probs[s] = self.task.problem(self.split, s)
            self._head_all()
        prob = self.probs[s]
        phi = reintegrated(prob.st, prob_f.st, best_f['phi'], rho,
                           prob_f.sy / prob.sy)
        return [] if phi is None else [(s, self.extend(s, phi))]

    def screen(self, cands, iterations, tick=True):
        """A few LM iterations from each (sign, phi) on the leading
        samples; sorted by cost."""
        out = []
        for s, phi in cands:
            st, u, y = self.heads[s]
            res = lm(st, phi, u, y, iterations, self.opt.tol)
            res['sign'] = s
            out.append(res)
            if tick:
                self.tick()
        return sorted(out, key=lambda res: res['cost'])

    def converge(self, s, phi):
        """`lm` to convergence on all the data from phi (sign s)."""
        p = self.probs[s]
        return dict(lm(p.st, phi, p.u, p.y, self.opt.max_iter,
                       self.opt.tol), sign=s)

    def step6_screen_and_converge(self, screened, others):
        """Step 6: the starts of step 5 screened with the best of step 4;
        the best `keep` to convergence, each with step 7. Returns (the
        best, every converged start)."""
        keep = self.opt.keep
        screened = sorted(screened[:keep] + self.screen(
            others, self.opt.screen_iter, tick=False),
            key=lambda out: out['cost'])
        best, finals = None, []
        for out in ordered_map(lambda out: self.step7_refit_l2(
                self.converge(out['sign'], out['phi'])), screened[:keep],
                self.task.workers):
            finals.append(out)
            if best is None or out['cost'] < best['cost']:
                best = out
            self.tick()
        return best, finals

    def step7_refit_l2(self, out):
        """Step 7: L2 re-fitted to the model's own backlash output and the
        sandwich refined again, while that lowers the cost."""
        p = self.probs[out['sign']]
        for _ in range(self.opt.refits):
            phi = refit_l2(p.st, out['phi'], p.u, p.y, self.opt.max_iter,
                           self.opt.tol)
            if phi is None or not (p.st.cost(phi, p.u, p.y)
                                   < out['cost'] * (1 - 1e-6)):
                break                   # L2 is already the best for its v
            # lm never raises the cost, so this refinement is an improvement
            out = self.converge(out['sign'], phi)
        return out

    def polish(self, best):
        """Steps 8 to 10 from `best`; each keeps only what lowers the
        cost."""
        best = self.step8_smoothed_path(best)
        for _ in range(self.opt.relocate):
            moved = self.step9_relocations(best)
            self.tick()
            if moved is best:
                break
            best = moved
        return self.step10_hops(best)

    def step8_smoothed_path(self, best):
        """Step 8: a path of smoothed costs from the best (continuous
        where the exact cost jumps), then the exact cost again."""
        if self.opt.smooth:
            p, n = self.probs[best['sign']], self.task.path_samples
            path = None if n is None else (leading(p.u, n), leading(p.y, n))
            out = smooth_refine(p.st, best['phi'], p.u, p.y,
                                self.opt.max_iter, self.opt.tol,
                                workers=self.task.workers, path=path)
            if out is not None and out['cost'] < best['cost']:
                best = dict(out, sign=best['sign'])
        self.tick()
        return best

    def step9_relocations(self, best):
        """Step 9, one round: every relocated start (`_starts.relocations`)
        gets L2 re-fitted and a short run on the leading samples; the best
        `RELOCATE_KEEP` converge. The best of them if it lowers the cost
        and has no zero on the search bound where `best` has none (the
        algorithm page, step 9), else `best` itself."""
        (st, us, ys), opt, starts = self.heads[best['sign']], self.opt, []
        for phi in relocations(st, best['phi'], us):
            refit = refit_l2(st, phi, us, ys, RELOCATE_REFIT_ITER, opt.tol)
            starts.append(phi if refit is None else refit)
        starts = [phi for phi in starts if st.stable(phi)]
        short = sorted((lm(st, phi, us, ys, opt.screen_iter // 2, opt.tol)
                        for phi in starts), key=lambda out: out['cost'])
        sound, found = not st.zeros_at_bound(best['phi']), best
        for out in ordered_map(lambda out: self.converge(
                best['sign'], out['phi']), short[:RELOCATE_KEEP],
                self.task.workers):
            if out['cost'] < found['cost'] * (1 - 1e-6) and not (
                    sound and st.zeros_at_bound(out['phi'])):
                found = out
        return found

    def step10_hops(self, best):
        """Step 10: `hops` perturbed restarts from the best so far, each
        refined to convergence if a short run looks promising
        (`HOP_SLACK`); the better is kept."""
        rng = np.random.default_rng(self.opt.seed + 1)
        for _ in range(self.opt.hops):
            best = self._hop(best, rng)
            self.tick()
        return best

    def _hop(self, best, rng):
        prob = self.probs[best['sign']]
        phi = perturb(prob.st, best['phi'], rng, HOP_SPREAD)
        if phi is None:
            return best
        out = lm(prob.st, phi, prob.u, prob.y, self.opt.screen_iter,
                 self.opt.tol)
        if not out['cost'] < best['cost'] * (1 + HOP_SLACK):
            return best               # on its way back up the same valley
        out = self.converge(best['sign'], out['phi'])
        return out if out['cost'] < best['cost'] else best

    def step11_degenerate_best(self, best, converged, finals):
        """Step 11: if the best (polished from the `converged` start of
        step 6) has a zero on the search bound, the cheapest other start of
        `finals` without one is polished as well; the cheaper."""
        def at_bound(out):
            return self.probs[out['sign']].st.zeros_at_bound(out['phi'])

        if not at_bound(best):
            return best
        rest = [out for out in finals if out is not converged and
                not at_bound(out)]
        if not rest:
            return best
        self.tick = lambda: None              # not counted in the bar
        other = self.polish(min(rest, key=lambda out: out['cost']))
        return other if other['cost'] < best['cost'] else best

    def step12_never_worse_than_linear(self, best):
        """Step 12: if no start ends below the linear fit, the model is the
        linear fit itself, as a sandwich with a closed backlash (the zero
        radius lifted to hold its zeros). A structure that cannot hold the
        linear fit is searched again from the best linear model it holds
        (`held_start`, `from_held`), the floor then."""
        if best['cost'] <= self.lin['cost'] and np.isfinite(best['cost']):
            return best
        held = self.held_start()
        if held is not None:
            best = self.from_held(best, held)
            if best['cost'] <= self.held['cost']:
                return best
        return self.closed()

    def closed(self, why=None):
        """The floor of step 12: the linear fit as a sandwich with a closed
        backlash (the zero radius lifted to hold its zeros), or the `held`
        model when the structure cannot hold the linear fit (tried here if
        step 12 did not); the message says `why` (default: no start
        improved on it)."""
        if self.held is None and not self.held_tried:
            self.held_start()
        prob = self.probs[self.sign]
        st = prob.st
        st.zero_radius = np.inf
        if self.held is None:
            phi = self.extend(self.sign, splits(
                st, self.sign * self.lin['B'], self.lin['F'])[0])
            text = "the linear fit"
        else:
            phi = self.held['phi']
            text = ("the best linear model this structure holds (it cannot "
                    "hold the linear fit: res.linear['held'])")
        # step 12 takes one step (none lowers the cost where the search
        # started); step 13 keeps the backlash closed, as it says
        out = lm(st, phi, prob.u, prob.y, max_iter=1 if why is None else 0)
        out['sign'] = self.sign
        out['fallback'] = True
        model = f"the model is {text.split(' (')[0]} with a closed backlash"
        out['message'] = (f"no sandwich start improved on {text}: {model}"
                          if why is None else f"{why}: {model}")
        if st.minimum_phase_start(phi) is not phi:
            out['message'] += (", its zeros of L1 reflected inside the unit "
                               "circle (minimum_phase='L1')")
        return out


def held_note(orders, st, roots, fit):
    """The sentence of the verdict when the structure cannot hold the
    linear fit: which `roots` ({'poles': ..., 'zeros': ...}, `unsplit`)
    cannot be split, the fit of the best linear model it holds, and the
    least raised orders that hold them."""
    names = {'poles': ('na', 'nc', st.na_free, orders['na'] - st.na_free),
             'zeros': ('nb', 'nd', orders['nb'], 0)}
    parts, raised = [], []
    for kind, rs in roots.items():
        first, second, k, fixed = names[kind]
        pairs = [r for r in rs if r.imag > 1e-8 * max(1.0, abs(r))]
        parts.append(f"its {kind} " + ', '.join(
            f"{r.real:.3g}\u00b1{r.imag:.3g}j" for r in pairs))
        for j in range(1, rs.size + 1):
            padded = np.r_[rs, np.zeros(j)]
            if holds(padded, k + j):
                raised.append(f"{first} = {k + fixed + j}")
                break
            if holds(padded, k):
                raised.append(f"{second} = {orders[second] + j}")
                break
    o = orders
    return (f"the structure cannot hold the linear fit: {' and '.join(parts)}"
            f" cannot be split into L1 (na = {o['na']}, nb = {o['nb']}) and "
            f"L2 (nc = {o['nc']}, nd = {o['nd']}) with complex pairs whole; "
            f"the search started from the best linear model it holds (fit "
            f"{fit:.3g} %, res.linear['held']) and is never worse than it; "
            f"a structure with {' and '.join(raised)} holds them (compare "
            f"structures with sw.select_structure)")


def refit_l2(st, phi, u, y, max_iter=100, tol=1e-10):
    """A start with L2 re-fitted to the model's own intermediate signal
    (steps 7 and 9).

    With L1 and the backlash held, y is a linear output-error model of
    the backlash output v; the linear OE fit (ARX, Steiglitz-McBride,
    Levenberg-Marquardt) finds its optimum far more reliably than the
    joint descent, which can stall with L2's zeros or poles in the wrong
    place. Its gain moves into the backlash slopes (d0 = 1 stays). The
    linear fit starts from rest; estimated initial conditions (if the
    parametrisation has them) are kept, their past v scaled with the
    slopes.

    Returns
    -------
    ndarray or None
        The new phi, or None when the fit gives no admissible start (v
        constant, a leading coefficient of the wrong sign, a denominator
        not strictly stable or a zero beyond the zero radius, a value not
        finite).
    """
    theta = st.theta(phi)
    vs = [oe_signals(theta, st.o, uu, st.init(phi, e))[2]
          for e, uu in enumerate(u)]
    with np.errstate(all='ignore'):
        sv = float(np.std(np.concatenate(vs)))
    if not (np.isfinite(sv) and sv > 0):
        return None
    na, nb, nc, nd = st.o[:4]
    fit = fit_oe([v / sv for v in vs], list(y), (nd + 1, nc, st.o[5]),
                 st.i2, max_iter=max_iter, tol=tol, offsets=bool(st.n_off))
    B, F = fit['B'], fit['F']
    if not (np.all(np.isfinite(B)) and np.all(np.isfinite(F))
            and B[0] > 1e-9 * np.max(np.abs(B))):
        return None
    new = theta.copy()
    new[:nc] = F[1:]
    im = nc + na
    new[im:im + 2] *= B[0] / sv
    new[im + 4 + nb:] = B[1:] / B[0]
    out = st.phi(new)
    out[st.q:] = phi[st.q:]
    if st.n_off:
        out[st.q:st.q + st.n_off] = fit['offsets'][:st.n_off]
    kx, kv = st.init_sizes[:2]
    for e in range(st.n_inits):           # past v scales with the slopes
        at = st.q + st.n_off + e * st.n_init + kx
        out[at:at + kv] *= B[0] / sv
    return out if st.stable(out) else None
