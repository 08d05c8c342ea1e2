"""`identify`: the identification pipeline over a whole record.

The default method, ``'oe'``, is output-error identification started from
the linear model that the sandwich nests:

1. u and y are scaled (units invariance) and a linear output-error model
   of the same total orders is fitted (`identify_linear`'s core, with
   integrators declared or found by AIC). It is the baseline. When it
   has integrators, the search below runs with them in L1 and in L2
   (``integrator_block='auto'``) and keeps the better sandwich, never
   worse than the linear fit without an integrator.
2. Its poles and zeros are assigned to L1 and L2 in every way that keeps
   complex pairs together; each assignment, with m1 = m2 = the linear
   gain and D1 = D2 = 0, is a sandwich with exactly the linear fit.
3. From each, the backlash is opened from a few small widths (and kept
   closed); with series-parallel and random starts (and, with an
   integrator in L2, the model of the search on the output filtered by
   (1 - q^-1) / (1 - 0.95 q^-1), without the drift the play puts on the
   integrator), short
   Levenberg-Marquardt runs on the leading samples screen them and the
   best ones are refined to convergence on all the data.
4. The best is polished: a path through smoothed backlashes (`_smooth`:
   where the slope lines cross, the exact cost jumps), relocations of one
   root of L1 and perturbed restarts (`_starts`); a best that ends with a
   zero on the search bound is retried from the next converged start.
5. Every accepted step lowers the cost, and the closed starts begin at the
   linear cost, so the sandwich never ends worse than the linear model.
   A structure that cannot hold the linear fit (a complex pair for two
   first-order blocks) starts from, and never ends worse than, the best
   linear model it holds (``res.linear['held']``); it is still judged
   against the linear fit, and the message says which roots could not
   be split and which orders hold them.
6. An open backlash must generalise: refitted on the leading three
   quarters of each experiment, the sandwich must predict the held-out
   last quarter at least as well as the linear model refitted there;
   otherwise the model is the closed-backlash floor of step 5 and the
   message says so (``res.held_out``).
   The verdict (``success``) checks stability, convergence, no zero on
   the search bound and that the model explains the data.

A record of more than 200,000 samples is searched on its leading 50,000
and refined on all of them (`_long`; ``res.long_record`` and the message
say so).

The search lives in `_search`, one function or method per step of
``docs/algorithm.md``; the options of each method in `_options`. The
paper's recursive methods (``'bundle'``, ``'gradient'``) and the recursive
prediction-error estimator (``'rpem'``) run here, through
`RecursiveIdentifier`, optionally followed by `refine`. Their models are
judged by the same `verdict`, against the same linear baseline (steps 1
and 2 alone, ``_search.linear_baseline``): one that fits the data worse is
not a success.
"""

import inspect
import numbers
import time
import warnings

import numpy as np

from ._data import excitation_order, input_offset, prepare, with_shift
from ._long import is_long, long_search
from ._options import OEOptions, RECURSIVE, method_options
from ._predictor import padding
from ._problem import Problem
from ._recursive import one_qp_warning
from ._search import Task, linear_baseline, search
from .batch import refine as _refine, _progress_range
from .recursive import RecursiveIdentifier
from .result import verdict, judge
from .._checks import (check_order, warn, serial_blas, SimulationWarning,
                       SandwichWarning, IdentificationWarning)
from .._checks import check_bool, check_data_scale, check_parameter_count

__all__ = ['identify']

#: identify's arguments that apply to some methods only, and where they
#: apply (the options of each method are in `_options`).
APPLIES = dict({'theta0': RECURSIVE, 'refine': RECURSIVE},
               **{name: ('oe',) for name in OEOptions.ARGUMENTS})


