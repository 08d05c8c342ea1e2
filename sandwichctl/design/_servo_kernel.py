"""The compiled per-sample step of `ServoController`.

All parameters live in one float array `p` and all sizes and offsets in
one int array `ix`, so that a call from Python unboxes five arguments.
The layout is written by `pack` and read by `_servo_step`:

``ix``: [preview, lead, n_fb, n_pre, n_post, compensate,
         off_fb, off_pre, off_post, off_scalar, n_lin, off_lin,
         n_ps, off_ps, adapt, n_other, off_other, blend, off_guard,
         d_lin, d_other]

- the feedback block C (e -> u_fb), the linear feedforward (r_ahead ->
  u_lin), the pre-inverse block (r_ahead -> w, the backlash output
  wanted) and the post-inverse block (x -> u_post) are state-space
  blocks, each packed as A (n x n), B (n), C (n), D (1); the linear
  feedforward and the other one read r_ahead d_lin and d_other samples
  late, from the reference delay line (a delay inside a block would be
  as many states, and its dense A their square in operations a sample);
- the process sensitivity block PS = P / (1 + C P) of the design plant
  (u_post -> phi, the regressor of the band's gain) is packed the same way;
- the scalars are [m1, m2, D1, D2, width, mbar, rate, alpha, lam, p0,
  pmax, gmax, pb0, pbmax, hunt, settle, beta, floor, gap, u0, y0]: x = alpha
  w / mbar + the band offset of the inverse; the band path's output is
  scaled by g in [0, gmax], estimated online by recursive least squares
  with forgetting factor lam, initial covariance p0 and largest
  covariance pmax, when ``adapt`` is set; with hunt > 0 the hunting guard
  (`_guard`) scales the error fed to C by c, which drops by beta (down to
  floor) whenever y reverses `TURNS` times in a row by more than hunt, each
  within gap / c samples of the last, in one hold of the reference,
  counted from `settle` samples into it (or in an early window from
  `EARLY` settle on), or whenever the error r - y reverses
  `MOTION_TURNS` times in a row that way while r moves one way.

The state `s` is laid out as [reference delay line (preview), w delay
line (lead), feedback states, pre states, x_prev, v_prev, offset, post
states, linear feedforward states, PS states, g - 1, 1 - P / p0, the
other feedforward's states, and when it is blended, the second PS states,
b, 1 - P_bb / pb0, P_bg / pb0; then the guard's c - 1, r(k-1), samples
into the hold, the last extreme, its direction, the reversals counted,
the sample of the last, samples into the move and the direction of r's
last step]: all zero at rest, where g = 1, b = 0, c = 1 and the
covariance is the prior's.
"""

import numba
import numpy as np

from .inverse import _inverse_step

#: names of the scalars in the scalar part of p, in order
SCALARS = ('m1', 'm2', 'D1', 'D2', 'width', 'mbar', 'rate', 'alpha', 'lam',
           'p0', 'pmax', 'gmax', 'pb0', 'pbmax', 'hunt', 'settle', 'beta',
           'floor', 'gap', 'u0', 'y0')
#: index of each scalar in the scalar part of p
(_M1, _M2, _D1, _D2, _WIDTH, _MBAR, _RATE, _ALPHA, _LAM, _P0, _PMAX, _GMAX,
 _PB0, _PBMAX, _HUNT, _SETTLE, _BETA, _FLOOR, _GAP, _U0,
 _Y0) = range(len(SCALARS))
NSCALAR = len(SCALARS)
#: names of the entries of ix, in order (the layout above)
IX = ('preview', 'lead', 'n_fb', 'n_pre', 'n_post', 'compensate', 'off_fb',
      'off_pre', 'off_post', 'off_scalar', 'n_lin', 'off_lin', 'n_ps',
      'off_ps', 'adapt', 'n_other', 'off_other', 'blend', 'off_guard',
      'd_lin', 'd_other')
#: the entries of ix that Python reads or turns off after `pack`
IX_SCALAR, IX_ADAPT, IX_BLEND, IX_GUARD = (
    IX.index(name) for name in ('off_scalar', 'adapt', 'blend', 'off_guard'))
#: the stretches of scalars that one part of the design writes: the backlash
#: inverse, the compensated band alone, the band gain's estimate, the
#: feedforward blend's prior and the hunting guard
INVERSE = slice(_M1, _ALPHA + 1)
BAND = slice(_D1, _D2 + 1)
ADAPT = slice(_LAM, _GMAX + 1)
BLEND = slice(_PB0, _PBMAX + 1)
GUARD = slice(_HUNT, _GAP + 1)

