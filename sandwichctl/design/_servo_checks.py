"""The checks of an identified sandwich's servo design around its own
model: that the band's compensation helps there (`helps_on_model`), that
the linear feedforward does not wreck the loop (`feedforward_checked`),
and that the feedback designed on the linear baseline does not either
(`feedback_checked`). Each runs the loop around the identified model
for `_servo_design.design_reference` travelling 20 of its bands (the
first also for the record's own travel). The last, on the design
returned, that its loop around the model tracks the record's travel
better than leaving the plant at rest (`bounded_checked`). And how
much input activity one linear feedforward asks for against another
(`activity_ratio`)."""

import contextlib
import contextvars
import warnings

import numpy as np
from scipy.signal import lfilter

from ._servo_design import loop_radius, tf_arrays
from ._servo_inputs import MAX_PREVIEW
from ._servo_kernel import BAND, IX_SCALAR
from .loop import servo_loop

#: the default compensation is turned off when it makes the loop around the
#: identified model this much worse (a gross failure: on the drives the
#: model predicts little of what compensation gains or loses)
HARM = 1.25
#: `servo_controller`'s keywords of the same design with its feedback
#: alone (no feedforward, hence no band compensation)
FEEDBACK_ALONE = dict(feedforward=None, band_fraction=None, smoothing=None,
                      jump_samples=None, adapt=None, max_preview=MAX_PREVIEW)
#: a loop whose RMS error around the identified model exceeds this many
#: times the reference's peak has diverged, and `bounded_checked` says it
#: runs away (random seed 51 with the integrator in L2 reached 2,100 times);
#: below that, that it tracks worse than leaving the plant at rest
DIVERGED = 10.0
#: `tracks`: a loop must keep the RMS error within `AT_REST` times the
#: reference's own, that of leaving the plant at rest (a loop that barely
#: moves the plant passes: a play wider than the record's travel leaves a
#: sound design there, random_case(1) with ten times the play); one too
#: slow for the record's reference must track it `STRETCH` times slower
#: within `SLOW_SHARE` of its RMS
AT_REST = 1.0
STRETCH = 10
SLOW_SHARE = 0.5

_INNER = contextvars.ContextVar('servo_controller_inner', default=False)


@contextlib.contextmanager
def inner():
    """Within: `servo_controller` is called by a check for another design,
    and leaves `bounded_checked` to the outer call."""
    token = _INNER.set(True)
    try:
        yield
    finally:
        _INNER.reset(token)


def outermost():
    """Whether this `servo_controller` call is not a check's (`inner`)."""
    return not _INNER.get()


def scalar_index(ctrl):
    """Where the scalars start in ctrl._p."""
    return int(ctrl._ix[IX_SCALAR])


def activity_ratio(ff, other, r):
    """The total variation of the feedforward ff = (num, den) along the
    reference r over that of `other` (inf where other's is 0): polynomials
    in z with the preview, which shifts the output but leaves its total
    variation alone."""
    def tv(num, den):
        num, den = np.atleast_1d(num), np.atleast_1d(den)
        # descending powers of z: num / den = z^(len(num) - len(den)) *
        # the causal filter num / den in z^-1, a shift
        return float(np.sum(np.abs(np.diff(lfilter(num, den, r)))))
    base = tv(*other)
    return tv(*ff) / base if base > 0 else np.inf


def loop_error(ctrl, model, r):
    """RMS error of `ctrl` around `model` for the reference r (inf if the
    loop blows up), in the model's coordinates: the design's operating
    point, the user's raw values, is set aside while it runs."""
    keep = ctrl._design['operating_point']
    ctrl._design['operating_point'] = (0.0, 0.0)    # servo_loop resets
    try:
        with np.errstate(all='ignore'), warnings.catch_warnings():
            warnings.simplefilter('ignore')
            y = servo_loop(model, r, ctrl)[0]
    finally:
        ctrl._design['operating_point'] = keep
        ctrl.reset()
    err = float(np.sqrt(np.mean((r - y) ** 2)))
    return err if np.isfinite(err) else np.inf


