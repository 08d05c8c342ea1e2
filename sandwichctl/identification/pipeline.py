"""`identify`: the identification pipeline over a whole record.

The default method, ``'oe'``, is output-error identification started from
the linear model that the sandwich nests:

1. u and y are scaled (units invariance) and a linear output-error model
   of the same total orders is fitted (`identify_linear`'s core, with
   integrators declared or found by AIC). It is the baseline.
2. Its poles and zeros are assigned to L1 and L2 in every way that keeps
   complex pairs together; each assignment, with m1 = m2 = the linear
   gain and D1 = D2 = 0, is a sandwich with exactly the linear fit.
3. From each, the backlash is opened from a few small widths (and kept
   closed); with series-parallel and random starts, short
   Levenberg-Marquardt runs on the leading samples screen them and the
   best ones are refined to convergence on all the data.
4. The best is polished: a path through smoothed backlashes (`_smooth`:
   where the slope lines cross, the exact cost jumps), relocations of one
   root of L1 (`_moves`) and perturbed restarts; a best that ends with a
   zero on the search bound is retried from the next converged start.
5. Every accepted step lowers the cost, and the closed starts begin at the
   linear cost, so the sandwich never ends worse than the linear model.
   The verdict (``success``) checks stability, convergence, no zero on
   the search bound and that the model explains the data.

The paper's recursive methods (``'bundle'``, ``'gradient'``) and the
recursive prediction-error estimator (``'rpem'``) run through
`RecursiveIdentifier`, optionally followed by `refine`. See
``docs/algorithm.md``.
"""

import numbers
import time
import warnings

import numpy as np

from ._data import prepare
from ._nested import splits, refit_l2
from ._moves import relocations, l1_std
from ._smooth import smooth_refine
from ._oe import lm
from ._predictor import padding, stable_and_finite
from .batch import Problem, refine as _refine, _progress_range, \
    _warn_poorly_determined, _admissible_start, MIN_FIT
from .linear import _fit_oe, fit_output, oe_transfer_function
from .recursive import RecursiveIdentifier, DEFAULTS
from .._checks import (check_int, check_order, check_positive, warn,
                       check_bool,
                       serial_blas,
                       progress_bar, check_option,
                       ExcitationWarning, SimulationWarning,
                       SandwichWarning, IdentificationWarning)
from .._checks import check_data_scale, check_parameter_count

__all__ = ['identify']

#: Options of method='oe' and their defaults.
OE_DEFAULTS = dict(widths=(0.05, 0.25), screen_iter=8, keep=3, max_iter=200,
                   tol=1e-8, min_fit=MIN_FIT, sp_iter=15, sp_starts=4,
                   n_random=6, seed=0, refits=2, max_splits=16, hops=4,
                   relocate=1, smooth=True, screen_samples=2000)