#: reversals of y in one hold that make the hunting guard scale down
TURNS = 3
#: reversals of the error in a row while the reference moves that do: a
#: loop that tracks had at most 12 on the benchmark's drives (its error
#: turns at the reference's own changes), one that oscillates hundreds
MOTION_TURNS = 24
#: a hold's reversals are also counted in an early window, from this share
#: of the guard's settle on, and that count is dropped just before the
#: settle (a loop can hunt from a hold's start; see the notes of
#: `_servo_guard`)
EARLY = 0.5
#: the guard's state: c - 1, r(k-1), samples into the hold, the last
#: extreme (of y in a hold, of the error in a move), its direction,
#: reversals counted, the sample of the last one, samples into the move,
#: the direction of r's last step
NGUARD = 9


def rest_scalars(u0, y0):
    """The scalars of a design that compensates, estimates and guards
    nothing (unit slopes, no band, g = 1), about the operating point
    (u0, y0)."""
    values = dict.fromkeys(SCALARS, 0.0)
    values.update(m1=1.0, m2=1.0, mbar=1.0, lam=1.0, gmax=1.0,
                  u0=float(u0), y0=float(y0))
    return [values[name] for name in SCALARS]


def pack(feedback, pre, post, linear, sensitivity, other, scalars, preview,
         lead, compensate, adapt, blend, delays=(0, 0)):
    """Lay out the blocks (each an (A, B, C, D) tuple of arrays) and the
    scalars in (p, ix); return them and the state size. `delays`: the
    samples (at most `preview`) by which the linear and the other
    feedforward read r_ahead late."""
    if not all(0 <= d <= preview for d in delays):
        raise ValueError(f"delays {delays} must lie in [0, preview = "
                         f"{preview}]")
    parts, offsets = [], []
    pos = 0
    for A, B, C, D in (feedback, pre, post, linear, sensitivity, other):
        offsets.append(pos)
        n = A.shape[0]
        block = np.concatenate([np.ravel(A), np.ravel(B), np.ravel(C),
                                np.ravel(D)[:1]])
        parts.append(block)
        pos += n * n + 2 * n + 1
    parts.append(np.asarray(scalars, dtype=float))
    p = np.ascontiguousarray(np.concatenate(parts), dtype=float)
    sizes = [feedback[0].shape[0], pre[0].shape[0], post[0].shape[0]]
    n_lin, n_ps = linear[0].shape[0], sensitivity[0].shape[0]
    n_other = other[0].shape[0]
    # the guard's state comes last
    guard = (preview + lead + sizes[0] + sizes[1] + 3 + sizes[2] + n_lin
             + n_ps + 2 + n_other + (n_ps + 3 if blend else 0))
    ix = np.array([preview, lead] + sizes + [int(bool(compensate))]
                  + offsets[:3] + [pos, n_lin, offsets[3], n_ps, offsets[4],
                                   int(bool(adapt)), n_other, offsets[5],
                                   int(bool(blend)), guard, *delays],
                  dtype=np.int64)
    return p, ix, guard + NGUARD


def adapt_index(ix):
    """Where g - 1 and the blend b sit in the state."""
    i_g = (ix[0] + ix[1] + ix[2] + ix[3] + 3 + ix[4] + ix[10] + ix[12])
    return int(i_g), int(i_g + 2 + ix[15] + (ix[12] if ix[17] else 0))


@numba.njit(cache=True)
def _block(p, off, n, s, s0, u):
    """Output C s + D u of a packed block, then s <- A s + B u in place."""
    a, b, c = off, off + n * n, off + n * n + n
    out = p[c + n] * u
    for i in range(n):
        out += p[c + i] * s[s0 + i]
    tmp = np.empty(n)
    for i in range(n):
        acc = p[b + i] * u
        for j in range(n):
            acc += p[a + i * n + j] * s[s0 + j]
        tmp[i] = acc
    for i in range(n):
        s[s0 + i] = tmp[i]
    return out


@numba.njit(cache=True)
def _shift(s, s0, n, value):
    """Push value into the delay line s[s0:s0+n]; return what falls out
    (the value pushed n samples ago; value itself if n = 0)."""
    if n == 0:
        return value
    out = s[s0 + n - 1]
    for i in range(n - 1, 0, -1):
        s[s0 + i] = s[s0 + i - 1]
    s[s0] = value
    return out


@numba.njit(cache=True)
def _late(s, d, preview, ra, r_now):
    """r_ahead d samples ago (0 <= d <= preview), from the reference
    delay line s[:preview] just shifted (s[j] is r_ahead j samples ago)
    or, at d = preview, the sample that fell out of it (r_now)."""
    if d == 0:
        return ra
    if d == preview:
        return r_now
    return s[d]


