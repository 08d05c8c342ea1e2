"""The hunting guard of `ServoController` (`servo_controller`'s
``hunting``).

A heavy load with little friction coasts into the play, and a feedback
loop whose gains suit the identified model then hunts in the holds: y
swings from one flank of the gap to the other and back (random drives 53
and 62 of ``benchmarks/bench_servo.py``: 8 and 16 reversals in a hold, 40
um RMS, for the linear design and the sandwich alike; with the gains
halved, 22 and 11 um without hunting). The record does not show it, since
its excitation keeps the load moving. The loop shows it in its own
measurements, so the controller watches them: in a hold of the reference,
from `SETTLE` time constants of the loop's crossover on, every `TURNS`
(3) reversals of y in a row by more than a deadband, each within `GAP`
half-periods of the crossover (`GAP` pi / w_c samples, over the scale
reached: lower gains slow the loop) of the last, scale the error fed to
the PID by `BETA`, down to `FLOOR`. Scaling the error, not the PID's output,
keeps the integrator's state: the input does not jump. It only lowers
the gains, and the loop is checked stable down to the floor; ``reset()``
restores them.

A loop can also hunt from a hold's very start: random drive 72's linear
design swings across its 272 um of play about once per time constant
1 / w_c, and counting from 10 time constants its guard fired only in the
hold's second half. So the reversals are also counted in an early window,
from 5 time constants (`EARLY` of the settle) to just before the settle,
where the count is dropped: the holds are then watched from the settle
on as before. Counting on from 5 time constants without the drop fired on
random drive 9's sandwich (held-out set), which does not hunt, and raised
its error near the reversals by 35 %.

A loop can also oscillate while the reference moves, where y has no
rest to reverse about: random drive 0 of the benchmark with 1.5 times the
play, whose sandwich design did not hunt in the holds before its sine
and then oscillated through the whole sine at 68 um RMS (the linear
design, whose guard had fired in the first hold, tracked at 9.8 um).
While r moves the guard counts the reversals of the error r - y instead,
by the same deadband and window, and scales the gains after every
`MOTION_TURNS` (24) of them in a row: a loop that tracks turns its error
at the reference's own changes, at most 12 times in a row on the
benchmark's drives and those of ``--mismatch`` (an offline count), and
one that oscillates turns it hundreds of times. The count restarts
wherever r turns, so that a reference that jitters, and turns the error
with it at every sample, is not taken for a loop that hunts.

Only fast reversals count. A limit cycle the gains cause, with the
play's phase lag, runs near or above the crossover: on the benchmark's
hunting drives their half-periods were 0.14 to 0.4 times the crossover's
period 2 pi / w_c. A load stuck by Coulomb friction that the integrator
breaks free hunts more slowly (random drive 59: half-periods 0.7 to 1.7
of that period), and lower gains make it worse (16.1 -> 21.2 um there
when the guard counted every reversal).

The deadband is `DEADBAND` times the noise of the record (the standard
deviation of the linear fit's residuals' increments, `noise_level`), so
that a reading flickering between encoder counts is not taken for a
limit cycle: on the drives of the benchmark it never fired where the loop
did not hunt.
"""

import math

import numpy as np

from ._servo_design import crossover, loop_radius
from ._servo_kernel import MOTION_TURNS, TURNS
from ..tools.residuals import noise_level
from .._checks import check_positive

__all__ = []

#: the deadband in multiples of the record's noise (`noise_level`)
DEADBAND = 8.0
#: reversals are counted from this many time constants 1 / w_c of the
#: loop's crossover into a hold (a step's overshoot has settled), and in an
#: early window from half of them on (`_servo_kernel.EARLY`)
SETTLE = 10.0
#: ... but from at most this many samples
SETTLE_MOST = 10000
#: reversals count in a row when each comes within GAP pi / w_c samples
#: of the one before (the half-period of an oscillation at 1 / GAP of the
#: crossover)
GAP = 1.5
#: each detection multiplies the gains by BETA, down to FLOOR
BETA = 0.6
FLOOR = 0.25


def record_noise(result):
    """The noise level of an identification result's record (the linear
    fit's residuals, `noise_level`), or None without one."""
    e = getattr(result, 'residuals', None)
    if e is not None:
        return noise_level(e)
    linear = getattr(result, 'linear', None)
    noise = linear.get('noise') if isinstance(linear, dict) else None
    return None if noise is None else float(noise)


def guard_scalars(hunting, result, num, den, C, notes):
    """The guard's scalars [deadband, settle, beta, floor, gap] for the loop
    C P, P = num / den (all 0: no guard), with a note of the choice.
    `hunting` is None (a deadband from the result's record; no guard
    without one), False (none) or the deadband in y's units."""
    if isinstance(hunting, np.bool_):
        hunting = bool(hunting)
    if hunting is False:
        notes.append("no hunting guard (hunting=False)")
        return [0.0] * 5
    if hunting is None or hunting is True:
        noise = None if result is None else record_noise(result)
        if noise is None or not noise > 0:
            if hunting is True:
                raise ValueError(
                    "hunting=True needs an identification result with its "
                    "record's residuals, for the deadband; pass the "
                    "deadband in y's units instead (hunting=0.002)")
            notes.append("no hunting guard: a model without a record has "
                         "no noise level for its deadband (pass "
                         "hunting=<deadband in y's units>)")
            return [0.0] * 5
        band, why = DEADBAND * noise, (f"{DEADBAND:g} times the record's "
                                       f"noise, {noise:.3g}")
    else:
        try:
            band = check_positive('hunting', hunting)
        except TypeError:
            raise TypeError(f"hunting must be None, True, False or a "
                            f"deadband in y's units; got {hunting!r}") \
                from None
        why = "as asked"
    wc = crossover(num, den, C)
    settle = float(min(SETTLE_MOST, math.ceil(SETTLE / wc)))
    gap = float(math.ceil(GAP * math.pi / wc))
    # the gains only drop: the loop must hold at every scale reached
    floor = 1.0
    while floor > FLOOR:
        c = max(floor * BETA, FLOOR)
        if not loop_radius(num, den, C * c) < 1:
            break
        floor = c
    if floor >= 1.0:
        notes.append("no hunting guard: the loop is unstable with its "
                     f"gains scaled by {BETA:g}")
        return [0.0] * 5
    notes.append(
        f"hunting guard: in a hold, from {settle:.0f} samples in, each "
        f"{TURNS} reversals of y in a row by more than {band:.3g} ({why}), "
        f"each within {gap:.0f} samples of the last ({GAP:g} half-periods "
        f"of the crossover; over the scale reached), and while the "
        f"reference moves each {MOTION_TURNS} such reversals of the error, "
        f"scale the feedback's gains by {BETA:g}, down to {floor:.3g} "
        f"(ctrl.feedback_gain; reset() restores them)")
    return [float(band), settle, BETA, floor, gap]
