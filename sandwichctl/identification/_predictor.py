r"""The predictor of the sandwich model and its sensitivities (private).

This module is the one place that builds the model output
:math:`\hat y(k, \theta)` and its derivative
:math:`w(k) = \partial \hat y(k, \theta) / \partial \theta`. All estimators
use it. Signals live in *padded* arrays: index ``pad + k`` holds sample k
and the first ``pad`` entries are the zero past, so ``arr[t - lag]`` is
always valid. ``o = (na, nb, nc, nd, q1, q2)`` are the orders and theta is
ordered as eq. (2.5): c, a, (m1, m2, D1, D2), b, d, with b0 = d0 = 1.

Two predictors are provided.

``window_predict`` (the paper's Section 3)
    f(k, theta) = e(k, theta)^2 / 2 is evaluated with the *stored* past of
    the estimator: x_hat and v_hat before the window are those the
    estimator computed when those samples were current. Only the backlash
    outputs that enter y_hat(k) directly, v_hat(k - q2 - j) for
    j = 0..nd (eq. (3.2)), are recomputed with theta, each from its stored
    memory (x_hat(t-1), v_hat(t-1)). Its gradient is eqs. (3.2)-(3.3):
    static (no recursion through past estimates) and zero in the memory
    zone. The past outputs y*(k-i) are either measured (series-parallel)
    or the stored predictions (parallel), see `identify`.

``oe_steps`` (exact output-error sensitivities)
    Sensitivities of the simulated output carried recursively through
    L1's dynamics, through the backlash (including its memory zone, where
    dv(k)/dtheta = dv(k-1)/dtheta) and through L2's dynamics.

At a switching point of eq. (2.2) both use the gradient of the zone that
`backlash_step` selects, which is one of the limiting gradients and so a
Clarke subgradient (Definition 3.1).
"""

import os
import threading
from concurrent.futures import ThreadPoolExecutor, wait

import numba
import numpy as np

from ..model.backlash import backlash_step

__all__ = []


@numba.njit(cache=True, inline='always')
def _idx(o):
    """Offsets (ia, im, ib, id) into theta for orders o."""
    na, nb, nc, nd = o[0], o[1], o[2], o[3]
    ia = nc
    im = nc + na
    ib = im + 4
    return ia, im, ib, ib + nb


def padding(o):
    """Number of zero samples needed in front of the signals."""
    na, nb, nc, nd, q1, q2 = o
    return q1 + nb + q2 + nd + na + nc + 2


@numba.njit(cache=True, inline='always')
def l1_output(theta, o, u, xs, t):
    """x_hat(t) of eq. (2.1) with stored past x_hat (xs) and input u."""
    na, nb, q1 = o[0], o[1], o[4]
    ia, im, ib, idd = _idx(o)
    x = u[t - q1]
    for j in range(1, nb + 1):
        x += theta[ib + j - 1] * u[t - q1 - j]
    for i in range(1, na + 1):
        x -= theta[ia + i - 1] * xs[t - i]
    return x


@numba.njit(cache=True, inline='always')
def l2_output(theta, o, vs, past, k):
    """y_hat(k) of eq. (2.1) from the backlash outputs vs and the past
    outputs `past` (the model's own, or measured ones)."""
    nc, nd, q2 = o[2], o[3], o[5]
    idd = _idx(o)[3]
    y = 0.0
    for i in range(1, nc + 1):
        y -= theta[i - 1] * past[k - i]
    for j in range(nd + 1):
        dj = 1.0 if j == 0 else theta[idd + j - 1]
        y += dj * vs[k - q2 - j]
    return y


@numba.njit(cache=True, inline='always')
def add_direct_partials(out, scale, zone, x, m1, m2, D1, D2, im):
    """Add scale * (direct derivative of v(k) w.r.t. m1, m2, D1, D2).

    Eq. (3.3): v = m1 (x - D1) in the increase zone gives (x - D1, -m1)
    for (m1, D1); v = m2 (x + D2) in the decrease zone gives (x + D2, m2)
    for (m2, D2); the memory zone has none. Returns the slope of the
    active line (0 in the memory zone), by which dx/dtheta enters dv.
    """
    if zone == 1:
        out[im] += scale * (x - D1)
        out[im + 2] -= scale * m1
        return m1
    if zone == -1:
        out[im + 1] += scale * (x + D2)
        out[im + 3] += scale * m2
        return m2
    return 0.0


