"""Which linear model a sandwich's servo design is built on: the feedback
on the result's linear baseline or on the sandwich's mbar L1 L2, the
feedforward inverting the one or the other (`linear_part`), the baseline
with its real modes at the Nyquist frequency damped where the PID so
designed holds on the baseline as fitted (`tamed_part`; a linear model's
own design likewise, `tamed_model`), the drift terms
(a pole at z = 1 beside a zero) cancelled from a model first, and the
design's note on the linear feedforward (`ff_note`)."""

import numpy as np
import control as ct

from ..model.sandwich import SandwichSystem
from .._checks import PINNED
from .inverse import _fmt_roots
from ._servo_design import (AT_ONE, FF_ACTIVITY, RINGING, at_one,
                            design_pid, loop_margins, low_frequency_gain,
                            low_frequency_sign, pid_tf, series_length,
                            tf_arrays)
from ._servo_data import nyquist_tamed


#: the sandwich's linear part drives the feedforward of a non-integrating
#: axis when the sandwich fits this many points better than the linear
#: baseline: the play then distorts the baseline's dynamics
MODEL_FF_GAP = 2.0


def outside(zeros, max_preview):
    """Which zeros lie outside the unit circle where the preview inverse
    can keep only their DC gain (sampling zeros on the negative real axis
    it may keep so)."""
    return np.array([abs(zj) >= 1 and np.real(zj) >= RINGING
                     and series_length(zj) > max_preview
                     for zj in zeros], bool)


def feedforward_source(choice, result, integrating, zeros, max_preview):
    """Whether the feedforward inverts the sandwich's own mbar L1 L2
    (else the linear baseline), and why (`choice` is 'auto', 'model' or
    'baseline'; there is a baseline)."""
    if choice != 'auto':
        return choice == 'model', "as asked"
    fits = getattr(result, 'fit', None), result.linear.get('fit')
    if any(fit is None for fit in fits):
        raise ValueError("feedforward_from='auto' compares model.fit with "
                         "model.linear['fit'] (percent), and the result "
                         "has not both: give them, or pass "
                         "feedforward_from='model' or 'baseline'")
    gap = fits[0] - fits[1]
    # zeros outside the unit circle that the preview inverse can only
    # keep by their DC gain (sampling zeros on the negative real axis
    # it may keep so)
    far = outside(zeros, max_preview)
    use = not integrating and gap >= MODEL_FF_GAP and not far.any()
    return use, (f"the sandwich fits {gap:.1f} points better than the "
                 f"baseline (" + ("at least " if gap >= MODEL_FF_GAP
                                  else "less than ") + f"{MODEL_FF_GAP:g})"
                 + (", but L1 integrates" if integrating else "")
                 + (f", but L1 L2 has zeros outside the unit circle at "
                    f"{_fmt_roots(zeros[far])}" if far.any() else ""))