@serial_blas
def identify(u, y=None, na=None, nb=None, nc=None, nd=None, q1=1, q2=1,
             method='oe', theta0=None, dt=True, refine=None, progress=False,
             integrators='auto', integrator_block='L1', name=None,
             offsets='none', initial_state='zero', **options):
    r"""Identify a sandwich system from input/output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Measured input and output (the system starts at rest), in any
        units: the result does not depend on them. Instead of two arrays,
        `u` may be a ``control.TimeResponseData`` (its time vector gives
        dt) or a list of experiments (pairs or records), each from its own
        initial state, with the cost summed; then give the orders by
        keyword (`sandwichctl.tools.experiments`).
    na, nb, nc, nd : int
        Orders of eq. (2.1); nb and nd count coefficients after b0 and
        d0. na and nc count integrators too. The returned model has
        exactly these orders.
    q1, q2 : int, optional
        Known delays (default 1).
    method : {'oe', 'rpem', 'bundle', 'gradient'}, optional
        ``'oe'`` (default) is output-error identification started from the
        linear output-error fit of the same total orders (module
        documentation): it is never worse than that linear model.
        ``'rpem'`` is the recursive Gauss-Newton estimator; ``'bundle'``
        and ``'gradient'`` are the paper's method and its baseline.
    theta0 : array_like, optional
        Starting point of the recursive methods (order of eq. (2.5)).
    dt : float or True, optional
        Sampling time of the returned model.
    refine : bool or dict, optional
        Recursive methods only: follow the recursive estimate by `refine`
        (a dict gives its keyword arguments). Default False.
    progress : bool, optional
        Show progress bars (tqdm) on long runs.
    integrators : int or 'auto', optional
        ``'oe'`` only. Poles fixed at z = 1, e.g. 1 for a speed command in
        and a position out. ``'auto'`` (default) decides from the linear
        fit (AIC; only tried when it has a real pole above 0.9).
    integrator_block : {'L1', 'L2'}, optional
        Where the integrators go (default 'L1': in a drive the nut's
        position integrates the speed before the play).
    name : str, optional
        Name of the identified model.
    offsets : {'none', 'mean', 'estimate'}, optional
        ``'none'`` (default): the data are used as given, from rest. An
        estimated output offset is nearly confounded with the asymmetry of
        the backlash (shifting both thresholds by d shifts the output by
        about m L2(1) d), so on data without offsets it costs accuracy on
        D1 and D2; hence not the default. For real data with offsets:
        ``'mean'`` removes each experiment's means of u and y first (quick;
        not for integrating plants, whose drift it changes), and
        ``'estimate'`` fits a constant output offset per experiment with
        the data as given (also the initial position of an integrating
        plant). The recursive methods take 'none' or 'mean'.
        ``res.offsets`` says what was done.
    initial_state : {'zero', 'estimate'}, optional
        ``'oe'`` only. ``'zero'`` (default): each experiment starts from
        rest. ``'estimate'``: the past values before each experiment's
        first sample (x and v, which include the backlash memory, and y:
        the states of L1, the backlash and L2) are estimated with the
        model; they matter for short records and slow or integrating
        plants. ``res.initial_conditions`` gives them per experiment; the
        returned model's own `simulate` starts from rest.
    **options
        ``'oe'``: widths (relative backlash widths the starts open to,
        default (0.05, 0.25)), screen_iter (8), keep (3), max_iter (200),
        tol (1e-8), min_fit (5, percent), max_splits (16: most pole/zero
        splits of the linear fit screened), sp_iter (15), sp_starts (4),
        n_random (6), seed (0), refits (2: L2 re-fits per refined
        start), relocate (1: rounds of moving one root of L1 across the
        disk), smooth (True: a path through smoothed backlashes), hops
        (4: perturbed restarts from the best), screen_samples
        (2000: the short screening runs use this many leading samples;
        the refinements use all of them); the
        algorithm page of the documentation explains them. Recursive
        methods: see `RecursiveIdentifier`.

    Returns
    -------
    IdentificationResult
        ``model`` (a `SandwichSystem` in the data's units, b0 = 1 and
        d0 = +-1), ``theta``, ``success`` and ``message``; for ``'oe'``
        also ``fit``, ``cost``, ``std``, ``linear`` (the baseline),
        ``significance`` (F-test of the backlash), ``whiteness`` and
        ``integrators``. ``print(res)`` shows them at a glance.

    Raises
    ------
    ValueError
        On constant u or y, too few samples for the orders (fewer than
        10 p plus the delays, or than p**2, with p = na + nb + nc + nd +
        4 parameters), data whose peak magnitude is outside 1e-100 ..
        1e100 (rescale them), or orders that cannot be estimated.

    Warns
    -----
    RuntimeWarning
        If the data barely excite the backlash or a parameter is poorly
        determined (large standard error), or if a recursive estimate
        diverged.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(2000, seed=1)
    >>> y = plant.simulate(u).outputs
    >>> res = sw.identify(u, y, **plant.orders)
    >>> res.success, bool(sw.parameter_error(res.theta, plant.theta) < 1e-3)
    (True, True)
    >>> res.fit > res.linear['fit']
    True
    """
    if isinstance(y, numbers.Integral) and not isinstance(y, bool):
        raise TypeError("with a record or a list of experiments, give the "
                        "orders by keyword: identify(data, na=..., nb=..., "
                        "nc=..., nd=...)")
    missing = [k for k, v in zip(('na', 'nb', 'nc', 'nd'), (na, nb, nc, nd))
               if v is None]
    if missing:
        raise TypeError(f"identify needs the orders {missing} (e.g. "
                        f"identify(u, y, na=2, nb=0, nc=2, nd=1))")
    us, ys, dt, offset_info, estimate = prepare(u, y, dt, offsets)
    check_data_scale('u', us), check_data_scale('y', ys)
    methods = ('oe',) + tuple(DEFAULTS)
    if not isinstance(method, str) or method not in methods:
        raise ValueError(f"method must be one of {list(methods)}; got "
                         f"{method!r}")
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string or None; got "
                        f"{type(name).__name__} {name!r}")
    orders = {k: check_order(k, v) for k, v in
              zip(('na', 'nb', 'nc', 'nd', 'q1', 'q2'),
                  (na, nb, nc, nd, q1, q2))}
    p = orders['na'] + orders['nb'] + orders['nc'] + orders['nd'] + 4
    needed = 10 * p + padding(tuple(orders.values()))
    n_samples = sum(part.size for part in us)
    if n_samples < needed:
        big = max(orders, key=orders.get)
        raise ValueError(
            f"the data have {n_samples} samples, too few for {p} parameters "
            f"with these orders and delays (the largest is {big} = "
            f"{orders[big]}); give at least {needed} samples or lower the "
            f"orders")
    check_parameter_count(orders, n_samples)
    if method == 'oe':
        if refine not in (None, True):
            raise ValueError(f"refine applies to the recursive methods; "
                             f"method='oe' always refines (got refine="
                             f"{refine!r})")
        if theta0 is not None:
            raise ValueError("theta0 applies to the recursive methods; "
                             "method='oe' starts from the linear fit")
        result = _identify_oe(us, ys, orders, dt, name, integrators,
                              integrator_block, progress, options, estimate,
                              check_option('initial_state', initial_state,
                                           ('zero', 'estimate'))
                              == 'estimate')
    else:
        if len(us) > 1:
            raise ValueError(f"method={method!r} is recursive and takes one "
                             f"experiment; got {len(us)} (use method='oe')")
        result = _identify_recursive(us[0], ys[0], orders, method, theta0,
                                     dt, refine, progress, name, options)
        if estimate:               # the recursive methods fit no offset
            offset_info['method'] = 'none'
    result.offsets = dict(offset_info, **(result.get('offsets') or {}))
    _check_excitation(result, us)
    return result