@numba.njit(cache=True, nogil=True)
def window_predict(theta, o, u, ystar, xs, vs, zs, k, grad):
    """y_hat(k, theta) of the paper's recursive predictor; see module doc.

    Writes the gradient (3.2)-(3.3) into `grad`. Returns (y_hat,
    nonsmooth) where nonsmooth is True if any recomputed backlash sample
    switches zone with respect to the stored zone before it.
    """
    na, nb, nc, nd, q1, q2 = o
    ia, im, ib, idd = _idx(o)
    m1, m2, D1, D2 = theta[im], theta[im + 1], theta[im + 2], theta[im + 3]
    grad[:] = 0.0
    yhat = 0.0
    nonsmooth = False
    for i in range(1, nc + 1):
        yhat -= theta[i - 1] * ystar[k - i]
        grad[i - 1] = -ystar[k - i]
    for j in range(nd + 1):
        t = k - q2 - j
        dj = 1.0 if j == 0 else theta[idd + j - 1]
        xt = l1_output(theta, o, u, xs, t)
        vt, zone = backlash_step(xt, xs[t - 1], vs[t - 1], m1, m2, D1, D2)
        yhat += dj * vt
        if j > 0:
            grad[idd + j - 1] = vt
        if zone != zs[t - 1]:
            nonsmooth = True
        m = add_direct_partials(grad, dj, zone, xt, m1, m2, D1, D2, im)
        if zone == 0:
            continue                    # memory zone: (3.3) gives 0
        for i in range(1, na + 1):
            grad[ia + i - 1] -= dj * m * xs[t - i]
        for jj in range(1, nb + 1):
            grad[ib + jj - 1] += dj * m * u[t - q1 - jj]
    return yhat, nonsmooth


@numba.njit(cache=True, nogil=True)
def store_state(theta, o, u, ystar_src, xs, vs, zs, ys, k, grad):
    """Store x_hat(k), v_hat(k), zone(k) and y_hat(k) for theta.

    `ystar_src` is the array the predictor reads past outputs from (the
    measured y, or `ys` itself for the parallel predictor). Returns
    y_hat(k).
    """
    im = _idx(o)[1]
    xs[k] = l1_output(theta, o, u, xs, k)
    v, z = backlash_step(xs[k], xs[k - 1], vs[k - 1], theta[im],
                         theta[im + 1], theta[im + 2], theta[im + 3])
    vs[k] = v
    zs[k] = z
    yhat, _ = window_predict(theta, o, u, ystar_src, xs, vs, zs, k, grad)
    ys[k] = yhat
    return yhat


@numba.njit(cache=True, nogil=True)
def oe_steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, k0, k1, past,
             parallel):
    """Samples k0..k1-1 of the output-error model with sensitivities.

    Computes x_hat(k), v_hat(k), zone(k), y_hat(k) from the stored past
    and their exact derivatives with respect to theta, Sx[k], Sv[k],
    Sy[k] (rows of p entries), carried recursively through L1, the
    backlash memory and L2. Returns y_hat(k1 - 1). (The loop over samples
    lives here, not in the callers, so that a whole record runs without a
    function call per sample.)

    L2's AR part reads its past outputs from `past`: ``ys`` itself with
    ``parallel=True`` (output error), or the measured outputs with
    ``parallel=False`` (series-parallel); then Sy has no recursion through
    L2's poles, but the L1 and backlash sensitivities stay exact.
    """
    return _steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, k0, k1, past,
                  parallel, Sx.shape[0], Sv.shape[0])


