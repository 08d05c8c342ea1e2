"""What a servo design reads from the data of an identification result.

`servo_controller` designs from a model; when that model comes with its
identification record, the linear fit's residuals say how far to trust
it, by frequency band (`tools.residuals.error_bands`,
`tools.residuals.relative_error`):

- how fast the PID may cross over (`crossover_limit`): up to where the
  model's relative error stays small, between CROSSOVER_LIMIT['pid'] and
  CROSSOVER_MOST plant bandwidths;
- on what plant its margins are read (`data_plant`): the plant's
  response as the data measured it (the fit corrected by the part of its
  residual that follows the fit's own output), besides or instead of the
  model.
"""

import numpy as np
import control as ct

from . import _servo_design as sd
from ._servo_design import (CROSSOVER_LIMIT, bandwidth, constraint_columns,
                            frequency_grid, loop_gain, tf_arrays)
from ..model.sandwich import SandwichSystem
from ..tools.residuals import band_errors
from .inverse import _fmt_roots

__all__ = []

#: a PID designed from an identification result may cross over above
#: CROSSOVER_LIMIT['pid'], up to CROSSOVER_MOST plant bandwidths, as far
#: as the residuals of its data put the model's relative error below
#: TRUSTED in every band from the lowest up (`tools.residuals.error_bands`).
#: The residuals of a drive with much play reach it within a few
#: bandwidths (its limit stays 3: a larger one hunted when the load
#: coasted, see above); those of a play-free one only beyond 10, and there
#: the limit of 3, not the modulus margin, bound the loop. Robust
#: stability asks |T| delta < 1: with |T| <= 1, TRUSTED leaves a factor 2
TRUSTED = 0.5
CROSSOVER_MOST = 8.0
#: relative standard error up to which `measured_response` uses the data
RELIABLE = 0.1
#: `checked_model`: a pole of L1 or L2 above the band the data measured is
#: one no record vouches for when its factor 1 / (z - p) peaks more than
#: RESONANT times above its DC gain, |1 - p| / (1 - |p|) (a mode all but
#: undamped: a mechanical mode damped at 2 % at a quarter of the sampling
#: frequency peaks 45 times); the checks read it damped to radius TAMED,
#: its angle and the block's DC gain kept
RESONANT = 100.0
TAMED = 0.5


def _top(w, good):
    """The highest of the band centres w up to which every band is
    `good` (0 if the first is not)."""
    bad = np.flatnonzero(~good)
    return float(w[-1] if bad.size == 0 else
                 (w[bad[0] - 1] if bad[0] else 0.0))


def trusted_band(bands):
    """The highest frequency (rad/sample) up to which every band of the
    error bands (w, delta) has delta <= TRUSTED (0 if the first has
    not)."""
    w, delta = (np.asarray(a, float) for a in bands)
    return _top(w, delta <= TRUSTED)


def crossover_limit(bands, num, den):
    """(limit, why): the crossover limit of `design_pid` in plant
    bandwidths for the plant num/den, given the error bands (w, delta) of
    its data (`tools.residuals.error_bands`, None for a model without
    data), and why in words."""
    if np.any(sd.at_one(np.roots(den))):
        return CROSSOVER_LIMIT['pd'], "the PD's of an integrating plant"
    base = CROSSOVER_LIMIT['pid']
    if bands is None or len(bands[0]) == 0:
        return base, 'the default, for a model without data'
    wb = bandwidth(num, den, frequency_grid(den))
    trusted = trusted_band(bands)
    ratio = trusted / wb
    limit = float(np.clip(ratio, base, CROSSOVER_MOST))
    return limit, (
        f"the data's residuals put the model's relative error below "
        f"{TRUSTED:g} up to {ratio:.3g} plant bandwidths ("
        + (f"below the least limit, {base:g}, which holds" if ratio < base
           else f"above the largest, {CROSSOVER_MOST:g}, which holds"
           if ratio > CROSSOVER_MOST else
           f"within the limits {base:g} to {CROSSOVER_MOST:g}") + ")")


def measured_response(base, rel):
    """The plant's frequency response as the data of an identification
    result measured it, from its baseline fit `base` and that fit's
    relative error `rel` (`result_errors`): a callable of w (rad/sample)
    giving the baseline's response times 1 + the relative error
    (`tools.residuals.relative_error`, interpolated on log w), NaN outside
    the bands from the lowest up to the last whose standard error is
    below RELIABLE; with the top of that range. None without them or
    without a reliable band."""
    if rel is None or not isinstance(base, ct.TransferFunction):
        return None
    wk, dk, sk = (np.asarray(a) for a in rel)
    if wk.size == 0:                # a record of fewer than 64 samples
        return None
    top = _top(wk, sk <= RELIABLE)
    if not top > wk[0]:
        return None
    num, den = tf_arrays(base)

    def response(w):
        w, lw = np.asarray(w, float), np.log(np.maximum(w, 1e-300))
        d = (np.interp(lw, np.log(wk), dk.real)
             + 1j * np.interp(lw, np.log(wk), dk.imag))
        return np.where((w >= wk[0]) & (w <= top), (1 + d) * np.polyval(
            num, np.exp(1j * w)) / np.polyval(den, np.exp(1j * w)), np.nan)
    return response, top