@numba.njit(cache=True)
def servo_step(p, ix, s, r_ahead, y):
    """One sample of the servo controller; returns u(k), updates s."""
    preview, lead = ix[0], ix[1]
    n_fb, n_pre, n_post, compensate = ix[2], ix[3], ix[4], ix[5]
    sc = ix[9]
    ra = r_ahead - p[sc + _Y0]
    yd = y - p[sc + _Y0]
    # feedback on the error against the reference of this sample
    r_now = _shift(s, 0, preview, ra)
    i_fb = preview + lead
    e = r_now - yd
    if p[sc + _HUNT] > 0.0:
        e *= _guard(p, ix, s, r_now, yd)
    u_fb = _block(p, ix[6], n_fb, s, i_fb, e)
    # feedforward: the backlash output wanted, the inverse, L1's inverse
    i_pre = i_fb + n_fb
    w_ahead = _block(p, ix[7], n_pre, s, i_pre, ra)
    w = _shift(s, preview, lead, w_ahead)
    mbar = p[sc + _MBAR]
    i_bl = i_pre + n_pre
    x = p[sc + _ALPHA] * w / mbar
    if compensate:
        x_inv, v_hat = _inverse_step(w_ahead, s[i_bl], s[i_bl + 1],
                                     p[sc + _M1], p[sc + _M2], p[sc + _D1],
                                     p[sc + _D2], p[sc + _WIDTH])
        s[i_bl], s[i_bl + 1] = x_inv, v_hat
        target = x_inv - w_ahead / mbar
        step = target - s[i_bl + 2]
        rate = p[sc + _RATE]
        if rate > 0.0:
            if step > rate:
                step = rate
            elif step < -rate:
                step = -rate
        s[i_bl + 2] += step
        x += s[i_bl + 2]
    u_ff = _block(p, ix[8], n_post, s, i_bl + 3, x)
    u_lin = _block(p, ix[11], ix[10], s, i_bl + 3 + n_post,
                   _late(s, ix[19], preview, ra, r_now))
    i_ps = i_bl + 3 + n_post + ix[10]
    if ix[17]:
        # the band's gain and the blend towards the other feedforward
        i_o = i_ps + ix[12] + 2
        d = _block(p, ix[16], ix[15], s, i_o,
                   _late(s, ix[20], preview, ra, r_now)) - u_lin
        g, b = _blend(p, ix, s, i_ps, i_o + ix[15], u_ff, d, r_now - yd)
        u_ff *= g
        u_ff += u_lin
        u_ff += b * d
    else:
        if ix[14]:
            u_ff *= _adapt(p, ix, s, i_ps, u_ff, r_now - yd)
        u_ff += u_lin
    return p[sc + _U0] + u_fb + u_ff


@numba.njit(cache=True)
def _guard(p, ix, s, r_now, yd):
    """The hunting guard's scale c(k) on the feedback's error: in a hold
    of the reference (r(k) = r(k-1)), from `settle` samples into it (and
    in an early window from `EARLY` settle samples on, whose count is
    dropped at settle - 1), y's reversals by more than `hunt` from its
    last extreme are counted while each comes within gap / c samples of
    the one before (lower gains slow the loop down; the count restarts
    from 0 after a slower one), and each `TURNS` of them multiply c by
    beta, down to floor (1 at rest); while the reference moves, the
    error's reversals are counted the same way from the move's first
    sample or r's last turn, and each `MOTION_TURNS` of them do."""
    sc, i = ix[9], ix[18]
    if r_now != s[i + 1]:
        s[i + 2] = 0.0                  # a new hold starts
        z = r_now - yd
        step = 1.0 if r_now > s[i + 1] else -1.0
        if s[i + 7] == 0.0 or step != s[i + 8]:
            # a move starts, or r turns (its own turns, or a reference
            # that jitters, turn the error): count afresh
            s[i + 3], s[i + 4], s[i + 5] = z, 0.0, 0.0
        s[i + 8] = step
        s[i + 7] += 1.0
        t, need = s[i + 7], MOTION_TURNS
    else:
        s[i + 2] += 1.0
        s[i + 7] = 0.0
        z, t, need = yd, s[i + 2], TURNS
    s[i + 1] = r_now
    settle = p[sc + _SETTLE]
    if s[i + 7] == 0.0 and (s[i + 2] < EARLY * settle
                            or s[i + 2] == settle - 1.0):
        s[i + 3], s[i + 4], s[i + 5] = yd, 0.0, 0.0
    else:
        move = z - s[i + 3]
        if s[i + 4] * move > 0.0:
            s[i + 3] = z                # further the same way
        elif abs(move) > p[sc + _HUNT]:
            if s[i + 4] != 0.0:
                if t - s[i + 6] <= p[sc + _GAP] / (1.0 + s[i]):
                    s[i + 5] += 1.0
                else:
                    s[i + 5] = 0.0
            s[i + 4] = 1.0 if move > 0.0 else -1.0
            s[i + 3] = z
            s[i + 6] = t
        if s[i + 5] >= need:
            c = (1.0 + s[i]) * p[sc + _BETA]
            if c < p[sc + _FLOOR]:
                c = p[sc + _FLOOR]
            s[i], s[i + 5] = c - 1.0, 0.0
    return 1.0 + s[i]