@numba.njit(cache=True, nogil=True)
def _steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, k0, k1, past, parallel,
           rx_n, rv_n):
    """`oe_steps`, its rings' sizes given: Sx and Sv may be rings whose
    row t lives at t % rows (whole records need only the last few rows of
    each; see `simulate_with_sensitivities`). A kernel compiled for given
    orders (`_build`) passes them as constants."""
    na, nb, nc, nd, q1, q2 = o
    ia, im, ib, idd = _idx(o)
    m1, m2, D1, D2 = theta[im], theta[im + 1], theta[im + 2], theta[im + 3]
    p = theta.size
    # x and v depend only on L1 and the backlash: theta[ia:idd] (a, m1,
    # m2, D1, D2, b). Their other sensitivity columns stay at the zeros
    # the caller's buffers hold, so only these are computed.
    y = 0.0
    for k in range(k0, k1):
        # L1, eq. (2.1); rows are updated whole (contiguous) for speed
        x = l1_output(theta, o, u, xs, k)
        xs[k] = x
        rx = Sx[k % rx_n]
        for r in range(ia, idd):
            rx[r] = 0.0
        for i in range(1, na + 1):
            ai = theta[ia + i - 1]
            prev = Sx[(k - i) % rx_n]
            for r in range(ia, idd):
                rx[r] -= ai * prev[r]
            rx[ia + i - 1] -= xs[k - i]
        for j in range(1, nb + 1):
            rx[ib + j - 1] += u[k - q1 - j]
        # backlash, eq. (2.2)
        v, zone = backlash_step(x, xs[k - 1], vs[k - 1], m1, m2, D1, D2)
        vs[k] = v
        zs[k] = zone
        rv = Sv[k % rv_n]
        if zone == 0:
            prev = Sv[(k - 1) % rv_n]
            for r in range(ia, idd):
                rv[r] = prev[r]
        else:
            m = m1 if zone == 1 else m2
            for r in range(ia, idd):
                rv[r] = m * rx[r]
            add_direct_partials(rv, 1.0, zone, x, m1, m2, D1, D2, im)
        # L2, eq. (2.1)
        y = l2_output(theta, o, vs, past, k)
        ys[k] = y
        ry = Sy[k]
        for r in range(p):
            ry[r] = 0.0
        if parallel:
            for i in range(1, nc + 1):
                ci = theta[i - 1]
                prev = Sy[k - i]
                for r in range(p):
                    ry[r] -= ci * prev[r]
        for j in range(nd + 1):
            dj = 1.0 if j == 0 else theta[idd + j - 1]
            prev = Sv[(k - q2 - j) % rv_n]
            for r in range(ia, idd):
                ry[r] += dj * prev[r]
        for i in range(1, nc + 1):
            ry[i - 1] -= past[k - i]
        for j in range(1, nd + 1):
            ry[idd + j - 1] += vs[k - q2 - j]

    return y


@numba.njit(cache=True, nogil=True)
def is_stable(theta, start, n, margin):
    """True if z^n + theta[start] z^(n-1) + ... has all roots inside
    |z| < 1 - margin (Schur-Cohn step-down test on the scaled polynomial).
    """
    if n == 0:
        return True
    r = 1.0 - margin
    a = np.empty(n + 1)
    a[0] = 1.0
    scale = 1.0
    for i in range(1, n + 1):
        scale /= r                       # roots of p(r z) inside |z| < 1
        a[i] = theta[start + i - 1] * scale
    b = np.empty(n + 1)
    for m in range(n, 0, -1):
        kr = a[m]
        if not abs(kr) < 1.0:
            return False
        den = 1.0 - kr * kr
        for j in range(m + 1):
            b[j] = (a[j] - kr * a[m - j]) / den
        for j in range(m + 1):
            a[j] = b[j]
    return True


@numba.njit(cache=True, nogil=True)
def stable_and_finite(theta, o):
    """Both denominators stable (|poles| < 0.999) and finite."""
    for r in range(theta.size):
        if not np.isfinite(theta[r]):
            return False
    na, nc = o[0], o[2]
    return is_stable(theta, nc, na, 1e-3) and is_stable(theta, 0, nc, 1e-3)


@numba.njit(cache=True, nogil=True)
def oe_simulate(theta, o, u, pad, xs, vs, zs, ys, Sx, Sv, Sy):
    """Run `oe_steps` over a whole padded record (fixed theta)."""
    oe_steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, pad, u.size, ys, True)


@numba.njit(cache=True, nogil=True)
def sp_simulate(theta, o, u, ymeas, pad, xs, vs, zs, ys, Sx, Sv, Sy):
    """`oe_simulate` with L2's past outputs measured (series-parallel)."""
    oe_steps(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, pad, u.size, ymeas,
             False)