def _oe_options(options):
    unknown = set(options) - set(OE_DEFAULTS)
    if unknown:
        raise TypeError(f"unknown option(s) {sorted(unknown)} for "
                        f"method='oe'; valid options are "
                        f"{sorted(OE_DEFAULTS)}")
    opt = dict(OE_DEFAULTS, **options)
    widths = opt['widths']
    if np.ndim(widths) != 1 or not all(
            isinstance(w, numbers.Real) and 0 < w < 10 for w in widths):
        raise ValueError(f"widths must be a sequence of relative widths in "
                         f"(0, 10); got {widths!r}")
    opt['widths'] = tuple(float(w) for w in widths)
    opt['screen_iter'] = check_int('screen_iter', opt['screen_iter'], 1)
    opt['sp_iter'] = check_int('sp_iter', opt['sp_iter'], 0)
    opt['sp_starts'] = check_int('sp_starts', opt['sp_starts'], 0)
    opt['n_random'] = check_int('n_random', opt['n_random'], 0)
    opt['seed'] = check_int('seed', opt['seed'], 0)
    opt['keep'] = check_int('keep', opt['keep'], 1)
    opt['refits'] = check_int('refits', opt['refits'], 0)
    opt['max_splits'] = check_int('max_splits', opt['max_splits'], 1)
    opt['hops'] = check_int('hops', opt['hops'], 0)
    opt['relocate'] = check_int('relocate', opt['relocate'], 0)
    opt['smooth'] = check_bool('smooth', opt['smooth'])
    opt['screen_samples'] = check_int('screen_samples',
                                      opt['screen_samples'], 100)
    opt['max_iter'] = check_int('max_iter', opt['max_iter'], 1)
    opt['tol'] = check_positive('tol', opt['tol'])
    opt['min_fit'] = float(opt['min_fit'])
    return opt


def _integrator_split(k, orders, block):
    if block not in ('L1', 'L2'):
        raise ValueError(f"integrator_block must be 'L1' or 'L2'; got "
                         f"{block!r}")
    na, nc = orders['na'], orders['nc']
    first, second = (na, nc) if block == 'L1' else (nc, na)
    if k > na + nc:
        raise ValueError(f"integrators = {k} exceed the na + nc = "
                         f"{na + nc} poles of the structure")
    i_first = min(k, first)
    i_second = k - i_first
    return (i_first, i_second) if block == 'L1' else (i_second, i_first)