@serial_blas
def identify(u, y=None, na=None, nb=None, nc=None, nd=None, q1=1, q2=1,
             method='oe', theta0=None, dt=True, refine=None, progress=False,
             integrators=None, integrator_block=None, name=None,
             offsets='none', initial_state=None, minimum_phase=None,
             **options):
    r"""Identify a sandwich system from input/output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Measured input and output (the system starts at rest), in any
        units: with ``method='oe'`` the result does not depend on them
        (the recursive methods, the paper's, run on the data as given, and
        their step sizes ``eta0`` and ``mu`` are in its units). Instead of
        two arrays,
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
        and ``'gradient'`` are the paper's method and its baseline. They
        can end worse than the linear fit; ``success`` is then False.
    theta0 : array_like, optional
        Recursive methods only: the starting point (order of eq. (2.5)).
    dt : float or True, optional
        Sampling time of the returned model.
    refine : bool or dict, optional
        Recursive methods only: follow the recursive estimate by `refine`
        (a dict gives its keyword arguments; ``{}`` refines with its
        defaults, as True does). Default False.
    progress : bool, optional
        Show progress bars (tqdm) on long runs.
    integrators : int or 'auto', optional
        ``'oe'`` only. Poles fixed at z = 1, e.g. 1 for a speed command in
        and a position out. ``'auto'`` (default) decides from the linear
        fit (AIC; only tried when it has a real pole above 0.9). An
        integrating model is kept only if it fits better than the linear
        fit without one.
    integrator_block : {'auto', 'L1', 'L2'}, optional
        ``'oe'`` only. Where the integrators go. ``'auto'`` (default)
        searches with the integrator in L1 and in L2 (each block that has
        a pole: na > 0, nc > 0) and keeps the lower cost: in a drive the
        nut's position integrates the speed before the play (L1), behind
        a valve with play a cylinder integrates the flow after it (L2).
        This costs one more search, and only when an integrator is tried.
        ``'L1'`` or ``'L2'`` puts them in that block (the other when it
        has too few poles). ``res.integrators`` says where they went.
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
        plant; ``'oe'`` only; the result does not depend on the output's
        zero). The recursive methods take 'none' or 'mean'.
        ``res.offsets`` says what was done. With 'none' or 'estimate', an
        input that starts more than 20 of its standard deviations from
        zero sits at an operating point that the model, from rest at
        u = 0, cannot start from: the result is a failure that says so.
    initial_state : {'zero', 'estimate'}, optional
        ``'oe'`` only. ``'zero'`` (default): each experiment starts from
        rest. ``'estimate'``: the past values before each experiment's
        first sample (x and v, which include the backlash memory, and y:
        the states of L1, the backlash and L2) are estimated with the
        model; they matter for short records and slow or integrating
        plants. ``res.initial_conditions`` gives them per experiment; the
        returned model's own `simulate` starts from rest.
    minimum_phase : {None, False, 'L1'}, optional
        ``'oe'`` only. ``'L1'``: L1's zeros are kept inside the unit
        circle (``|z| < 0.999``), as for the motor and inner loop of a
        drive, so that L1 can be inverted exactly (e.g. by a servo
        controller's feedforward): every start has them reflected
        inside (1 / conj(z), the same magnitude response) and every step
        keeps them there. ``res.minimum_phase`` records it. Default
        None (or False): no constraint, the search of before. The linear
        baseline stays unconstrained, so a constrained model that fits
        worse than it is not a success.
    **options
        The method's options (each method's defaults and checks are one
        frozen dataclass in ``_options``; an option or argument that does
        not apply to the method raises). ``'oe'``: widths (relative
        backlash widths the starts open to, at least one, each in (0, 10);
        default (0.05, 0.25)), screen_iter (8), keep (3), max_iter (200),
        tol (1e-8), min_fit (5, percent), max_splits (16: most pole/zero
        splits of the linear fit screened), sp_iter (15), sp_starts (4),
        n_random (6), seed (0), refits (2: L2 re-fits per refined
        start), relocate (3: rounds of moving roots of L1 across the
        disk, while a round lowers the cost), smooth (True: a path
        through smoothed backlashes), hops (4: perturbed restarts from
        the best), screen_samples
        (2000: the short screening runs use this many leading samples;
        the refinements use all of them); the
        algorithm page of the documentation explains them. Recursive
        methods: see `RecursiveIdentifier`.

    Returns
    -------
    IdentificationResult
        ``model`` (a `SandwichSystem` in the data's units, b0 = 1 and
        d0 = +-1), ``theta``, ``success`` and ``message``, ``fit``,
        ``cost`` and ``linear`` (the linear baseline; ``success`` needs a
        fit at least the baseline's, whatever the method; with ``'held'``,
        the best linear model the structure holds when it cannot hold the
        baseline, see the module documentation); for ``'oe'``
        and a refined recursive estimate also ``std``, and for ``'oe'``
        ``significance`` (F-test of the backlash), ``whiteness``,
        ``integrators`` (where they went: ``{'L1': .., 'L2': ..}``) and
        ``held_out`` (the check that an open backlash predicts the end of
        each experiment, fitted without it, at least as well as the
        linear model; see `IdentificationResult`). ``print(res)`` shows
        them at a glance.

    Raises
    ------
    ValueError
        On constant u or y, too few samples for the orders (fewer than
        10 p plus the delays, or than p**2, with p = na + nb + nc + nd +
        4 parameters), data whose peak magnitude is outside 1e-100 ..
        1e100 (rescale them), orders that
        cannot be estimated, or ``offsets='estimate'`` with a recursive
        method.
    TypeError
        On an option or argument that does not apply to the method (e.g.
        ``integrators`` with ``method='bundle'``, ``theta0`` with
        ``method='oe'``).

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

    A minimum-phase L1 (its zeros inside the unit circle):

    >>> drive = sw.SandwichSystem.from_coefficients(
    ...     a=[-0.7], b=[1.0, 0.5], c=[-0.5], d=[1.0], m1=1.0, m2=1.0,
    ...     D1=0.1, D2=0.1, q1=1, q2=0)
    >>> y = drive.simulate(u).outputs
    >>> res = sw.identify(u, y, na=1, nb=1, nc=1, nd=0, q2=0,
    ...                   minimum_phase='L1')
    >>> res.minimum_phase, bool(max(abs(res.model.L1.zeros())) < 1)
    ('L1', True)
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
    progress = check_bool('progress', progress)
    if refine is not None and not isinstance(refine, (bool, dict)):
        raise TypeError(f"refine must be True, False, None or a dict of "
                        f"sw.refine's options; got {type(refine).__name__} "
                        f"{refine!r}")
    _check_refine_keys(refine)
    us, ys, dt, offset_info, estimate = prepare(u, y, dt, offsets)
    check_data_scale('u', us), check_data_scale('y', ys)
    opt = _method_options(method, options, offsets, dict(
        theta0=theta0, refine=refine, integrators=integrators,
        integrator_block=integrator_block, initial_state=initial_state,
        minimum_phase=None if minimum_phase is False else minimum_phase))
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name must be a string or None; got "
                        f"{type(name).__name__} {name!r}")
    orders = {k: check_order(k, v) for k, v in
              zip(('na', 'nb', 'nc', 'nd', 'q1', 'q2'),
                  (na, nb, nc, nd, q1, q2))}
    _check_length(orders, us)
    if method == 'oe':
        result = _identify_oe(Task(us, ys, orders, opt, dt=dt, name=name,
                                   progress=progress, offsets=estimate))
    else:
        if len(us) > 1:
            raise ValueError(f"method={method!r} is recursive and takes one "
                             f"experiment; got {len(us)} (use method='oe')")
        result = _identify_recursive(us[0], ys[0], orders, method, dict(
            theta0=theta0, dt=dt, refine=refine, progress=progress,
            name=name, options=opt.as_dict()))
    estimated = (result.get('offsets') or {}).get('y')
    result.offsets = with_shift(offset_info, estimated)
    moving = _excitation(result.model, us)
    result.excitation = np.nan if moving is None else moving
    order = _input_order(result, us, orders)
    # L1's free coefficients (need less b0) and m1, m2, D1, D2
    moves = None if moving is None else (
        int(round(moving * sum(np.size(u) for u in us))), order[1] + 3)
    judge(result, verdict(excitation=moving, input_offset=input_offset(us),
                          input_order=order, backlash_moves=moves))
    _warn_mean_integrating(result, offsets)
    return result


def _check_refine_keys(refine):
    """A `refine` dict holds only keywords of `sw.refine` that identify
    does not set itself (checked before a recursive run, not after)."""
    if not isinstance(refine, dict):
        return
    taken = sorted(set(inspect.signature(_refine).parameters)
                   - {'model', 'u', 'y', 'offsets'})
    wrong = sorted(k for k in refine if k not in taken)
    if wrong:
        raise TypeError(f"refine={{...}} holds {wrong[0]!r}, which is not "
                        f"an option of sw.refine here; it takes {taken}")


def _warn_mean_integrating(result, offsets):
    """Warn where a model identified on centred data integrates: the
    means removed changed its drift."""
    k = getattr(result, 'integrators', None)
    if offsets == 'mean' and isinstance(k, dict) and any(k.values()):
        warn("the model integrates, and the means removed from u and y "
             "(offsets='mean') changed its drift, so its fit may mislead: "
             "offsets='estimate' uses the data as given",
             IdentificationWarning)


def _method_options(method, options, offsets, arguments):
    """The options of `method` (`_options`): identify's `arguments` that
    were given (not None) and apply to it, and `options`; one that does
    not apply raises, naming the method."""
    method_options(method, {})                 # checks `method`
    # refine=False, the documented default, is as good as not given
    given = {k: v for k, v in arguments.items()
             if v is not None and not (k == 'refine' and v is False)}
    wrong = sorted(k for k in given if method not in APPLIES[k])
    if wrong:
        raise TypeError(f"{wrong[0]} does not apply to method={method!r}; "
                        f"it applies to {list(APPLIES[wrong[0]])}")
    if offsets == 'estimate' and method != 'oe':
        raise ValueError(f"offsets='estimate' does not apply to method="
                         f"{method!r}, which fits no offset; use "
                         f"offsets='mean' or method='oe'")
    if method == 'oe':
        return method_options(method, dict(
            options, **{k: v for k, v in given.items()
                        if k in OEOptions.ARGUMENTS}))
    return method_options(method, options)


def _check_length(orders, us):
    """Enough samples for the parameters of these orders and delays."""
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


def _identify_oe(task):
    """The output-error search (`_search`) and its judged result."""
    start = time.perf_counter()
    prob, best, linear = (long_search if is_long(task) else search)(task)
    opt = task.opt
    return prob.result(best, 'oe', linear=linear, min_fit=opt.min_fit,
                       extra={'elapsed': time.perf_counter() - start,
                              'minimum_phase': opt.minimum_phase,
                              'options': opt.search(),
                              'n_starts': best['n_starts'], 'theta0': None,
                              'long_record': best.get('long_record'),
                              'held_out': best.get('held_out')})


def _identify_recursive(u, y, orders, method, kw):
    """The recursive route: `RecursiveIdentifier` over the record (`kw`:
    theta0, dt, refine, progress, name and the method's options),
    optionally followed by `refine`."""
    est = RecursiveIdentifier(*orders.values(), method=method,
                              theta0=kw['theta0'], dt=kw['dt'],
                              **kw['options'])
    start = time.perf_counter()
    step = max(u.size // 20, 1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        with one_qp_warning():
            for lo in _progress_range(u.size, kw['progress'], method, step):
                est.update_many(u[lo:lo + step], y[lo:lo + step])
                if est.diverged_at is not None:
                    break
    for w in caught:
        warn(str(w.message), w.category if issubclass(
            w.category, SandwichWarning) else IdentificationWarning)
    # judged finite and stable by the estimator itself
    result = est.result(elapsed=time.perf_counter() - start)
    facts = {}
    if kw['refine'] is not None and kw['refine'] is not False:
        refine = kw['refine']           # True, or a dict ({}: defaults)
        kwargs = dict(progress=kw['progress'])
        kwargs.update(refine if isinstance(refine, dict) else {})
        refined = _refine(result.model, u, y, **kwargs)
        refined.recursive = result
        refined.history = result.history
        refined.method = f"{method}+refine"
        refined.elapsed = time.perf_counter() - start
        result = refined
        facts = {'min_fit': None}           # `refine` judged the rest
    judge(result, verdict(**facts, **_against_linear(result, u, y, orders,
                                                     kw['dt'])))
    if kw['name'] is not None:
        m = result.model
        result.model = type(m)(m.L1, m.backlash, m.L2, name=kw['name'],
                               orders=m.orders)
    return result


def _against_linear(result, u, y, orders, dt):
    """The facts of `verdict` that compare a recursive `result` with the
    linear output-error baseline of the same total orders, fitted as
    'oe' fits its own (`_search.linear_baseline`, without integrators, as
    the recursive methods fit none). Sets ``fit``, ``cost`` and
    ``linear`` on `result`; a model that diverges on the data is judged
    by its estimate alone."""
    task = Task([u], [y], orders, method_options('oe', {'integrators': 0}),
                dt=dt)
    result.linear = linear_baseline(task)
    prob = Problem([u], [y], orders, sign=result.model.gain_sign)
    cost_scaled, result.cost, result.fit = prob.evaluate(result.model)
    if not np.isfinite(cost_scaled):
        return {}
    return dict(fit=result.fit, linear=result.linear,
                cost_scaled=cost_scaled, method=result.method)


def _input_order(result, us, orders):
    """(got, need, 'L1'): how many coefficients the inputs `us` can
    determine (`_data.excitation_order`), and the coefficients of L1
    (na + nb + 1, its integrators fixed): a single sinusoid determines
    two, the phase and gain of L1 at its frequency, and L1's gain trades
    with the backlash's m and D."""
    fixed = (result.get('integrators') or {}).get('L1', 0)
    need = orders['na'] - fixed + orders['nb'] + 1
    return excitation_order(us, need), need, 'L1'


def _excitation(model, us):
    """Share of the samples the model's backlash is outside its memory
    zone on the inputs `us` (None if the model's x is not finite: an
    unstable estimate, said already)."""
    with np.errstate(all='ignore'), warnings.catch_warnings():
        warnings.simplefilter('ignore', SimulationWarning)  # said already
        x = np.concatenate([model.simulate(u, internal=True).outputs[1]
                            for u in us])
    if not np.all(np.isfinite(x)):
        return None
    _, zones = model.backlash.response(x, return_zones=True)
    return float(np.mean(zones != 0))