def linear_part(model, result, lin_model, feedback_from, feedforward_from,
                integrating, zeros, max_preview, mm, check_plant,
                limit=None, measured=None, info=None):
    """The linear part of a sandwich's design: (P, pid, ff_model, note,
    baseline). P is the plant the feedback is designed on and pid its
    gains where they were designed already (else None; `zeros` are L1
    L2's); ff_model whether
    the feedforward inverts the sandwich's mbar L1 L2 (else the
    baseline); note why; baseline the linear baseline where the design
    uses it (else None). `limit`: `design_pid`'s, a callable of the
    plant's (num, den), or None; `measured` likewise; `info` is passed
    on to `design_pid`.

    The baseline (`lin_model`, a result's linear fit) carries the play's
    effect on the loop, so by default the feedback is designed on it;
    not when L2 integrates: a linear model cannot follow the drift the
    play puts through an integrator after it, and spends a slow pole and
    zero on it (step 5 of docs/algorithm.md), often with the wrong sign
    or a crossover hundreds of times too slow; nor when the baseline's
    low-frequency gain has the sign opposite to the sandwich's (with an
    integrator in L1 and unequal slopes it can spend such a pair on the
    drift too, and its PD then pushes the plant the wrong way); nor when
    the baseline's fit stopped with a free pole pinned at the stability
    boundary (`pinned`: its integral gain comes out near zero)."""
    for name, choice in (('feedback_from', feedback_from),
                         ('feedforward_from', feedforward_from)):
        if choice == 'baseline' and not isinstance(lin_model,
                                                   ct.TransferFunction):
            raise ValueError(f"{name}='baseline' needs an identification "
                             f"result with a linear baseline (sw.identify's "
                             f"result)")
    co = model.coefficients
    own = 0.5 * (co['m1'] + co['m2']) * model.L1 * model.L2
    if lin_model is None:
        return own, None, True, "linear part designed on the model's " \
            "mbar L1 L2", None
    why = None
    if feedback_from == 'auto' and integrates(model.L2):
        why = ("L2 integrates (the integrator after the play), which a "
               "linear baseline cannot follow (it spends a slow pole and "
               "zero on the play's drift)")
    elif feedback_from == 'auto' and (
            low_frequency_sign(*tf_arrays(lin_model))
            != low_frequency_sign(*tf_arrays(own))):
        why = ("the result's linear baseline and the sandwich's mbar L1 L2 "
               "move the output opposite ways at low frequency (the "
               "baseline spent a pole and zero near z = 1 on the play's "
               "drift)")
    elif feedback_from == 'auto' and (radius := pinned(lin_model)):
        why = (f"the result's linear baseline has a free pole pinned at "
               f"the stability boundary (|p| = {radius:.7f}: its fit "
               f"stopped there)")
    if why is not None:
        why += ", so linear part designed on the model's mbar L1 L2"
        if feedforward_from == 'baseline':      # asked: kept
            return own, None, False, why + ("; feedforward inverts the "
                                            "baseline: as asked"), lin_model
        return own, None, True, why, None
    pid, fb_why = None, ''
    if feedback_from != 'model':
        try:
            num, den = check_plant('the baseline', lin_model)
            pid = design_pid(num, den, lin_model.dt, mm,
                             limit(num, den) if callable(limit) else limit,
                             measured(num, den) if callable(measured)
                             else measured, info)
        except ValueError as exc:
            if 'baseline' in (feedback_from, feedforward_from):
                raise ValueError(f"the result's linear baseline, asked for "
                                 f"by feedback_from or feedforward_from, "
                                 f"cannot be designed on: {exc}") from None
            # the sandwich is what identify vouched for: design on it
            return own, None, True, (
                f"the result's linear baseline cannot be designed on "
                f"({exc}), so linear part designed on the model's mbar L1 "
                f"L2"), None
    else:
        fb_why = " (as asked)"
    use, why = feedforward_source(feedforward_from, result, integrating,
                                  zeros, max_preview)
    note = ("feedback designed on " + ("the result's linear baseline fit"
                                       if pid is not None else
                                       "the sandwich's mbar L1 L2" + fb_why)
            + "; feedforward inverts the " + ("sandwich's mbar L1 L2" if use
                                              else "baseline") + f": {why}")
    return (lin_model if pid is not None else own), pid, use, note, lin_model


#: `tamed_part` keeps the PID designed on the damped baseline when its
#: modulus margin on the baseline as fitted is at least this share of the
#: one asked
TAMED_MARGIN = 0.98


def tamed_part(model, result, lin_model, feedback_from, feedforward_from,
               integrating, zeros, max_preview, mm, check_plant, limit,
               measured, *, response, notes, info):
    """`linear_part` (the same arguments) on the baseline with its real
    modes at the Nyquist frequency damped (`_servo_data.nyquist_tamed`),
    where the PID so designed also meets the modulus margin (`TAMED_MARGIN`)
    on the baseline as fitted, told in `notes`; else `linear_part` on the
    fitted baseline. Such a pole may be an artefact of the fit (a record
    at a tenth of the usual amplitude: its PD held the mode and tracked
    the drive 1.21 times worse than the linear design) or the plant's
    (an aggressive digital inner loop rings at the Nyquist frequency): a
    PID designed without a real one can run away on the plant."""
    rest = (feedback_from, feedforward_from, integrating, zeros,
            max_preview, mm, check_plant, limit, measured)
    said, trial = [], {}
    tamed = nyquist_tamed(lin_model, response, said)
    if tamed is not lin_model:
        got = linear_part(model, result, tamed, *rest, info=trial)
        if got[0] is tamed and got[1] is not None and _holds_as_fitted(
                (*check_plant('the baseline', lin_model), lin_model.dt),
                got[1], mm, ('the baseline', 'the linear baseline'), said,
                notes):
            info.update(trial)
            return got
    return linear_part(model, result, lin_model, *rest, info=info)


def _holds_as_fitted(fitted, pid, mm, names, said, notes):
    """Whether the PID `pid` (kp, ki, kd, pole), designed with the real
    modes of `fitted` (num, den, dt) at the Nyquist frequency damped
    (`said`: `nyquist_tamed`'s note), meets `TAMED_MARGIN` of the modulus
    margin `mm` on `fitted` as it is, told in `notes`; `names` are the
    plant's short and long names."""
    num, den, dt = fitted
    margin, _, _, radius = loop_margins(num, den, pid_tf(*pid, dt))
    if radius < 1 and margin >= TAMED_MARGIN * mm:
        notes.append(f"{said[0]}; its PID meets modulus margin "
                     f"{margin:.3g} on {names[0]} as fitted too")
        return True
    notes.append(f"{names[1]}'s real modes at the Nyquist frequency kept "
                 f"as fitted: a PID designed with them damped would not "
                 f"meet the margin on it")
    return False