@numba.njit(cache=True, inline='always')
def _smoothed_step(x, x_prev, v_prev, m1, m2, D1, D2, eps):
    """Eq. (2.2) with its choice of line smoothed (see `smooth_output`)."""
    rising = max(v_prev, m1 * (x - D1))
    falling = min(v_prev, m2 * (x + D2))
    w = min(max(0.5 + 0.5 * (x - x_prev) / eps, 0.0), 1.0)
    return w * rising + (1.0 - w) * falling


@numba.njit(cache=True, nogil=True)
def _output_padded(theta, o, u, past, pad, xs, vs, ys, eps):
    """The recursion without derivatives; L2's past outputs are read from
    `past`: ys itself (output error) or the measured ones
    (series-parallel). With eps > 0 the backlash is smoothed
    (`smooth_output`)."""
    im = _idx(o)[1]
    m1, m2, D1, D2 = theta[im], theta[im + 1], theta[im + 2], theta[im + 3]
    for k in range(pad, u.size):
        x = l1_output(theta, o, u, xs, k)
        xs[k] = x
        if eps > 0.0:
            v = _smoothed_step(x, xs[k - 1], vs[k - 1], m1, m2, D1, D2, eps)
        else:
            v, _ = backlash_step(x, xs[k - 1], vs[k - 1], m1, m2, D1, D2)
        vs[k] = v
        ys[k] = l2_output(theta, o, vs, past, k)


#: A record of at least this many samples (the search's head of a long
#: record, `_long.LONG_HEAD`, and beyond) is simulated by kernels compiled
#: for its orders (`_kernel`): the same recursion as `oe_simulate`,
#: `sp_simulate` and `_output_padded`, whose loops then have constant
#: bounds and whose rings are indexed by a mask, 3 to 4 times faster a
#: sample (benchmarks/bench_long_records.py). Compiling the three takes
#: about 4 s the first time for a set of orders on a machine (numba's
#: cache keeps them); they are compiled on a thread of their own while the
#: kernels for any orders run. Shorter records, and the grids of orders
#: that `select_structure` tries on them, keep the kernels for any orders.
#: The linear fits switch to their lagged normal equations at the same
#: length (`_linear._lagged_normal`).
SPECIALIZE_FROM = 50_000

_KERNELS = {}           # (orders, kind): the Future of its compiled kernel
_KERNELS_LOCK = threading.Lock()
_COMPILER = []          # the compiling thread's executor, made on first use


def ring_rows(o):
    """Rows of the rings that hold x's and v's sensitivities: the power
    of two at or above `padding(o)`."""
    return 1 << (padding(o) - 1).bit_length()


def _kernel(o, kind, n, *rings):
    """The kernel of `kind`: 'oe' (`oe_simulate`), 'sp' (`sp_simulate`)
    or 'output' (`_output_padded`), called as they are, for a record of
    `n` samples whose sensitivity rings are `rings`: one compiled for the
    orders `o` from `SPECIALIZE_FROM` samples on (rings of `ring_rows`)
    once its compilation, started by the first such call, is done; else
    the one for any orders. The numbers are the same, bit for bit
    (tests/test_predictor_kernels.py), so which one runs changes only the
    time (and a compilation that failed leaves the one for any orders)."""
    o = tuple(int(v) for v in o)
    rows = ring_rows(o)
    if n < SPECIALIZE_FROM or any(r.shape[0] != rows for r in rings):
        return _any_orders(kind)
    with _KERNELS_LOCK:
        job = _KERNELS.get((o, kind))
        if job is None:
            if not _COMPILER:
                _COMPILER.append(ThreadPoolExecutor(
                    max_workers=1, thread_name_prefix='sandwichctl-kernels'))
            job = _KERNELS[(o, kind)] = _COMPILER[0].submit(
                _compiled, o, kind, rows)
    if job.done() and job.exception() is None:
        return job.result()
    return _any_orders(kind)


def wait_for_kernels():
    """Wait until every kernel `_kernel` has started to compile is
    compiled or has failed (tests and timings that want them all; and
    before a fork, which must not copy numba's compiler lock while the
    compiling thread holds it)."""
    with _KERNELS_LOCK:
        jobs = list(_KERNELS.values())
    wait(jobs)