def wild_poles(poles, top):
    """Which of `poles` no data vouch for: above `top` rad/sample (the top
    of the band measured reliably) and all but undamped (`RESONANT`)."""
    poles = np.asarray(poles, complex)
    with np.errstate(divide='ignore', invalid='ignore'):
        peak = np.abs(1 - poles) / (1 - np.abs(poles))
    return (np.abs(np.angle(poles)) > top) & (np.abs(poles) < 1) \
        & (peak > RESONANT)


def checked_model(model, response, notes):
    """The sandwich `model` that the checks of `_servo_checks` run loops
    around: `model` itself, or with the poles of L1 and L2 that no data
    vouch for damped (`RESONANT`, `TAMED`), told in `notes`. Such a pole
    lies above the top of the band `measured_response` measured reliably,
    all but on the unit circle: a swept sine up to 12 Hz of a speed loop
    sampled at 1 kHz left a pole of L1 at -0.9993, a mode at the Nyquist
    frequency that the input never excited (its low-frequency tail, half a
    sample of lead, fits the record). A loop designed on the linear
    baseline, which fits the record as well without it, runs away around
    that mode, and the checks moved the feedback to the sandwich's own
    mbar L1 L2: a loop 24 times worse on the drive than the linear
    design's. The design itself keeps the model's poles."""
    if response is None or not isinstance(model, SandwichSystem):
        return model
    moved = []
    L1, L2 = (_tamed(block, lambda p: wild_poles(p, response[1]), moved)
              for block in (model.L1, model.L2))
    if not moved:
        return model
    notes.append(
        f"the checks around the identified model read its pole(s) at "
        f"{_fmt_roots(np.array(moved))} damped to radius {TAMED:g} "
        f"(DC gain kept): modes all but undamped above the band the record "
        f"measured reliably ({response[1]:.3g} rad/sample), which no data "
        f"vouch for (excite the plant up there to identify them)")
    return SandwichSystem(L1, model.backlash, L2, name=model.name)


def _roots(poly):
    """The roots of a polynomial (descending powers; none if constant)."""
    return np.roots(poly) if np.size(poly) > 1 else np.zeros(0)


def _tamed(block, select, moved):
    """`block` with the poles `select` picks (a mask of the poles) damped
    to radius TAMED, their angle and the block's DC gain kept; they are
    added to `moved`."""
    num, den = sd.tf_arrays(block)
    poles = _roots(den)
    wild = select(poles)
    if not np.any(wild):
        return block
    moved.extend(poles[wild])
    new = np.where(wild, TAMED * np.exp(1j * np.angle(poles)), poles)
    dc = np.prod((1 - new[wild]) / (1 - poles[wild]))
    return ct.tf(num * np.real(dc), np.real(np.poly(new)), block.dt)


def nyquist_tamed(baseline, response, notes, what='the linear baseline'):
    """The linear `baseline` a sandwich's PID is designed on, with its real
    poles on the negative axis that no data vouch for (`wild_poles`)
    damped like `checked_model`'s, told in `notes`. Such a pole is an
    oscillation at exactly the Nyquist frequency, which the fit may have
    placed from its low-frequency tail alone (a digital inner loop tuned
    aggressively can have one too: `_servo_linear.tamed_part` checks the
    PID on the baseline as fitted). The baseline of
    a speed loop identified from a record at a tenth of the usual
    amplitude had one at -0.9869; the PD designed on it held that mode, its
    derivative gain fell to 9.8 and the loop tracked the drive at 16.3 um,
    1.21 times the linear design's error (6.5 um with the pole damped).
    `what` names the model in the note."""
    if response is None or not isinstance(baseline, ct.TransferFunction):
        return baseline
    moved = []
    baseline = _tamed(baseline, lambda p: wild_poles(p, response[1])
                      & (np.abs(p.imag) < 1e-9) & (p.real < 0), moved)
    if moved:
        notes.append(
            f"the PID is designed on {what} with its pole(s) at "
            f"{_fmt_roots(np.array(moved))} damped to radius {TAMED:g} (DC "
            f"gain kept): real modes at the Nyquist frequency, above the "
            f"band the record measured reliably ({response[1]:.3g} "
            f"rad/sample), which no data vouch for")
    return baseline


def measured_modulus(measured, num, den, C):
    """The modulus margin of the loop C P on the log grid, read where
    `design_pid` reads it (`constraint_columns`): with `data_plant`'s
    `measured`, on the measured response where it has data and on the
    plant num/den elsewhere, and on the plant too unless alone."""
    w = frequency_grid(den, 6000)
    wc, P = constraint_columns(w, np.polyval(num, np.exp(1j * w))
                               / np.polyval(den, np.exp(1j * w)), measured)
    one = np.ones(1)
    return float(np.min(np.abs(1 + P * loop_gain(one, one, C, wc))))