def helps_on_model(ctrl, model, refs):
    """Whether the band offset does not make the RMS error of the loop
    around the identified model `HARM` times worse, for each reference of
    `refs` (None skipped)."""
    for r in (r for r in refs if r is not None):
        errors = []
        for scale in (1.0, 0.0):
            trial = type(ctrl)(ctrl._design)
            sc = scalar_index(trial)
            trial._p[sc + BAND.start:sc + BAND.stop] *= scale
            errors.append(loop_error(trial, model, r))
        if not errors[0] <= HARM * errors[1]:
            return False
    return True


def feedforward_checked(ctrl, design, model, ff_model, r):
    """`ctrl`, unless its linear feedforward makes the loop around the
    identified model `HARM` times worse than feedback alone for the
    reference r: then the design that inverts the other linear model, or
    failing that the one without feedforward, with a note (a baseline
    that fits far worse than the sandwich can ask for inputs hundreds of
    times too large). `design(**kw)` is the same design with the keywords
    kw changed; `ff_model` whether ctrl's feedforward inverts the
    sandwich's mbar L1 L2 (else the baseline)."""
    bare = design(**FEEDBACK_ALONE)
    e, e_bare = loop_error(ctrl, model, r), loop_error(bare, model, r)
    if e <= HARM * e_bare:
        return ctrl
    which = "sandwich's mbar L1 L2" if ff_model else "baseline"
    other = design(feedforward_from='baseline' if ff_model else 'model')
    pick = other if loop_error(other, model, r) <= HARM * e_bare else bare
    pick.notes.append(
        f"the feedforward inverting the {which} made tracking on the "
        f"identified model {e / e_bare:.3g} times worse than feedback alone: "
        + ("the other linear model is inverted" if pick is other else
           "no feedforward") + " (pass feedforward_from to force it)")
    return pick


def feedback_checked(ctrl, design, model, own, r):
    """None where `ctrl`'s feedback, designed on the result's linear
    baseline, stands; else the design with the feedback designed on the
    sandwich's own mbar L1 L2 (`own`), with a note: where the baseline's
    feedback leaves the loop around `own` unstable and, without
    feedforward, makes the loop around the identified sandwich `HARM`
    times worse than the feedback designed on `own` does, for the
    reference r (`design(**kw)` is the same design with the keywords kw
    changed). The baseline carries the play's effect on the loop, and is
    the better plant on the benchmark's drives: random drive 7's baseline
    PID leaves its mbar L1 L2 unstable (radius 1.013) and tracks the
    drive at 12.2 um, against 20.9 designed on mbar L1 L2, and better
    around the sandwich too. Where the play distorts the baseline far more
    (a random plant whose baseline fits 61 % against the sandwich's 90 %),
    its loop diverges around the sandwich and on the plant."""
    radius = loop_radius(*tf_arrays(own), ctrl.pid)
    if not radius >= 1:
        return None
    e = loop_error(design(**FEEDBACK_ALONE), model, r)
    e_own = loop_error(design(feedback_from='model', **FEEDBACK_ALONE),
                       model, r)
    if e <= HARM * e_own:
        return None
    other = design(feedback_from='model')
    other.notes.append(
        f"the feedback designed on the result's linear baseline left the "
        f"loop around the sandwich's mbar L1 L2 unstable (pole radius "
        f"{radius:.4g}) and, feedback alone, tracking on the identified "
        f"model {e / e_own:.3g} times worse than the feedback designed on "
        f"mbar L1 L2, so the feedback is designed on that (pass "
        f"feedback_from='baseline' to force the baseline)")
    return other