def only_itself(**choices):
    """Refuse a choice between a sandwich's own linear part and its
    baseline (feedforward_from, feedback_from) for a linear model."""
    for key, choice in choices.items():
        if choice != 'auto':
            raise ValueError(
                f"{key}={choice!r} chooses between a sandwich's own "
                f"linear part and its linear baseline, and a linear "
                f"model is only itself: leave it out")


def tamed_model(model, response, mm, check_plant, limit, measured, *,
                notes, info):
    """A linear model's own design plant and PID (P, pid): the model with
    its real modes at the Nyquist frequency damped (`nyquist_tamed`) and
    the PID designed on it, where that PID also meets the modulus margin
    on the model as fitted (`TAMED_MARGIN`), told in `notes`, as
    `tamed_part` does for a sandwich's baseline; else (model, None). The
    linear design of a record must treat such a mode as the sandwich's
    does: on an axis whose baseline had one at -0.9869 the sandwich's PD,
    designed without it, used 5.3 times the input activity of the linear
    design's, which held the mode (benchmarks/bench_servo_foreign.py,
    axis 3, speed loop, 9 um)."""
    said = []
    tamed = nyquist_tamed(model, response, said, 'the model')
    if tamed is model:
        return model, None
    fitted = (*check_plant('model', model), model.dt)
    num, den = check_plant('the design plant', tamed)
    trial = {}
    try:
        pid = design_pid(num, den, tamed.dt, mm, limit(num, den),
                         measured(num, den), trial)
    except ValueError:           # no PID on the damped model: as fitted
        return model, None
    if _holds_as_fitted(fitted, pid, mm, ('the model', 'the model'), said,
                        notes):
        info.update(trial)
        return tamed, pid
    return model, None


#: a pole at z = 1 with a zero this close to it is a drift term of the
#: model, not an integrator of the axis: the pair is cancelled first
UNIT_CANCEL = 1e-4


def cancel_unit_pair(sys):
    """`sys` with a pole at z = 1 removed together with the zero next to
    it (within `UNIT_CANCEL`), when no other pole is that close to 1; or,
    beside a pole at z = 1 (an integrator), a second pole that close with
    that zero: a drift term (the linear fit pins a free pole at its
    stability boundary on the play's drift, with a zero beside it); its
    high-frequency gain is kept. A free pole pinned there (beyond `PINNED`)
    counts as one at z = 1: with a zero beside it, it is the same drift
    term (random drive 41 of benchmarks/bench_servo.py: a pole at 0.999999
    and a zero at 0.9999986, their DC gain 1.4 times the rest's).
    Returns (sys, the zero cancelled or None)."""
    num, den = tf_arrays(sys)
    if num.size < 2 or den.size < 2:
        return sys, None
    poles, zeros = np.roots(den), np.roots(num)
    unit = np.flatnonzero(at_one(poles) | (_pinned_mask(poles)
                                           & (np.abs(poles.imag) < AT_ONE)))
    near = np.flatnonzero(np.abs(zeros - 1) < UNIT_CANCEL)
    close = np.flatnonzero(np.abs(poles - 1) < UNIT_CANCEL)
    if not (near.size and unit.size and close.size in (1, 2)):
        return sys, None      # none, or more poles near 1 than a pair
    i = near[np.argmin(np.abs(zeros[near] - 1))]
    gone = close[np.argmax(np.abs(poles[close] - 1))]
    num = np.real(num[0] * np.poly(np.delete(zeros, i)))
    den = np.real(den[0] * np.poly(np.delete(poles, gone)))
    return ct.tf(num, den, sys.dt, name=sys.name), float(np.real(zeros[i]))


def pinned(sys):
    """The radius of `sys`'s largest pole inside the unit circle, not at
    z = 1 (within 5e-7: an integrator; a pinned pole is 1e-6 or more
    inside), when it is beyond `PINNED`, else None."""
    poles = np.roots(tf_arrays(sys)[1])
    inside = np.abs(poles[_pinned_mask(poles)])
    return float(inside.max()) if inside.size else None


def _pinned_mask(poles):
    """Which of the poles lie inside the unit circle beyond `PINNED`, not
    at z = 1 (within 5e-7: an integrator): pinned at the boundary."""
    radii = np.abs(poles)
    return (np.abs(poles - 1) > 5e-7) & (radii > PINNED) & (radii < 1)