def _forked():
    """In a forked child: the compiling thread was not copied, so a new
    one is made on the next compilation."""
    _COMPILER.clear()


if hasattr(os, 'register_at_fork'):
    os.register_at_fork(before=wait_for_kernels, after_in_child=_forked)


def _any_orders(kind):
    """The kernel of `kind` for any orders."""
    return {'oe': oe_simulate, 'sp': sp_simulate,
            'output': _output_padded}[kind]


def _compiled(o, kind, rows):
    """`_build`'s kernel, compiled by a call on an empty record of the
    types the callers pass."""
    kernel = _build(o, kind, rows)
    pad, p = padding(o), sum(o[:4]) + 4
    theta, u, xs, vs, ys = (np.zeros(p), np.zeros(pad), np.zeros(pad),
                            np.zeros(pad), np.zeros(pad))
    if kind == 'output':
        kernel(theta, o, u, ys, pad, xs, vs, ys, 0.0)
        return kernel
    zs, ring, Sy = (np.zeros(pad, dtype=np.int64), np.zeros((rows, p)),
                    np.zeros((pad, p)))
    if kind == 'sp':
        kernel(theta, o, u, np.zeros(pad), pad, xs, vs, zs, ys, ring,
               ring.copy(), Sy)
    else:
        kernel(theta, o, u, pad, xs, vs, zs, ys, ring, ring.copy(), Sy)
    return kernel


#: Copies of the recursions without numba's cache, for the kernels of
#: `_build`: those compile them for their orders as literal types, and a
#: cached overload for each set of orders would share one cache index that
#: processes compiling other orders at once could mix up.
_steps_for_orders = numba.njit(nogil=True)(_steps.py_func)
_output_for_orders = numba.njit(nogil=True)(_output_padded.py_func)


def _build(o, kind, rows):
    """A kernel of `kind` with the orders `o` and the rings' `rows` as
    constants (numba takes closure variables as constants); the orders
    passed in the call are not read. Each set of orders has a cache file
    of its own (`_jit_for`)."""
    if kind == 'output':
        @_jit_for(o, rows)
        def output(theta, _o, u, past, pad, xs, vs, ys, eps):
            _output_for_orders(theta, o, u, past, pad, xs, vs, ys, eps)
        return output
    if kind == 'sp':
        @_jit_for(o, rows)
        def series(theta, _o, u, ymeas, pad, xs, vs, zs, ys, Sx, Sv, Sy):
            _steps_for_orders(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, pad,
                              u.size, ymeas, False, rows, rows)
        return series

    @_jit_for(o, rows)
    def parallel(theta, _o, u, pad, xs, vs, zs, ys, Sx, Sv, Sy):
        _steps_for_orders(theta, o, u, xs, vs, zs, ys, Sx, Sv, Sy, pad,
                          u.size, ys, True, rows, rows)
    return parallel


def _jit_for(o, rows):
    """numba.njit with its cache in files named after the orders and rows:
    numba names a cache after the function and updates its index without a
    lock, so kernels of other orders that processes compile at once must
    not share one."""
    def jit(func):
        func.__qualname__ += '_' + '_'.join(str(v) for v in o + (rows,))
        return numba.njit(cache=True, nogil=True)(func)
    return jit


def init_sizes(o):
    """How many past values of x, v and y make an initial condition.

    x(-1..-max(na, 1)) (x(-1) is also the backlash memory's input),
    v(-1..-max(q2 + nd, 1)) (v(-1) is the memory) and y(-1..-nc); the
    input before the record is taken as zero.
    """
    na, nb, nc, nd, q1, q2 = o
    return max(na, 1), max(q2 + nd, 1), nc


def _place_init(pad, init, xs, vs, ys, ymeas=None):
    """Write past values (newest first) before sample 0 of padded arrays."""
    if init is None:
        return
    x_past, v_past, y_past = init
    for arr, past in ((xs, x_past), (vs, v_past), (ys, y_past)):
        for i, value in enumerate(past):
            arr[pad - 1 - i] = value
    if ymeas is not None:
        for i, value in enumerate(y_past):
            ymeas[pad - 1 - i] = value