def bounded_checked(ctrl, design, model, r, moves, given):
    """`ctrl`, where its loop around the identified model tracks the
    reference r at all (`tracks`); else the first design of `moves`
    (keywords for `design`, the same design with them changed) that does,
    with a note. None does: raise, with the reason and the keywords
    `given` (a dict) the user set. A PID with the margins asked on the
    model's linear part can still run away around the sandwich: the
    backlash's lag and lower gain act as a gain reduction, and a loop
    around poles near z = 1 after the play can be only conditionally
    stable; a feedforward inverting a poor baseline can ask for inputs
    hundreds of times too large. And a loop that tracks its own model
    worse than no control does no better on the plant: on
    `bench_servo_random.py`'s plants, seeds 0-49, every such default
    design tracked its true plant worse than at rest too, or diverged
    there (seed 35 with the integrator in L2: its mbar L1 L2 has the
    plant's low-frequency sign reversed)."""
    slow = np.interp(np.arange(STRETCH * r.size) / STRETCH,
                     np.arange(r.size), r)
    ok, e, e_slow = tracks(ctrl, model, r, slow)
    if ok:
        return ctrl
    peak, rest = float(np.max(np.abs(r))), _rms(r)
    why = (f"the loop around the identified model runs away for the "
           f"record's travel (RMS error {e / peak:.3g} times the "
           f"reference's peak)" if e > DIVERGED * peak else
           f"the loop around the identified model tracks the record's "
           f"travel worse than leaving the plant at rest (RMS error "
           f"{e / rest:.3g} times the reference's RMS; {STRETCH} times "
           f"slower, {e_slow / _rms(slow):.3g} times, above "
           f"{SLOW_SHARE:g})")
    for kw in moves:
        try:
            other = design(**kw)
        except ValueError:
            continue
        if tracks(other, model, r, slow)[0]:
            other.notes.append(f"{why} with the feedback chosen first; "
                               f"designed with {_words(kw)} instead")
            return other
    tried = f"; nor with {' or '.join(map(_words, moves))}" if moves else ""
    asked = f" with {_words(given)} as asked" if given else ""
    raise ValueError(
        f"servo_controller: {why}{asked}{tried}. Check the model (its "
        f"poles near z = 1, the sign of its gain at low frequencies) and "
        f"re-identify (other orders, integrators=, integrator_block=), or "
        f"ask for another design (modulus_margin=, feedback_from=, "
        f"feedforward_from=)")


def tracks(ctrl, model, r, slow):
    """(Whether the loop of `ctrl` around `model` tracks r, its RMS error
    for r, that for `slow` or None where not run): an RMS error at most
    `AT_REST` times r's own, that of leaving the plant at rest; or, for a
    loop too slow for r, at most `SLOW_SHARE` of it for `slow`, r
    `STRETCH` times slower (a loop that merely lags a fast reference
    tracks a slow one closely; on the random plants the loops that
    tracked their model worse than at rest tracked a 10 times slower
    reference no better than 0.6 times its RMS, most of them far
    worse)."""
    e = loop_error(ctrl, model, r)
    if e <= AT_REST * _rms(r):
        return True, e, None
    e_slow = loop_error(ctrl, model, slow)
    return e_slow <= SLOW_SHARE * _rms(slow), e, e_slow


def set_keywords(asked, defaults):
    """The keywords of `asked` whose values differ from `defaults` (a
    value equal to its default, as 1 for 1.0 or an array for a tuple, is
    not one the user changed)."""
    def same(value, default):
        try:
            return bool(np.array_equal(value, default))
        except (TypeError, ValueError):
            return False
    return {k: v for k, v in asked.items() if not same(v, defaults[k])}


def _words(kw):
    """Keywords as a call spells them."""
    return ", ".join(f"{k}={v!r}" for k, v in kw.items())


def _rms(x):
    """RMS of x as `loop_error` takes it (not `loop._rms`, scaled by the
    peak): a loop that leaves the plant at rest has an error equal to the
    reference's RMS to the last bit, and `AT_REST` = 1 keeps it."""
    return float(np.sqrt(np.mean(np.square(x))))