def integrates(block):
    """True if the transfer function has a pole at z = 1."""
    den = block.den[0][0].astype(float)
    return den.size > 1 and bool(np.any(at_one(np.roots(den))))


def cancel_drift(model, notes):
    """A model with its drift terms (`cancel_unit_pair`) cancelled, each
    told in `notes`."""
    def cancel(sys, pole, zero):
        out, at = cancel_unit_pair(sys)
        if at is not None:
            notes.append(f"{pole} at (or pinned next to) z = 1 and {zero} "
                         f"at {at:.7g} cancelled before the design (a drift "
                         f"term of the model, not an integrator)")
        return out

    if isinstance(model, SandwichSystem):
        L1, L2 = (cancel(getattr(model, tag), f"a pole of {tag}",
                         "its zero")
                  for tag in ('L1', 'L2'))
        if L1 is model.L1 and L2 is model.L2:
            return model
        return SandwichSystem(L1, model.backlash, L2, name=model.name)
    if isinstance(model, ct.TransferFunction) and model.issiso():
        return cancel(model, "a pole", "the zero")
    return model


def band_note(model, share, asked, jump, lead, gains):
    """The design note on the backlash inverse: `share` of the model's
    band (D1 + D2, in x), `asked` by the user or the default, its jump
    spread over `jump` samples and started `lead` early; with L2
    integrating and the feedback's `gains` (kp, ki) a PD, how far from
    the reference a hold may stop (`hold_error`)."""
    co = model.coefficients
    band = co['D1'] + co['D2']
    if not band > 0:
        return ("no backlash inverse: the identified backlash is closed "
                "(D1 + D2 = 0 in x), so there is no band to compensate")
    text = (f"backlash inverse on the reference: {share:.0%} of the "
            f"model's band (D1 + D2 = {band:.4g} in x) "
            + ("as asked" if asked else
               "by default" + (" for an integrating L1"
                               if integrates(model.L1) else "")
               + ", since the play a loop sees is smaller than the gap (the "
               "load coasts into it) and more over-compensated on the "
               "benchmark drives")
            + f"; jump spread over {jump} samples, started {lead} early")
    error = hold_error(model, share, *gains)
    if error:
        text += (f"; L2 integrates and the feedback is a PD (integral "
                 f"action would hunt around the play before the "
                 f"integrator), so a hold may stop up to {error:.3g} in y "
                 f"from the reference, where the PD must push x across "
                 f"the {1 - share:.0%} of the band left uncompensated "
                 f"(a larger band_fraction shrinks it; 1 where the model "
                 f"is the plant)")
    return text


def hold_error(model, share, kp, ki):
    """How far from the reference a hold may stop when L2 integrates and
    the feedback is a PD: y stops wherever x rests inside the band, and
    the PD's error moves x by kp times L1's DC gain, so the part of the
    band the inverse leaves, (1 - share)(D1 + D2), is a dead zone of
    that width over kp |L1(1)| in the error. None where L2 does not
    integrate, the feedback integrates or L1 does (x then moves on)."""
    co = model.coefficients
    if ki != 0 or not kp > 0 or not integrates(model.L2):
        return None
    n, d, integrating = low_frequency_gain(*tf_arrays(model.L1))
    if integrating:
        return None
    with np.errstate(divide='ignore', invalid='ignore'):
        error = (1 - share) * (co['D1'] + co['D2']) * abs(d / (kp * n))
    return float(error) if np.isfinite(error) and error > 0 else None


def ff_note(kind, preview, approx, linear_note, smooth, ratio):
    """The design note on the linear feedforward."""
    text = (f"feedforward: model inverse with {preview} samples of "
            f"preview" + (" (ZPETC for zeros outside the unit circle)"
                          if kind == 'zpetc' else ""))
    if smooth:
        text += (f", smoothed by a zero-phase Hann window of {2 * smooth + 1}"
                 f" taps ({smooth} of the samples of preview): unsmoothed "
                 f"it asks for {ratio:.3g} times the input activity of the "
                 f"baseline's inverse (more than {FF_ACTIVITY:g})")
    approx, pairs = approx
    if approx:
        text += (f"; zero(s) at {_fmt_roots(np.array(approx))} kept by "
                 f"their DC gain only")
    if pairs:
        text += (f"; zero(s) at {_fmt_roots(np.array([z for z, _ in pairs]))}"
                 f" cancelled with the pole(s) beside them at "
                 f"{_fmt_roots(np.array([p for _, p in pairs]))} (their DC "
                 f"gain alone would raise the inverse's gain where the pair "
                 f"cancels)")
    if linear_note:
        text += f"; {linear_note}"
    return text