@numba.njit(cache=True)
def _adapt(p, ix, s, i_ps, u_post, e):
    """The band path's gain g(k), after the recursive least-squares step
    on the error e(k) = r(k) - y(k) with the regressor phi(k) = PS u_post
    (the error's sensitivity to g; PS is strictly proper, so phi(k) holds
    u_post up to k - 1 only)."""
    sc, n_ps = ix[9], ix[12]
    phi = _block(p, ix[13], n_ps, s, i_ps, u_post)
    i_g = i_ps + n_ps
    g, p0 = 1.0 + s[i_g], p[sc + _P0]
    cov = p0 * (1.0 - s[i_g + 1])
    lam = p[sc + _LAM]
    gain = cov * phi / (lam + phi * phi * cov)
    g += gain * e
    cov = (cov - gain * phi * cov) / lam
    if cov > p[sc + _PMAX]:
        cov = p[sc + _PMAX]
    if g < 0.0:
        g = 0.0
    elif g > p[sc + _GMAX]:
        g = p[sc + _GMAX]
    s[i_g], s[i_g + 1] = g - 1.0, 1.0 - cov / p0
    return g


@numba.njit(cache=True)
def _blend(p, ix, s, i_ps, i_ps2, u_post, d, e):
    """(g, b) after the recursive least-squares step on e(k) with the
    regressors PS d (d: the other feedforward less the chosen one; b its
    share) and PS u_post (g: the band path's gain)."""
    sc, n_ps = ix[9], ix[12]
    phi_g = _block(p, ix[13], n_ps, s, i_ps, u_post)
    phi_b = _block(p, ix[13], n_ps, s, i_ps2, d)
    i_g, i_b = i_ps + n_ps, i_ps2 + n_ps
    p0g, p0b = p[sc + _P0], p[sc + _PB0]
    g, b = 1.0 + s[i_g], s[i_b]
    pgg = p0g * (1.0 - s[i_g + 1])
    pbb = p0b * (1.0 - s[i_b + 1])
    pbg = p0b * s[i_b + 2]
    lam = p[sc + _LAM]
    hb = pbb * phi_b + pbg * phi_g
    hg = pbg * phi_b + pgg * phi_g
    den = lam + phi_b * hb + phi_g * hg
    kb, kg = hb / den, hg / den
    b += kb * e
    g += kg * e
    pbb = (pbb - kb * hb) / lam
    pbg = (pbg - kb * hg) / lam
    pgg = (pgg - kg * hg) / lam
    # a bound on a variance scales the covariance by the same ratio (the
    # matrix stays positive semidefinite)
    if pbb > p[sc + _PBMAX]:
        pbg *= p[sc + _PBMAX] / pbb
        pbb = p[sc + _PBMAX]
    if pgg > p[sc + _PMAX]:
        pbg *= p[sc + _PMAX] / pgg
        pgg = p[sc + _PMAX]
    if g < 0.0:
        g = 0.0
    elif g > p[sc + _GMAX]:
        g = p[sc + _GMAX]
    if b < 0.0:
        b = 0.0
    elif b > 1.0:
        b = 1.0
    s[i_g], s[i_g + 1] = g - 1.0, 1.0 - pgg / p0g
    s[i_b], s[i_b + 1], s[i_b + 2] = b, 1.0 - pbb / p0b, pbg / p0b
    return g, b


@numba.njit(cache=True)
def servo_run(p, ix, s, r_ahead, y):
    """`servo_step` over given sequences (open loop: y is given); from
    the first sample whose memory overflows on, u is nan."""
    u = np.full(r_ahead.size, np.nan)
    for k in range(r_ahead.size):
        u[k] = servo_step(p, ix, s, r_ahead[k], y[k])
        if not _finite(s):
            u[k] = np.nan
            break
    return u


@numba.njit(cache=True)
def servo_step_kept(p, ix, s, keep, r_ahead, y):
    """`servo_step` with the memory s copied to `keep` first, so that a
    caller can put it back when u overflows: u is nan when u or the
    memory does (a huge r_ahead can fill the memory with inf before it
    reaches u)."""
    keep[:] = s
    u = servo_step(p, ix, s, r_ahead, y)
    return u if _finite(s) else np.nan


@numba.njit(cache=True)
def _finite(s):
    """Whether every entry of the memory s is finite."""
    for v in s:
        if not np.isfinite(v):
            return False
    return True