def result_errors(result):
    """(error bands, relative error, baseline) of an identification
    result's linear fit (`tools.residuals.band_errors`): of
    `identify_linear`'s from its residuals, of `identify`'s as it stored
    them for its baseline; None for each it has not (no result, or a
    result of an older version)."""
    e, yhat = (getattr(result, key, None) for key in ('residuals', 'yhat'))
    if e is not None and yhat is not None:
        return (*band_errors(e, yhat), result.model)
    linear = getattr(result, 'linear', None)
    if not isinstance(linear, dict):
        return None, None, None
    return (linear.get('error_bands'), linear.get('relative_error'),
            linear.get('model'))


def data_plant(measured, bands, num, den):
    """`design_pid`'s `measured` for the plant num/den: (response, alone,
    trusted), with response `measured_response`'s callable, alone whether
    the margins are read on it alone (else on it and the model both) and
    trusted how far the residuals vouch for the model, in plant
    bandwidths (`trusted_band`); None
    without a measured response, or one that turns the design plant's
    phase by 90 deg or more where it starts (the plant is then not the
    baseline the data measured, and does not move the output the same
    way). Alone only where the residuals vouch
    for the model up to CROSSOVER_MOST plant bandwidths (`trusted_band`):
    a record of a drive with play measures the response at its own
    amplitude, and a speed loop's PD designed on it alone hunted where the
    model's did not (random drive 39 of benchmarks/bench_servo.py, 42 um:
    18 reversals in a hold, 3.4 -> 10.5 um)."""
    if measured is None:
        return None
    w = frequency_grid(den)
    G = measured[0](w)
    have = np.flatnonzero(np.isfinite(G))
    z = np.exp(1j * w[have[0]]) if have.size else None
    if z is None or not np.real(G[have[0]] * np.polyval(den, z)
                                / np.polyval(num, z)) > 0:
        return None
    wb = bandwidth(num, den, w)
    trusted = (trusted_band(bands) / wb if bands is not None
               and len(bands[0]) > 0 else 0.0)
    return measured[0], bool(trusted >= CROSSOVER_MOST), trusted


def measured_arrays(data, den):
    """(w, P): `data_plant`'s measured response where it has data, on the
    log grid of the plant with denominator den; None without data."""
    if data is None:
        return None
    w = frequency_grid(den)
    G = data[0](w)
    return w[np.isfinite(G)], G[np.isfinite(G)]


def margin_words(data, response, mmeas, mmod, num, den):
    """Where the design's margins were read, in words, for its notes:
    `data_plant`'s data, `measured_response`'s (response, top), the
    margin so measured and the model's, for the plant num/den."""
    grid = frequency_grid(den)
    if data is None:
        return f" (got {mmod:.3f} on a log grid from {grid[0]:.1e} rad/sample)"
    top = f"{response[1] / bandwidth(num, den, grid):.3g} plant bandwidths"
    how = ("the baseline fit's response corrected by its residuals, tools."
           "residuals.relative_error")
    return ((f", read on the plant's response as the data measured it up to "
             f"{top} ({how}) and on the model above" if data[1] else
             f", read on the model and, up to {top}, on the plant's response "
             f"as the data measured it ({how}) too: the residuals vouch for "
             f"the model only below {CROSSOVER_MOST:g} plant bandwidths")
            + f" (got {mmeas:.3f}; {mmod:.3f} on the model alone, on a log "
            f"grid from {grid[0]:.1e} rad/sample)"
            + _wild_words(response, den))


def _wild_words(response, den):
    """The margin note's words on the plant's poles that no data vouch for
    (`wild_poles`), or ''."""
    poles = _roots(den)
    wild = poles[wild_poles(poles, response[1])]
    if not wild.size:
        return ""
    return (f"; the plant's pole(s) at {_fmt_roots(wild)} are all but "
            f"undamped above the band the record measured reliably "
            f"({response[1]:.3g} rad/sample): the margins hold them, which "
            f"lowers the gains where no data vouch for the model (excite the "
            f"plant up there to identify them)")


def raised_words(num, den, C, info):
    """The design note's words on a PID raised past |T| <= T_PEAK where
    the data vouch for the model (`_servo_design.RAISE_MOST`; `info` as
    `design_pid` filled it), or ''."""
    if 'raised' not in info:
        return ''
    w = frequency_grid(den)
    L = loop_gain(num, den, C, w)
    return (f"; then its three gains raised together {info['raised']:.3g} "
            f"times (at most {sd.RAISE_MOST:g}) as far as that margin "
            f"allows, crossing over below {info['limit']:.3g} plant "
            f"bandwidths, where the residuals vouch for the model: |T| "
            f"peaks at {float(np.max(np.abs(L / (1 + L)))):.4g} on the "
            f"model")