def _identify_oe(u, y, orders, dt, name, integrators, block, progress,
                 options, offsets, inits):
    opt = _oe_options(options)
    start = time.perf_counter()
    if not (integrators == 'auto' or (isinstance(integrators,
                                                 numbers.Integral)
                                      and not isinstance(integrators, bool)
                                      and integrators >= 0)):
        raise ValueError(f"integrators must be an integer >= 0 or 'auto'; "
                         f"got {integrators!r}")
    _integrator_split(0, orders, block)            # checks `block`
    o = orders
    nf_l = o['na'] + o['nc']
    if integrators != 'auto' and integrators > nf_l:
        raise ValueError(f"integrators = {integrators} exceed the na + nc "
                         f"= {nf_l} poles of the structure")
    scaled = Problem(u, y, orders, dt=dt, name=name)
    shape = (o['nb'] + o['nd'] + 1, nf_l, o['q1'] + o['q2'])
    if integrators == 'auto':
        free = _fit_oe(scaled.u, scaled.y, *shape, 0, opt['max_iter'],
                       opt['tol'], offsets)
        poles = np.roots(free['Ff']) if nf_l else np.zeros(0)
        slow = bool(np.any((poles.real > 0.9) & (np.abs(poles.imag) < 0.1)))
        linears = {0: free}
        if slow:
            linears[1] = _fit_oe(scaled.u, scaled.y, *shape, 1,
                                 opt['max_iter'], opt['tol'], offsets)
    else:
        linears = {integrators: _fit_oe(scaled.u, scaled.y, *shape,
                                        integrators, opt['max_iter'],
                                        opt['tol'], offsets)}
    fits = {k: _fit_sandwich(u, y, orders, lin, k, shape, block, opt, dt,
                             name, progress, offsets, inits)
            for k, lin in linears.items()}
    if len(fits) > 1 and fits[1][1]['cost'] < fits[0][1]['cost']:
        # the fit without an integrator nests the one with (a pole just
        # inside z = 1): when it ended worse, it stopped in a poorer
        # basin, so it restarts from the other one's model
        fits[0] = _unintegrated(fits[0], fits[1], u, y, orders, block, opt,
                                dt, name, offsets, inits)
    # several integrator counts: the lower AIC of the sandwich fits
    n = sum(part.size for part in u)

    def aic(k):
        prob, out, _ = fits[k]
        return n * np.log(max(out["cost"], 1e-300)) + 2 * prob.st.size

    k = min(fits, key=aic)
    prob, best, linear = fits[k]
    if len(fits) > 1:
        linear['message'] += (
            f"; integrators='auto' chose {k} by AIC of the sandwich fits ("
            + ', '.join(f"{j}: {aic(j):.6g}" for j in sorted(fits)) + ")")
    res = prob.result(best, 'oe', linear=linear, min_fit=opt['min_fit'],
                      extra={'elapsed': time.perf_counter() - start,
                             'options': opt, 'n_starts': best['n_starts'],
                             'theta0': None})
    _warn_poorly_determined(res)
    return res


#: Where the integrator of a model goes when it restarts a fit without one.
UNINTEGRATED_POLE = 0.99


def _unintegrated(free, integrating, u, y, orders, block, opt, dt, name,
                  offsets, inits):
    """The fit without an integrator, `free` = (problem, best, linear),
    restarted from the fit with one: its pole at z = 1 moved to
    `UNINTEGRATED_POLE`, refined and polished (stages 4 to 6 of
    `_fit_sandwich`); the cheaper of that and `free`."""
    prob1, best1, _ = integrating
    prob0, best0, linear0 = free
    sign = best1['sign']
    if prob0.sign != sign:
        prob0 = Problem(u, y, orders, 0, 0, sign, dt, name, offsets, inits)
    st0, st1 = prob0.st, prob1.st
    theta = st1.theta(best1['phi'])
    nc, na = orders['nc'], orders['na']
    lo, n = (nc, na) if st1.i1 else (0, nc)
    roots = np.roots(np.r_[1.0, theta[lo:lo + n]])
    roots[np.argmin(np.abs(roots - 1.0))] = UNINTEGRATED_POLE
    theta[lo:lo + n] = np.real(np.poly(roots))[1:]
    phi = st0.phi(theta)
    phi[st0.q:] = best1['phi'][st1.q:]       # offsets, initial conditions
    if not st0.stable(phi):
        return free
    out = dict(lm(st0, phi, prob0.u, prob0.y, opt['max_iter'], opt['tol']),
               sign=sign)
    probs = {sign: prob0}
    out = _polish(probs, _heads(probs, opt), out, opt, None)
    if not out['cost'] < best0['cost']:
        return free
    out['n_starts'] = best0['n_starts'] + 1
    return prob0, out, linear0


