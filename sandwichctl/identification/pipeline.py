"""`identify`: the identification pipeline over a whole record.

It runs a recursive estimator (`RecursiveIdentifier`) and, by default,
follows it by the batch output-error refinement (`refine`). See
``docs/algorithm.md`` for the methods and the measured table behind the
default.
"""

import time
import warnings

import numpy as np

from ._predictor import padding
from .recursive import RecursiveIdentifier, DEFAULTS
from .batch import refine as _refine
from .._checks import check_signal

__all__ = ['identify']


def identify(u, y, na, nb, nc, nd, q1=1, q2=1, method='oe', theta0=None,
             dt=True, refine=None, progress=False, **options):
    r"""Identify a sandwich system from input/output data.

    Parameters
    ----------
    u, y : array_like, shape (N,)
        Measured input and output (the system starts at rest).
    na, nb, nc, nd : int
        Orders of eq. (2.1); nb and nd count coefficients after
        b0 = d0 = 1.
    q1, q2 : int, optional
        Known delays (default 1).
    method : {'oe', 'rpem', 'bundle', 'gradient'}, optional
        ``'oe'`` (default) is the library's best: two recursive passes,
        the prediction-error estimator run series-parallel (``'rpem'``
        with ``warmup=N``) and the paper's bundle method, each give the
        start of a batch output-error refinement with multi-start
        (`refine`); the lower output-error cost wins. ``'rpem'`` is the recursive
        Gauss-Newton estimator alone; ``'bundle'`` and ``'gradient'`` are
        the paper's method and its baseline. ``docs/algorithm.md`` gives
        the measured table behind this default.
    theta0 : array_like, optional
        Starting point (order of eq. (2.5)).
    dt : float or True, optional
        Sampling time of the returned model.
    refine : bool or dict, optional
        Follow the recursive estimate by `refine` (a dict gives its
        keyword arguments). Default: True for ``'oe'`` (with
        ``n_starts=8``), False otherwise.
    progress : bool, optional
        Print progress to stderr on long runs.
    **options
        Options of the recursive method (see `RecursiveIdentifier`).

    Returns
    -------
    IdentificationResult
        With ``model`` (a normalised `SandwichSystem`), ``theta``,
        ``history``, ``errors``, step ``counts``, ``success`` and
        ``message``. After refinement also ``std``, ``fit`` and
        ``recursive`` (the recursive pass's result).

    Warns
    -----
    RuntimeWarning
        If the data barely excite the backlash or a parameter is poorly
        determined (large standard error), or if the estimate diverged.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> u = sw.examples.paper_input(2000, seed=1)
    >>> y = plant.simulate(u).outputs
    >>> res = sw.identify(u, y, **plant.orders)
    >>> res.success, bool(sw.parameter_error(res.theta, plant.theta) < 1e-3)
    (True, True)
    """
    u = check_signal('u', u)
    y = check_signal('y', y)
    if u.size != y.size:
        raise ValueError(f"u and y must have the same length; got "
                         f"{u.size} and {y.size} samples")
    if np.ptp(u) == 0:
        raise ValueError("u is constant; a constant input cannot excite "
                         "the backlash or identify the dynamics. Use a "
                         "persistently exciting input (e.g. noise, or "
                         "steps plus sines)")
    if method not in ('oe',) + tuple(DEFAULTS):
        raise ValueError(f"method must be one of "
                         f"{['oe'] + sorted(DEFAULTS)}; got {method!r}")
    recursive = 'rpem' if method == 'oe' else method
    if method == 'oe':
        options = dict({'warmup': u.size}, **options)
        if refine is None:
            refine = {'n_starts': 8, 'seed': 0}
    est = RecursiveIdentifier(na, nb, nc, nd, q1, q2, method=recursive,
                              theta0=theta0, dt=dt, **options)
    p = len(est.labels)
    needed = 10 * p + padding(est._o)
    if u.size < needed:
        raise ValueError(
            f"u and y have {u.size} samples, too few for {p} parameters "
            f"with these orders and delays; give at least {needed}")
    start = time.perf_counter()
    step = max(u.size // 20, 1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        for lo in range(0, u.size, step):
            est.update_many(u[lo:lo + step], y[lo:lo + step])
            if progress:
                _progress(recursive, est.n_samples, u.size, start)
            if est.diverged_at is not None:
                break
    for w in caught:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    result = est.result(elapsed=time.perf_counter() - start)
    if refine:
        kwargs = refine if isinstance(refine, dict) else {}
        refined = _refine(result.model, u, y, progress=progress, **kwargs)
        if method == 'oe':
            # a second, independent start: the paper's bundle method
            # (series-parallel, robust but biased under noise)
            with warnings.catch_warnings():
                warnings.simplefilter('ignore', RuntimeWarning)
                alt = identify(u, y, na, nb, nc, nd, q1, q2,
                               method='bundle', dt=dt, refine=kwargs)
            if alt.cost < refined.cost:
                refined = alt
        refined.recursive = result
        refined.history = result.history
        refined.method = f"{recursive}+refine" if method != 'oe' else 'oe'
        refined.elapsed = time.perf_counter() - start
        result = refined
    _check_excitation(result, u)
    return result


def _check_excitation(result, u):
    """Warn if the identified backlash barely leaves its memory zone."""
    model = result.model
    with np.errstate(all='ignore'):
        x = model.simulate(u, internal=True).outputs[1]
    if not np.all(np.isfinite(x)):
        result.excitation = np.nan          # unstable estimate: said already
        return
    _, zones = model.backlash.response(x, return_zones=True)
    moving = float(np.mean(zones != 0))
    result.excitation = moving
    if moving < 0.01:
        warnings.warn(
            f"the backlash of the identified model is outside its memory "
            f"zone in only {moving:.1%} of the samples: the data hardly "
            f"excite it, so m1, m2, D1, D2 are unreliable (is the input "
            f"amplitude smaller than the dead band?)", RuntimeWarning,
            stacklevel=3)


def _progress(method, done, total, start):
    import sys
    elapsed = time.perf_counter() - start
    left = elapsed / done * (total - done) if done else 0.0
    text = (f"{method:>9}: {done}/{total} samples, {elapsed:5.1f}s elapsed, "
            f"~{left:4.1f}s left")
    if sys.stderr.isatty():
        bar = '#' * int(30 * done / total)
        sys.stderr.write(f"\r{method:>9}: [{bar:<30}] " + text[11:])
        if done >= total:
            sys.stderr.write('\n')
    elif done >= total or (20 * done // total) % 5 == 0:
        sys.stderr.write(text + '\n')       # a line every 25% in logs
    sys.stderr.flush()