def smooth_output(theta, o, u, eps, init=None):
    r"""Simulated output of a sandwich whose backlash is smoothed (eps > 0).

    Eq. (2.2) reads v(k) = max(v(k-1), m1 (x(k) - D1)) while x rises and
    min(v(k-1), m2 (x(k) + D2)) while it falls. Where the slope lines
    cross, the two differ by a finite amount, so the output jumps when a
    small change of the parameters flips the sign of a tiny x(k) - x(k-1),
    and the output-error cost is discontinuous. Here the two are blended,
    weight w = clip(1/2 + (x(k) - x(k-1)) / (2 eps), 0, 1) on the rising
    one: the output is continuous in the parameters, and eq. (2.2)
    wherever |x(k) - x(k-1)| >= eps. A path of decreasing eps leads an
    optimiser across the jumps (see `_smooth`).
    """
    return oe_signals(theta, o, u, init, eps=eps)[0]


def oe_output(theta, o, u, init=None):
    """Simulated output y_hat (no sensitivities), from zero state or from
    the past values `init` = (x_past, v_past, y_past) (see `init_sizes`).

    The same recursion as `oe_steps` without the derivatives: the cheap
    cost evaluation of a trial step.
    """
    return oe_signals(theta, o, u, init)[0]


def sp_output(theta, o, u, ymeas, init=None):
    """The series-parallel prediction (L2's past outputs measured), no
    sensitivities: the cheap cost of a trial step of that predictor."""
    return oe_signals(theta, o, u, init, ymeas)[0]


def oe_signals(theta, o, u, init=None, ymeas=None, eps=0.0):
    """`oe_output`'s y_hat with the intermediate signals: (y, x, v); with
    `ymeas`, the series-parallel prediction's; with eps > 0, those of the
    smoothed backlash (`smooth_output`)."""
    pad = padding(o)
    n = u.size
    up = np.zeros(pad + n)
    up[pad:] = u
    xs, vs, ys = np.zeros(pad + n), np.zeros(pad + n), np.zeros(pad + n)
    if ymeas is None:
        past = ys
    else:
        past = np.zeros(pad + n)
        past[pad:] = ymeas
    _place_init(pad, init, xs, vs, ys, None if ymeas is None else past)
    _kernel(o, 'output', n)(np.ascontiguousarray(theta, dtype=float), o,
                            up, past, pad, xs, vs, ys, float(eps))
    return ys[pad:], xs[pad:], vs[pad:]


def simulate_with_sensitivities(theta, o, u, ymeas=None, init=None):
    """Simulated output y_hat and Jacobian d y_hat / d theta (N x p).

    Zero initial conditions (or the past values `init`, see `oe_output`),
    like the estimators. Returns (y_hat, J, zones). With `ymeas` (the
    measured output), L2's past outputs are measured ones: the
    series-parallel predictor and its Jacobian.
    """
    pad = padding(o)
    n = u.size
    up = np.zeros(pad + n)
    up[pad:] = u
    xs, vs, ys = np.zeros(pad + n), np.zeros(pad + n), np.zeros(pad + n)
    zs = np.zeros(pad + n, dtype=np.int64)
    p = theta.size
    # only the output's sensitivities are returned; those of x and v are
    # read a few samples back, so rings of at least `pad` rows hold them
    rows = ring_rows(o)
    Sx, Sv = np.zeros((rows, p)), np.zeros((rows, p))
    Sy = np.zeros((pad + n, p))
    theta = np.ascontiguousarray(theta, dtype=float)
    if ymeas is None:
        _place_init(pad, init, xs, vs, ys)
        _kernel(o, 'oe', n, Sx, Sv)(theta, o, up, pad, xs, vs, zs, ys, Sx,
                                    Sv, Sy)
    else:
        yp = np.zeros(pad + n)
        yp[pad:] = ymeas
        _place_init(pad, init, xs, vs, ys, yp)
        _kernel(o, 'sp', n, Sx, Sv)(theta, o, up, yp, pad, xs, vs, zs, ys,
                                    Sx, Sv, Sy)
    return ys[pad:], Sy[pad:], zs[pad:]