def _fit_sandwich(u, y, orders, lin, k, shape, block, opt, dt, name,
                  progress, offsets, inits):
    """The sandwich of `orders` with k integrators, from the linear fit
    `lin` (on data scaled like `Problem`'s): (problem, best lm, linear)."""
    nb_l, nf_l, nk_l = shape
    i1, i2 = _integrator_split(k, orders, block)
    sign = -1 if lin['B'][0] < 0 else 1
    probs = {sign: Problem(u, y, orders, i1, i2, sign, dt, name, offsets,
                           inits)}
    prob = probs[sign]
    y_all = np.concatenate(y)
    r_lin = y_all - prob.sy * fit_output(
        lin, [part / prob.su for part in prob.u_user], nk_l)
    denom = np.linalg.norm(y_all - y_all.mean())
    linear = {
        'fit': float(100 * (1 - np.linalg.norm(r_lin) / denom)),
        'cost': 0.5 * float(r_lin @ r_lin), 'cost_scaled': lin['cost'],
        'n_params': nb_l + nf_l - k, 'integrators': k,
        'model': oe_transfer_function(lin['B'] * prob.sy / prob.su,
                                      lin['F'], nk_l, dt),
        'converged': lin['converged'], 'message': lin['message']}
    # exact sandwich starts of the linear fit, closed and opened
    def extend(s, phi):
        """A model start with the linear fit's output offsets (and zero
        initial conditions)."""
        st = probs[s].st
        phi = st.extend(phi)
        phi[st.q:st.q + st.n_off] = s * lin['offsets'][:st.n_off]
        return phi

    starts = [(sign, extend(sign, phi))
              for phi in splits(prob.st, sign * lin['B'], lin['F'])]
    B = lin['B']
    if abs(B[0]) < 0.2 * np.max(np.abs(B)):
        # the sign of a small leading coefficient is uncertain: also try
        # the other sign, from the linear fit with that coefficient flipped
        probs[-sign] = Problem(u, y, orders, i1, i2, -sign, dt, name,
                               offsets, inits)
        flipped = B.copy()
        flipped[0] = -B[0]
        starts += [(-sign, extend(-sign, phi)) for phi in
                   splits(probs[-sign].st, -sign * flipped, lin['F'])]
    if not starts:
        raise ValueError(
            f"the linear fit of the total orders cannot be split into "
            f"L1 (na = {orders['na']}, nb = {orders['nb']}) and L2 (nc = "
            f"{orders['nc']}, nd = {orders['nd']})")
    # the screening stages (1, 2) run on the leading `screen_samples`
    # samples; the refinements (3 on) on all of them
    heads = _heads(probs, opt)
    # stage 1: the linear fit's splits, closed and opened, briefly; when
    # there are many, those whose widest opening fits best (one simulation
    # each; closed, they all have the linear fit's cost)
    groups = []
    for s, phi in starts:
        p = probs[s]
        group = [(s, phi)]
        width = l1_std(p.st, phi, p.u)
        for w in opt['widths']:
            opened = phi.copy()
            opened[p.st.im + 2:p.st.im + 4] = w * width
            group.append((s, opened))
        groups.append(group)
    if len(groups) > opt['max_splits']:
        def widest_cost(group):
            s, phi = group[-1]
            return heads[s][0].cost(phi, *heads[s][1:])
        groups = sorted(groups, key=widest_cost)[:opt['max_splits']]
    cands = [c for g in groups for c in g]
    widest = [g[-1] for g in groups]
    bar = _progress(progress, len(cands) + len(widest) + opt['sp_starts']
                    + opt['n_random'] + 1 + opt['keep'] + opt['relocate']
                    + 1 + opt['hops'])
    screened = _screen(cands, heads, opt['screen_iter'] // 2, opt, bar)
    # stage 2: starts in other basins, through the series-parallel cost
    # (measured past outputs in L2: smoother, and exact without noise):
    # from every split opened widest, from the best screened starts, from
    # random structures, and from the recursive prediction-error estimator
    others = []
    if opt['sp_iter']:
        rng = np.random.default_rng(opt['seed'])
        seeds = widest + [(out['sign'], out['phi'])
                          for out in screened[:opt['sp_starts']]]
        seeds += [(sign, probs[sign].st.extend(
            _random_start(probs[sign].st, probs[sign].u, rng)))
            for _ in range(opt['n_random'])]
        for s, phi in seeds:
            st, us, ys = heads[s]
            out = lm(st, phi, us, ys, opt['sp_iter'], sp=True)
            if st.stable(out['phi']):
                others.append((s, out['phi']))
            bar.update()
    if not (k or orders['na'] == 0):
        others += _recursive_start(probs[sign], orders)
    bar.update()
    screened = sorted(screened[:opt['keep']]
                      + _screen(others, heads, opt['screen_iter'], opt, None),
                      key=lambda out: out['cost'])
    # stage 3: the best to convergence, each then with L2 re-fitted to the
    # model's own backlash output (a linear OE problem, solved
    # near-globally) and refined again while that helps
    best, finals = None, []
    for out in screened[:opt['keep']]:
        p = probs[out['sign']]
        out = dict(lm(p.st, out['phi'], p.u, p.y, opt['max_iter'],
                      opt['tol']), sign=out['sign'])
        for _ in range(opt['refits']):
            phi = refit_l2(p.st, out['phi'], p.u, p.y, opt['max_iter'],
                           opt['tol'])
            if phi is None or not (p.st.cost(phi, p.u, p.y)
                                   < out['cost'] * (1 - 1e-6)):
                break                   # L2 is already the best for its v
            # lm never raises the cost, so this refinement is an improvement
            out = dict(lm(p.st, phi, p.u, p.y, opt['max_iter'],
                          opt['tol']), sign=out['sign'])
        finals.append(out)
        if best is None or out['cost'] < best['cost']:
            best = out
        bar.update()
    polished = _polish(probs, heads, best, opt, bar)
    if probs[polished['sign']].st.zeros_at_bound(polished['phi']):
        # a degenerate valley (a zero pressed against the search bound):
        # polish the cheapest other converged start without one as well,
        # and keep the cheaper of the two
        rest = [out for out in finals if out is not best and not
                probs[out['sign']].st.zeros_at_bound(out['phi'])]
        if rest:
            other = _polish(probs, heads, min(rest, key=lambda out:
                                              out['cost']), opt, None)
            if other['cost'] < polished['cost']:
                polished = other
    best = polished
    bar.close()
    cands += others
    if best['cost'] > lin['cost'] or not np.isfinite(best['cost']):
        # the linear model itself, as a sandwich with a closed backlash:
        # a sandwich fit is never worse than the linear fit it nests
        best = _linear_as_sandwich(probs[sign], lin, extend)
    best['n_starts'] = len(cands)
    return probs[best['sign']], best, linear


def _polish(probs, heads, best, opt, bar):
    """Stages 4 to 6 of `_fit_sandwich` from `best`: the smoothed path,
    the relocations (screened on `heads`, the leading samples) and the
    hops; each keeps only what lowers the cost. `bar` (or None) counts
    them."""
    tick = bar.update if bar is not None else (lambda: None)
    # stage 4: a path of smoothed costs from the best (continuous where
    # the exact cost jumps: the slope lines of the backlash cross), then
    # the exact cost again
    if opt['smooth']:
        p = probs[best['sign']]
        out = smooth_refine(p.st, best['phi'], p.u, p.y, opt['max_iter'],
                            opt['tol'])
        if out is not None and out['cost'] < best['cost']:
            best = dict(out, sign=best['sign'])
    tick()
    # stage 5: relocations of one root of L1 (a pole or zero moved across
    # the disk, L2 re-fitted): the local optima that differ from a better
    # one in a single root of L1, which no small perturbation leaves
    for _ in range(opt['relocate']):
        moved = _relocate(probs[best['sign']], heads[best['sign']], best,
                          opt)
        tick()
        if moved is best:
            break
        best = moved
    # stage 6: hops from the best: perturbed copies refined to
    # convergence (kinks of the cost stop LM short of a nearby better
    # minimum, notably with square-wave inputs)
    rng = np.random.default_rng(opt['seed'] + 1)
    for _ in range(opt['hops']):
        best = _hop(probs[best['sign']], best, opt, rng)
        tick()
    return best


def _linear_as_sandwich(prob, lin, extend):
    """The exact closed-backlash sandwich of the linear fit, as an `lm`
    output (the zero radius of its structure lifted to hold the linear
    fit's zeros)."""
    st = prob.st
    st.zero_radius = np.inf
    phi = extend(prob.sign, splits(st, prob.sign * lin['B'], lin['F'])[0])
    out = lm(st, phi, prob.u, prob.y, max_iter=1)
    out['sign'] = prob.sign
    out['converged'] = True
    out['message'] = ("no sandwich start improved on the linear fit: the "
                      "model is the linear fit with a closed backlash")
    return out


#: A hop is refined to convergence only if a short run (screen_iter
#: iterations) already brings it within this share of the best cost.
HOP_SLACK = 0.1


def _hop(prob, best, opt, rng, sigma=0.1):
    """One perturbed restart: the model parameters of `best` moved by
    `sigma` of their size (at least 0.05) and refined (to convergence if
    a short run looks promising, see `HOP_SLACK`); the better of the
    two."""
    st = prob.st
    for _ in range(20):
        phi = best['phi'].copy()
        size = np.maximum(np.abs(phi[:st.q]), 0.05)
        phi[:st.q] += sigma * size * rng.standard_normal(st.q)
        phi = st.clip(phi, 1e-9)
        if st.stable(phi):
            break
    else:
        return best
    out = lm(st, phi, prob.u, prob.y, opt['screen_iter'], opt['tol'])
    if not out['cost'] < best['cost'] * (1 + HOP_SLACK):
        return best                   # on its way back up the same valley
    out = dict(lm(st, out['phi'], prob.u, prob.y, opt['max_iter'],
                  opt['tol']), sign=best['sign'])
    return out if out['cost'] < best['cost'] else best


#: Relocated starts refined to convergence per round.
RELOCATE_KEEP = 2
#: Iterations of the L2 re-fit of a relocated start (a start only).
RELOCATE_REFIT_ITER = 20


def _head(parts, n):
    """The leading samples of the experiments, about n in all (each
    experiment in proportion to its length, at least 50 samples)."""
    total = sum(part.size for part in parts)
    if total <= n:
        return parts
    return [part[:max(50, int(np.ceil(n * part.size / total)))]
            for part in parts]


def _heads(probs, opt):
    """{sign: (structure, u, y)} of each problem's leading
    `screen_samples` samples (see `_head`)."""
    n = opt['screen_samples']
    return {s: (p.st, _head(p.u, n), _head(p.y, n))
            for s, p in probs.items()}


def _relocate(prob, head, best, opt):
    """One round of root relocations from `best` (see `_moves`): every
    moved start gets L2 re-fitted and a short run on `head` = (st, u, y),
    the leading `screen_samples` samples; the best `RELOCATE_KEEP` are
    refined to convergence on all the data. Returns the best of them if
    it lowers the cost, else `best` itself."""
    st, u, y = prob.st, prob.u, prob.y
    us, ys = head[1:]
    starts = []
    for phi in relocations(st, best['phi'], us):
        refit = refit_l2(st, phi, us, ys, RELOCATE_REFIT_ITER, opt['tol'])
        phi = phi if refit is None else refit
        if st.stable(phi):
            starts.append(phi)
    short = sorted((lm(st, phi, us, ys, opt['screen_iter'] // 2, opt['tol'])
                    for phi in starts), key=lambda out: out['cost'])
    found = best
    for out in short[:RELOCATE_KEEP]:
        out = dict(lm(st, out['phi'], u, y, opt['max_iter'], opt['tol']),
                   sign=best['sign'])
        if out['cost'] < found['cost'] * (1 - 1e-6):
            found = out
    return found


def _screen(cands, data, iterations, opt, bar):
    """A few LM iterations from each (sign, phi) on data[sign] = (st, u,
    y); sorted by cost."""
    out = []
    for s, phi in cands:
        st, u, y = data[s]
        res = lm(st, phi, u, y, iterations, opt['tol'])
        res['sign'] = s
        out.append(res)
        if bar is not None:
            bar.update()
    return sorted(out, key=lambda res: res['cost'])


def _random_roots(n, rng, radius=0.9):
    """n roots, real or in conjugate pairs, uniform in the disk."""
    roots = []
    while len(roots) < n:
        r = radius * np.sqrt(rng.random())
        if n - len(roots) >= 2 and rng.random() < 0.5:
            a = rng.uniform(0, np.pi)
            roots += [r * np.exp(1j * a), r * np.exp(-1j * a)]
        else:
            roots.append(r * rng.choice([-1.0, 1.0]) + 0j)
    return np.array(roots)


def _random_start(st, u, rng):
    """A random admissible structure: poles and zeros in the disk, the
    slopes scaled to the spread of x, a random backlash width."""
    na, nb, nc, nd = st.o[:4]
    poly = [np.real(np.poly(_random_roots(n, rng)))[1:] if n else
            np.zeros(0) for n in (st.nc_free, st.na_free, nb, nd)]
    phi = np.concatenate([poly[0], poly[1], [1.0, 1.0, 0.0, 0.0], poly[2],
                          poly[3]])
    width = l1_std(st, phi, u)
    phi[st.im:st.im + 2] = 1.0 / width
    phi[st.im + 2:st.im + 4] = rng.uniform(0.05, 0.8) * width
    return phi


def _progress(progress, total):
    """A tqdm bar over the starts when asked for, else a disabled one."""
    return progress_bar(progress, total=total, desc='identify: starts',
                        leave=False)


def _recursive_start(prob, orders):
    """A start from the recursive prediction-error estimator run
    series-parallel over the scaled data (a different basin than the
    linear fit's; skipped if it fails)."""
    st = prob.st
    try:
        with warnings.catch_warnings():
            warnings.simplefilter('ignore')
            longest = int(np.argmax([part.size for part in prob.u]))
            u, y = prob.u[longest], prob.y[longest]
            est = RecursiveIdentifier(*orders.values(), method='rpem',
                                      warmup=u.size)
            est.update_many(u, y)
        phi = _admissible_start(st, st.phi(est.theta), 1e-9)
    except (ValueError, RuntimeError, np.linalg.LinAlgError):
        return []
    if not st.stable(phi):
        return []
    return [(prob.sign, phi)]


def _identify_recursive(u, y, orders, method, theta0, dt, refine, progress,
                        name, options):
    est = RecursiveIdentifier(*orders.values(), method=method,
                              theta0=theta0, dt=dt, **options)
    start = time.perf_counter()
    step = max(u.size // 20, 1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        for lo in _progress_range(u.size, progress, method, step):
            est.update_many(u[lo:lo + step], y[lo:lo + step])
            if est.diverged_at is not None:
                break
    for w in caught:
        warn(str(w.message), w.category if issubclass(
            w.category, SandwichWarning) else IdentificationWarning)
    result = est.result(elapsed=time.perf_counter() - start)
    if not stable_and_finite(result.theta, est._o):
        result.success = False
        result.message += ("; the estimate is unstable or not finite (a "
                           "pole of L1 or L2 on or outside the unit circle)")
    if refine:
        kwargs = refine if isinstance(refine, dict) else {}
        refined = _refine(result.model, u, y, progress=progress, **kwargs)
        refined.recursive = result
        refined.history = result.history
        refined.method = f"{method}+refine"
        refined.elapsed = time.perf_counter() - start
        result = refined
    if name is not None:
        m = result.model
        result.model = type(m)(m.L1, m.backlash, m.L2, name=name,
                               orders=m.orders)
    return result


def _check_excitation(result, us):
    """Warn if the identified backlash barely leaves its memory zone."""
    model = result.model
    with np.errstate(all='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', SimulationWarning)  # said already
        x = np.concatenate([model.simulate(u, internal=True).outputs[1]
                            for u in us])
    if not np.all(np.isfinite(x)):
        result.excitation = np.nan          # unstable estimate: said already
        return
    _, zones = model.backlash.response(x, return_zones=True)
    moving = float(np.mean(zones != 0))
    result.excitation = moving
    if moving < 0.01:
        warn(f"the backlash of the identified model is outside its memory "
             f"zone in only {moving:.1%} of the samples: the data hardly "
             f"excite it, so m1, m2, D1, D2 are unreliable (is the input "
             f"amplitude smaller than the dead band?)", ExcitationWarning)
