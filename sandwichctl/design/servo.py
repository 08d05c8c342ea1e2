r"""A servo controller designed from a model, that runs against any plant.

`servo_controller` turns an identified (or known) model into a
`ServoController`: a PID feedback designed for the model's linear part,
and a feedforward that inverts the model along the reference, using a few
samples of reference preview. For a `SandwichSystem` the feedforward also
runs the reference through a backlash inverse, so the drive crosses the
play *when the reference reverses*, before an error has built up. The
controller steps one sample at a time (``u = ctrl.step(r_ahead, y)``), so
it runs against a simulation, a hardware-in-the-loop rig or the
physically simulated drive of ``sandwichctl.data.ServoDrive``.

Which linear model
------------------
A known model (a `SandwichSystem` given directly) is inverted exactly:
:math:`L_1^{-1} B^{-1} L_2^{-1}` along the reference, over the share of
the band that ``band_fraction`` asks (0.25 by default, as for a model
from data: pass 1.0 where the model is the plant, as in a simulation
study), and the PID is designed on :math:`\bar m L_1 L_2`. For an
identification result, the PID is designed on its linear baseline fit
(the loop in the holds is then the linear design's), and the feedforward
inverts the sandwich's own :math:`\bar m L_1 L_2` when it is the clearly
better model (see ``feedforward_from``), else the baseline. When L2
integrates (a valve's play before a cylinder) both are designed on
:math:`\bar m L_1 L_2`: no linear model follows the drift the play puts
through an integrator after it, and the baseline spends a slow pole and
zero on it (see ``feedback_from``); so they are when the baseline's
low-frequency gain has the sign opposite to the sandwich's (such a pair
flipped it). The band offset of the inverse reaches the plant through
the DC gains of L1 and L2 (their fitted fast dynamics, inverted, would
turn the offset's jump into ringing).

Why the backlash inverse sits in the feedforward
------------------------------------------------
Inside the feedback loop, an inverse built from an identified band jumps
across the band whenever a small correction changes sign. On an axis
whose load coasts into the gap, the play the loop sees is smaller than
the identified band, so every jump overshoots and the loop hunts in the
holds (measured on the simulated drive: 13-14 reversals per hold with
95 % of the band compensated). Driven by the reference, the inverse jumps
only where the reference reverses: the holds see exactly the linear loop,
which cannot hunt more than the linear design, and the reversals are
crossed ahead of time. Only a share of the band (``band_fraction``) is
compensated, since the seen play is smaller than the band, and the jump
is spread over ``jump_samples`` samples, started half of them early, so
that :math:`L_1^{-1}` (a differentiator when L1 integrates) does not turn
it into a one-sample spike that saturates the drive.

How much of the band: online
----------------------------
The play the loop meets is not the band identified. For an identified
sandwich the controller estimates the band path's gain from its own error,
by recursive least squares: the regressor is the band path's output
through the design plant's process sensitivity :math:`P/(1+CP)`, the
error's sensitivity to that gain; the share of the other linear model's
feedforward (the baseline's or the sandwich's) is estimated with it. Both
are deterministic and bounded; ``reset()`` restarts them (``adapt``).

Hunting: online
---------------
A heavy load with little friction coasts into the play, and a loop whose
gains suit the identified model can then hunt in the holds, although
the record (whose excitation keeps the load moving) showed nothing. The
controller counts the reversals of y in each hold of the reference; every
three in quick succession (as fast as the loop's crossover: a load that
friction holds and the integrator breaks free hunts more slowly, and lower
gains would make that worse) by more than a deadband scale the error fed
to the PID, and so its gains, by 0.6, down to 0.25 (``hunting``,
``ctrl.feedback_gain``; the loop is checked stable down there); while the
reference moves, every 24 such reversals of the error r - y do. Scaling
the error keeps the PID's states, so u does not jump.
"""

import inspect
import math
import warnings

import numpy as np
import control as ct

from . import _servo_design as sd
from . import _servo_data as sdata
from . import _servo_band as sb
from . import _servo_linear as sl
from ._servo_checks import (HARM, activity_ratio, bounded_checked,
                            feedback_checked, feedforward_checked,
                            helps_on_model, inner, outermost, scalar_index,
                            set_keywords)
from ._servo_guard import guard_scalars
from ._servo_inputs import (MAX_PREVIEW, DESIGN_KEYS, check_options,
                            check_plant_tf, unwrap_model, warn_result,
                            python_step, check_inputs, check_input_arrays,
                            overflow, check_level)
from ._servo_kernel import (pack, servo_step_kept, servo_run, adapt_index,
                            rest_scalars, BAND, GUARD, INVERSE,
                            NSCALAR, IX_ADAPT, IX_BLEND, IX_GUARD, IX_SCALAR)
from .loop import ss_arrays
from ..model.sandwich import SandwichSystem
from .._checks import (MAX_ORDER, PLAIN_REALS, IdentificationWarning,
                       check_int, check_nonnegative, named_copy,
                       check_positive, check_real, check_signal)

__all__ = ['ServoController', 'servo_controller']

#: default share of the identified band the feedforward compensates, and
#: the share when L1 integrates (a speed command in): chosen on the tuning
#: drives of ``benchmarks/bench_servo.py`` (seeds 0-1, random drives 0-7)
#: and checked on held-out ones; larger shares over-compensate there
BAND_FRACTION = 0.25
BAND_FRACTION_INTEGRATING = 0.1
#: the share when the feedforward inverts the sandwich's own linear part:
#: half the band did a little better on the tuning drives, but on a fresh
#: drive whose load coasts far into the gap (random drive 26) it made the
#: loop 1.20 times the linear design's error, a quarter 1.02
BAND_FRACTION_MODEL = 0.25
#: default smoothing width of the inverse, as a share of the band (in v)
SMOOTHING = 0.02


def _ss(num, den, dt):
    """(A, B, C, D) arrays of num/den (descending powers of z)."""
    return ss_arrays(ct.tf(num, den, dt))


class ServoController(ct.NonlinearIOSystem):
    r"""A discrete servo controller: ``u(k) = ctrl.step(r_ahead, y)``.

    Built by `servo_controller`. The control law is

    .. math::

        u(k) = u_0 + C(z)\,[r(k) - y(k)] + u_{ff}(k),

    with C a PID and :math:`u_{ff}` the model inverse along the reference
    (see the module notes); r(k + preview) is passed in as ``r_ahead``, so
    that the feedforward can lead. Signals are in the model's data
    coordinates; with an operating point (u0, y0), in raw sensor units.

    It is also a python-control discrete system with inputs
    ``['r_ahead', 'y']`` and output ``['u']``, so ``ct.interconnect`` and
    ``ct.input_output_response`` use it; its state vector is the
    controller's memory, the same one `step` updates (the `step` method
    keeps its own copy, reset by ``reset``). It pickles with its names and
    its memory.

    Attributes
    ----------
    model : SandwichSystem or control.TransferFunction
        The model it was designed from.
    preview : int
        Samples of reference preview: r_ahead(k) = r(k + preview).
    pid : control.TransferFunction
        C(z), from the error r - y to u.
    kp, ki, kd, derivative_pole : float
        :math:`C(z) = k_p + k_i z/(z-1) + k_d (1-p)(z-1)/(z-p)`.
    design_plant : control.TransferFunction
        The linear plant the feedback is designed and checked for (the
        model, or :math:`\bar m L_1 L_2` for a sandwich).
    crossover_limit : float
        The loop gain is below 1 above this many plant bandwidths.
    margins : dict
        'modulus' (:math:`\min |1 + CP|` on a log grid below the slowest pole),
        'gain', 'phase' (deg) and 'pole_radius' of the designed loop on
        the design plant; 'modulus_measured', the modulus margin with P
        the plant's response as an identification result's data measured
        it where they have it (NaN for a model without data): the margin
        the design holds.
    measured_response : tuple of ndarray or None
        (w, P) of that response, w in rad/sample (`plot_loop` draws
        the loop on it); None for a model without data.
    band_fraction, smoothing, jump_samples : float, float, int
        The compensation: the share of the model's band inverted, the
        inverse's smoothing width (in the model's v) and the samples the
        band jump is spread over (0 for a linear model).
    compensates : bool
        Whether a backlash inverse runs in the feedforward.
    hunting : dict or None
        The hunting guard: 'deadband' (in y), 'settle' (samples into a
        hold before reversals count; from half of it they count in an
        early window, dropped at the settle), 'gap' (most samples between
        reversals counted in a row; in a move, of the error), 'beta' and
        'floor' (each detection's factor on the gains, and their least);
        None without it.
    notes : list of str
        Why each choice was made, as `repr` prints them.
    operating_point : tuple
        (u0, y0).
    """

    def __init__(self, design, name=None):
        if not (isinstance(design, dict) and DESIGN_KEYS <= set(design)):
            raise TypeError(f"a ServoController is built by sw.servo_"
                            f"controller(model, ...); got {design!r:.60}")
        self._design = design
        self.__dict__.update({k: v for k, v in design.items()
                              if not k.startswith('_')})
        p, ix, nstate = pack(*(design[k] for k in (
            '_fb', '_pre', '_post', '_linear', '_ps', '_other', '_scalars',
            'preview', '_lead', 'compensates', 'adapts', 'blends')),
            design.get('_delays', (0, 0)))
        self._p, self._ix = p, ix
        self._s = np.zeros(nstate)
        self._keep = np.zeros(nstate)       # the memory before a step
        super().__init__(self._update, self._output,
                         inputs=['r_ahead', 'y'], outputs=['u'],
                         states=nstate, dt=design['dt'], name=name)
        self._built = True

    # --- the per-sample interface -------------------------------------
    def reset(self, *, y=None, u=None):
        """Back to rest: every internal state zero.

        Parameters
        ----------
        y, u : float, optional (keywords)
            For a bumpless start on a running axis: the measured y and
            the u being applied now become the operating point, so that
            the controller starts at u with the reference taken as y.
            Without them the operating point given at design is restored
            (and one not given is the design's). Both are checked before
            anything changes: a bad value raises with the controller as
            it was.
        """
        u0, y0 = self._design['operating_point']
        if y is not None:
            y0 = check_level('y', y)
        if u is not None:
            u0 = check_level('u', u)
        self._s[:] = 0.0
        sc = self._ix[IX_SCALAR]
        self._p[sc + NSCALAR - 2:sc + NSCALAR] = u0, y0
        self.__dict__['operating_point'] = (float(u0), float(y0))

    def step(self, r_ahead, y):
        """One sample: the reference `preview` samples ahead and the y(k)
        just measured in; u(k) out. A value not finite or above 1e100 in
        magnitude raises before the memory is touched, so one bad reading
        does not poison every later sample."""
        # a float or an int goes straight on (about 1 us a step); an int
        # too large for a float takes check_real's way to its error
        try:
            r = (float(r_ahead) if type(r_ahead) in PLAIN_REALS else
                 check_real('r_ahead', r_ahead))
            yk = float(y) if type(y) in PLAIN_REALS else check_real('y', y)
        except OverflowError:
            r, yk = check_real('r_ahead', r_ahead), check_real('y', y)
        check_inputs(r, yk, " (the controller's memory is unchanged)")
        u = servo_step_kept(self._p, self._ix, self._s, self._keep, r, yk)
        if not math.isfinite(u):
            self._s[:] = self._keep
            overflow(None)
        return u

    def run(self, r_ahead, y):
        """`step` over given sequences from the current memory (open loop:
        y is recorded, not simulated); returns u."""
        r_ahead = check_signal('r_ahead', r_ahead)
        y = check_signal('y', y, r_ahead.size, of='r_ahead')
        check_input_arrays(r_ahead, y)
        keep = self._s.copy()
        u = servo_run(self._p, self._ix, self._s, r_ahead, y)
        bad = np.flatnonzero(~np.isfinite(u))
        if bad.size:
            self._s[:] = keep
            overflow(int(bad[0]))
        return u

    @property
    def state(self):
        """A copy of the memory `step` updates."""
        return self._s.copy()

    @property
    def band_gain(self):
        """The gain g on the band path now (1 at rest; moved online when
        `adapts`): the share of the band compensated is
        ``band_fraction * band_gain``."""
        return (1.0 + float(self._s[adapt_index(self._ix)[0]])
                if self.adapts else 1.0)

    @property
    def feedback_gain(self):
        """The hunting guard's scale c on the feedback's gains now (1 at
        rest and without the guard; see `hunting`)."""
        return 1.0 + float(self._s[int(self._ix[IX_GUARD])])

    @property
    def feedforward_blend(self):
        """The share b of the other linear feedforward now (0 at rest;
        moved online when `blends`): u_lin = (1 - b) F + b F_other, with F
        the one `feedforward_from` chose."""
        return (float(self._s[adapt_index(self._ix)[1]]) if self.blends
                else 0.0)

    # --- python-control system ----------------------------------------
    def _update(self, t, x, u, params=None):
        return python_step(self._p, self._ix, self.nstates, t, x, u)[0]

    def _output(self, t, x, u, params=None):
        return np.array([python_step(self._p, self._ix, self.nstates, t,
                                     x, u)[1]])

    def __setattr__(self, name, value):
        if self.__dict__.get('_built') and name in self._design:
            raise AttributeError(f"ServoController.{name} is read-only (the "
                                 f"compiled controller would not see it): "
                                 f"design again with sw.servo_controller")
        super().__setattr__(name, value)

    def __delattr__(self, name):
        if self.__dict__.get('_built') and name in self._design:
            raise AttributeError(f"ServoController.{name} is read-only")
        super().__delattr__(name)

    copy = named_copy            # its name checked

    def __reduce__(self):
        return (_rebuild, (self._design, self.name, self._s.copy(),
                           self.operating_point,
                           (self.input_labels, self.output_labels)))

    def __repr__(self):
        m = self.margins
        kind = 'sandwich' if self.compensates else 'linear'
        dt = self.dt if self.dt is True else f"{self.dt:g}"
        head = (f"ServoController({kind}, dt={dt}, preview={self.preview}, "
                f"kp={self.kp:.4g}, ki={self.ki:.4g}, kd={self.kd:.4g}, "
                f"modulus_margin={m['modulus']:.3f}, "
                f"gain_margin={m['gain']:.3g}, phase_margin="
                f"{m['phase']:.3g}, pole_radius={m['pole_radius']:.4f}")
        if self.compensates:
            head += (f", band_fraction={self.band_fraction:g}, "
                     f"smoothing={self.smoothing:.3g}, "
                     f"jump_samples={self.jump_samples}, "
                     f"adapts={self.adapts}")
        return head + ")\n" + "\n".join(f"  - {n}" for n in self.notes)

    __str__ = __repr__


def _rebuild(design, name, state, operating_point, labels=None):
    ctrl = ServoController(design, name=name)
    ctrl.reset(y=operating_point[1], u=operating_point[0])
    ctrl._s[:] = state
    if labels is not None:
        ctrl.set_inputs(list(labels[0]))
        ctrl.set_outputs(list(labels[1]))
    return ctrl


def servo_controller(model, *, modulus_margin=0.6, feedforward='preview',
                     max_preview=MAX_PREVIEW, band_fraction=None,
                     smoothing=None, jump_samples=None, feedback_scale=1.0,
                     crossover_limit=None, feedforward_from='auto',
                     feedback_from='auto',
                     adapt=None, hunting=None,
                     operating_point=(0.0, 0.0), name=None):
    r"""Design a servo controller from an identified or known model.

    The feedback is a PID on the model's linear part (a `SandwichSystem`'s
    :math:`\bar m L_1 L_2`), with the largest integral gain that keeps the
    modulus margin and a complementary sensitivity :math:`|T| \le 1` on a
    log grid from below the slowest pole, denser for long delays and sharp
    resonances (an integrating plant gets a PD: the module notes). Where a
    result's residuals vouch for the model past eight plant bandwidths
    (little play), the PID's gains are raised together as far as the
    margin allows, crossing over below where they vouch (``ctrl.notes``).
    The poles are checked: an unstable design is never returned. The
    feedforward inverts the model along the reference with ``preview``
    samples of preview; for a sandwich it holds the backlash inverse.

    Parameters
    ----------
    model : SandwichSystem, control.TransferFunction or result
        The model: a sandwich (the design compensates its play), a
        discrete SISO transfer function (the linear design), or the
        result of ``sw.identify`` / ``sw.identify_linear``.
    modulus_margin : float, optional
        Required :math:`\min_\omega |1 + C P|`, in (0, 1) (default 0.6: a
        sensitivity peak of 1.67, gain margin >= 2.5, phase margin >= 35
        deg). From an identification result, P is read where the data
        measured it, the model where not (``ctrl.margins``).
    feedforward : {'preview', 'zpetc', None}, optional
        How zeros on or outside the unit circle are inverted: an
        anticausal series using reference preview (default), Tomizuka's
        ZPETC, or no feedforward at all (feedback only, no compensation).
    max_preview : int, optional
        Most samples of preview one unstable zero may use (default 20).
    band_fraction : float, optional
        Share of the model's band that the feedforward's backlash inverse
        compensates, in [0, 1]. By default 0.25, and 0.1 when L1
        integrates: the play a loop sees is smaller than the mechanical
        gap, since the load coasts into it, and larger shares
        over-compensated on drives of ``benchmarks/bench_servo.py``. A
        default compensation that makes the loop around the identified
        model itself 1.25 times worse is turned off, and the notes say
        so. Where the model is the plant (a known model in a simulation
        study), 1.0 compensates the whole band.
    smoothing : float, optional
        Smoothing width of the inverse in the model's v (default 2 % of
        the compensated band).
    jump_samples : int, optional
        Samples the band jump is spread over, started half of them early
        (default: the fewest for which :math:`L_1^{-1}` keeps the jump's
        input within twice what holds the far side; with an integrating
        L1, which turns the jump into a speed pulse, at least two time
        constants :math:`1/\omega_c` of the loop's crossover, so that a
        load that coasts is not kicked past the reference).
    feedforward_from : {'auto', 'model', 'baseline'}, optional
        What the feedforward inverts, for an identification result of a
        sandwich: the sandwich's :math:`\bar m L_1 L_2` ('model'), the
        baseline, or by default the sandwich's when L2 integrates (see
        `feedback_from`), or when L1 does not integrate,
        L1 L2 has no zero outside the unit circle that its inverse could
        not follow (sampling zeros with a real part below -0.5, and zeros
        far enough out for their anticausal series to fit in
        `max_preview` samples, aside) and the sandwich fits at least 2 points
        better than the baseline (the play then distorts the baseline's
        dynamics). With 'auto', a feedforward that makes the loop around
        the identified model 1.25 times worse than feedback alone gives
        way to the other linear model's, or to none (the notes say so).
    feedback_from : {'auto', 'model', 'baseline'}, optional
        What the feedback is designed on, for an identification result of
        a sandwich: its linear baseline, which carries the play's effect
        on the loop (by default), or the sandwich's :math:`\bar m L_1 L_2`
        ('model', and by default when L2 integrates: a linear model
        cannot follow the drift that play puts through an integrator
        after it, and its baseline then has a crossover far too slow or
        the wrong sign; and when the baseline's low-frequency gain has the
        sign opposite to the sandwich's, or its fit stopped with a free
        pole pinned at the stability boundary (with a zero beside it the
        pair is a drift term, cancelled first); the feedforward then
        inverts the sandwich's too, unless `feedforward_from` is
        'baseline'; and when the baseline's feedback leaves the loop around
        :math:`\bar m L_1 L_2` unstable and, feedback alone, tracks the
        identified sandwich 1.25 times worse than one designed on it).
    adapt : bool, optional
        Whether the band's gain g (the share compensated is
        ``band_fraction * g``, g = 1 at rest) is estimated online from the
        loop's own error, by recursive least squares on the regressor
        :math:`PS\,u_{band}` (the error's sensitivity to g through the
        design plant's process sensitivity), with a memory of 2,000
        samples, a prior worth ten band jumps, and g in [0, 3] (the share
        at most 1); ``ctrl.band_gain`` reads it and ``reset()`` restarts
        it. By default it runs for an identification result of a sandwich
        with the default share; True asks for it with a share given by
        hand, False turns it off. It reads only r and the measured y, so a
        load that coasts into the gap (the play seen smaller than the
        band) and a play larger than identified both move it the right
        way. With ``feedforward_from='auto'`` and both linear models
        invertible, the share b of the feedforward not chosen (the
        baseline's or the sandwich's, ``ctrl.feedforward_blend``, 0 at
        rest) is estimated with g; its prior is worth one
        `servo_reference` run travelling five of the model's bands.
    hunting : None, bool or float, optional
        The hunting guard: in a hold of the reference, every 3 reversals
        of y in a row by more than a deadband, each within 1.5 half-periods
        of the loop's crossover of the last, and while the reference
        moves one way every 24 such reversals of the error r - y, scale
        the feedback's gains by 0.6, down to 0.25 (a heavy load that
        coasts into the play makes a loop hunt that the record did not
        show; see the notes of ``sandwichctl.design._servo_guard``).
        ``ctrl.feedback_gain`` reads the scale, ``reset()`` restores 1.
        By default (None) it runs for an identification result, with a
        deadband of 8 times its record's noise (``noise_level`` of
        ``sandwichctl.tools.residuals``); True asks for it (an error
        without a record), False turns it off, and a number is the
        deadband in y's units.
    feedback_scale : float, optional
        Factor on the designed PID gains (default 1), for detuning or
        sweeps; the scaled loop is checked like the designed one.
    crossover_limit : float, optional
        The loop gain must be below 1 above this many plant bandwidths
        (the plant's -3 dB frequency), in [0.1, 1000]. By default 3 for
        a PID and 1 for the PD of an integrating plant; for a PID from
        an identification result, up to 8 where the residuals of its data
        put the model's relative error below 0.5 in every band up to there
        (`error_bands` of ``sandwichctl.tools.residuals``; much play keeps
        it at 3), and up to 32 for a PID then raised. Given, it holds.
    operating_point : (float, float), optional
        (u0, y0): raw units of u and y at the model's zero (for a result
        identified with offsets, its ``res.offsets``).
    name : str, optional
        System name.

    Returns
    -------
    ServoController

    Raises
    ------
    ValueError
        If the model is unstable (more than one integrator, or a pole
        outside the unit circle), has no delay, has a zero at z = 1, or
        no PID meets the margin with a stable loop; or, for an
        identification result, if its loop around its model tracks the
        record's travel worse than leaving the plant at rest (an RMS
        error above the reference's, and above half of it 10 times
        slower) with the keywords given, and with the feedback on the
        other linear model where it was left to choose (notes say so).

    Warns
    -----
    IdentificationWarning
        If the model is an identification result that is not a success,
        or one identified about offsets with no operating point given.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> ctrl = sw.servo_controller(plant)
    >>> ctrl.preview, ctrl.compensates, ctrl.margins['pole_radius'] < 1
    (2, True, True)
    >>> r = np.r_[np.zeros(20), np.ones(80)]
    >>> resp = sw.closed_loop_response(plant, r, ctrl)
    >>> bool(abs(resp.outputs[0][-1] - 1) < 1e-3)
    True
    """
    asked = {k: v for k, v in locals().items() if k != 'model'}
    source = model
    model, result = unwrap_model(model)
    band_by_default = band_fraction is None
    mm, adapt, crossover_limit, max_preview, name, (u0, y0) = \
        check_options(modulus_margin, feedforward, feedforward_from,
                      feedback_from, adapt, crossover_limit, max_preview,
                      name, operating_point)
    failed = warn_result(result, (u0, y0))
    bands, relative, baseline = sdata.result_errors(result)
    response = sdata.measured_response(baseline, relative)

    def limit(num, den):
        return (sdata.crossover_limit(bands, num, den) if crossover_limit
                is None else (crossover_limit, 'as asked'))

    def measured(num, den):         # a limit asked for holds a raised PID
        data = sdata.data_plant(response, bands, num, den)
        return data if crossover_limit is None or not data else data[:2] + (0,)
    notes, info = [], {}
    model = sl.cancel_drift(model, notes)
    if isinstance(model, SandwichSystem):
        co = model.coefficients
        mbar = 0.5 * (co['m1'] + co['m2'])
        L1n, L1d = sd.tf_arrays(model.L1)
        lin_model = (result.linear.get('model') if result is not None
                     and isinstance(getattr(result, 'linear', None), dict)
                     else None)
        lin_model = sl.cancel_drift(lin_model, notes)
        integrating = sl.integrates(model.L1)
        ff_zeros = np.concatenate([model.L1.zeros(), model.L2.zeros()])
        P, pid, ff_model, linear_note, lin_model = sl.tamed_part(
            model, result, lin_model, feedback_from, feedforward_from,
            integrating, ff_zeros, max_preview, mm, check_plant_tf,
            lambda n, d: limit(n, d)[0], measured, response=response,
            notes=notes, info=info)
    else:
        sl.only_itself(feedforward_from=feedforward_from,
                       feedback_from=feedback_from)
        linear_note, (P, pid) = None, sl.tamed_model(
            model, response, mm, check_plant_tf, lambda n, d: limit(n, d)[0],
            measured, notes=notes, info=info)
    num, den = check_plant_tf('model' if P is model else 'the design plant',
                              P)
    dt = P.dt
    # the baseline's gains were designed when it was checked
    lim, lim_why = limit(num, den)
    data = measured(num, den)
    kp, ki, kd, pole = pid if pid is not None else sd.design_pid(
        num, den, dt, mm, lim, data, info)
    scale = check_positive('feedback_scale', feedback_scale)
    kp, ki, kd = scale * kp, scale * ki, scale * kd
    C = sd.pid_tf(kp, ki, kd, pole, dt)
    with np.errstate(over='ignore', invalid='ignore', divide='ignore'):
        # a feedback_scale of 1e300 overflows |CP|: refused just below
        mmod, gm, pm, radius = sd.loop_margins(num, den, C)
    if not radius < 1:
        raise ValueError(f"feedback_scale={scale:g} gives an unstable loop "
                         f"(pole radius {radius:.4g}); use a feedback_scale "
                         + ("smaller" if scale > 1 else "closer to 1")
                         + " (1 is the designed loop)")
    mmeas = (np.nan if data is None else
             sdata.measured_modulus(data, num, den, C))
    where = sdata.margin_words(data, response, mmeas, mmod, num, den)
    notes.append(f"{'PD' if ki == 0 else 'PID'} with the largest "
                 f"{'proportional' if ki == 0 else 'integral'} gain at "
                 f"modulus margin {mm:g}"
                 f"{'' if ki == 0 else f' and |T| <= {sd.T_PEAK:g}'}"
                 f"{where}, crossover below {lim:.3g} plant bandwidths: "
                 f"{lim_why}{sdata.raised_words(num, den, C, info)}")
    lim = info.get('limit', lim)
    design = dict(model=model, dt=dt, kp=float(kp), ki=float(ki),
                  kd=float(kd), derivative_pole=float(pole),
                  pid=ct.tf(C.num[0][0], C.den[0][0], dt,
                                 inputs='e', outputs='u_fb'),
                  design_plant=P, crossover_limit=float(lim),
                  measured_response=sdata.measured_arrays(data, den),
                  margins=dict(modulus=mmod, modulus_measured=mmeas, gain=gm,
                               phase=pm, pole_radius=radius),
                  operating_point=(u0, y0), feedforward_kind=feedforward,
                  _fb=_ss(C.num[0][0], C.den[0][0], dt))
    zero = _ss([0.0], [1.0], dt)
    comp = isinstance(model, SandwichSystem) and feedforward is not None
    unused = [k for k, v in (('band_fraction', band_fraction),
                             ('smoothing', smoothing),
                             ('jump_samples', jump_samples),
                             ('adapt', adapt or None)) if v is not None]
    if unused and not comp:
        raise ValueError(
            f"{', '.join(unused)} set the backlash compensation, and "
            + ("a linear model has none" if feedforward is not None else
               "feedforward=None turns it off") + ": leave them out")
    pre = post = ps = other = zero
    lead, jump, band_fraction_out, smoothing_out = 0, 0, 0.0, 0.0
    delays = [0, 0]     # samples r_ahead waits for the lin and other blocks
    adapts, other_inv, blends, smooth, ratio = False, None, False, 0, None
    scal = rest_scalars(u0, y0)
    if feedforward is None:
        preview, lin_ff = 0, zero
        notes.append("no feedforward: feedback only")
    else:
        if comp:
            Pm = sd.tf_arrays(mbar * model.L1 * model.L2)
        fn, fd, preview, approx = sd.preview_inverse(
            *(Pm if comp and ff_model else (num, den)), feedforward,
            max_preview)
        if comp and ff_model and result is not None and \
                isinstance(lin_model, ct.TransferFunction):
            # the chatter bound: against the baseline's inverse
            ratio = activity_ratio(
                (fn, fd), sd.preview_inverse(*sd.tf_arrays(lin_model),
                                             feedforward, max_preview)[:2],
                sd.design_reference(model, 20, dt))
            smooth = sd.FF_SMOOTH if ratio > sd.FF_ACTIVITY else 0
            fn, fd, preview = sd.smoothed(fn, fd, preview, smooth)
        notes.append(sl.ff_note(feedforward, preview, approx, linear_note,
                              smooth, ratio))
        if (comp and result is not None and adapt is not False
                and band_by_default and feedforward_from == 'auto'
                and isinstance(lin_model, ct.TransferFunction)
                and not integrating
                and not sl.outside(ff_zeros, max_preview).any()):
            # the other feedforward, blended in online (see sd.blend)
            other_inv = sd.smoothed(*sd.preview_inverse(
                *((num, den) if ff_model else Pm), feedforward,
                max_preview)[:3], smooth)
    if comp:
        # a model without data (known, or built by hand) is inverted
        # exactly along the reference; an identified one gets the band
        # offset through the DC gains (see sb.static_inverse)
        exact = result is None
        L2n, L2d = sd.tf_arrays(model.L2)
        if exact:
            sb.crossing_note(model, notes)
            n2, d2, p2, _ = sd.preview_inverse(L2n, L2d, feedforward,
                                               max_preview)
            n1, d1, p1, _ = sd.preview_inverse(L1n, L1d, feedforward,
                                               max_preview)
            preview, fn, fd = 0, np.zeros(1), np.ones(1)
        else:
            # the band offset smoothed as the linear feedforward is
            n2, d2, p2 = sd.smoothed(*sb.static_inverse(L2n, L2d), smooth)
            if np.any(np.abs(model.L1.zeros()) >= 1):
                # a non-minimum-phase L1 first moves the wrong way: its DC
                # gain alone would send the offset astray
                n1, d1, p1, _ = sd.preview_inverse(L1n, L1d, feedforward,
                                                   max_preview)
            else:
                n1, d1, p1 = sb.static_inverse(L1n, L1d)
        default = (BAND_FRACTION_INTEGRATING if integrating else
                   BAND_FRACTION_MODEL if ff_model else BAND_FRACTION)
        band_fraction_out = (
            default if band_fraction is None else
            check_nonnegative('band_fraction', band_fraction))
        if band_fraction_out > 1:
            raise ValueError(f"band_fraction must be in [0, 1]; got "
                             f"{band_fraction_out!r}")
        band_x = band_fraction_out * (co['D1'] + co['D2'])
        smoothing_out = (SMOOTHING * mbar * band_x if smoothing is None
                         else check_nonnegative('smoothing', smoothing))
        if jump_samples is None:
            jump = sb.jump_samples(L1n, L1d, band_x, dt)
            if integrating:
                # L1^-1 turns the jump into a speed pulse: no faster than
                # the loop follows, or a load that coasts overshoots
                slow = int(round(JUMP_CROSSOVERS / sd.crossover(num, den,
                                                                 C)))
                if slow > JUMP_MOST:
                    notes.append(
                        f"the loop's crossover is too slow to spread the "
                        f"band jump over {JUMP_CROSSOVERS:g} of its time "
                        f"constants ({slow} samples): spread over "
                        f"{JUMP_MOST} (check the model: a loop this slow "
                        f"hardly controls the axis)")
                jump = max(jump, min(slow, JUMP_MOST))
        else:
            # half of it is preview, a delay: at most MAX_ORDER samples
            jump = check_int('jump_samples', jump_samples, minimum=1,
                             maximum=2 * MAX_ORDER)
        lead = jump // 2
        # align the band offset (through L2^-1, the inverse, L1^-1) with
        # the linear feedforward: both reach the plant for the same r(k)
        offset_preview = p1 + p2 + lead
        total = max(preview, offset_preview,
                    0 if other_inv is None else other_inv[2])
        pre = _ss(n2, d2, dt)
        post = _ss(n1, np.r_[d1, np.zeros(total - offset_preview)], dt)
        delays[0], preview = total - preview, total
        # the exact inverse keeps both slopes; the band offset alone (the
        # linear feedforward carries the mean slope) uses the mean one
        slopes = (co['m1'], co['m2']) if exact else (mbar, mbar)
        scal[INVERSE] = [*slopes, band_fraction_out * co['D1'],
                         band_fraction_out * co['D2'], smoothing_out, mbar,
                         band_x / jump if jump > 1 else 0.0, float(exact)]
        got = sd.band_adaptation(adapt, num, den, C, post, band_x,
                                 band_fraction_out, exact, band_by_default,
                                 scal, notes)
        if got is not None:
            ps, adapts = got, True
            if other_inv is not None:
                on, od, op = other_inv
                blends = sd.blend(
                    ps, _ss(on, np.r_[od, np.zeros(total - op)], dt),
                    _ss(fn, np.r_[fd, np.zeros(delays[0])], dt), model, dt,
                    scal, notes)
                if blends:
                    other, delays[1] = _ss(on, od, dt), total - op
        notes.append(sl.band_note(model, band_fraction_out, band_fraction
                                  is not None, jump, lead, (kp, ki)))
    if feedforward is not None:
        lin_ff = _ss(fn, fd, dt)
    band_fraction, smoothing = band_fraction_out, smoothing_out
    scal[GUARD] = guard_scalars(hunting, result, num, den, C, notes)
    design.update(preview=int(preview), band_fraction=float(band_fraction),
                  smoothing=float(smoothing), jump_samples=int(jump),
                  compensates=bool(comp), adapts=bool(adapts), _ps=ps,
                  hunting=(dict(zip(('deadband', 'settle', 'beta', 'floor',
                                     'gap'), scal[GUARD]))
                           if scal[GUARD][0] else None),
                  blends=bool(blends), _other=other,
                  notes=notes, _pre=pre, _post=post,
                  _linear=lin_ff, _delays=tuple(map(int, delays)),
                  _lead=int(lead), _scalars=np.array(scal, float))
    if failed:
        notes.append("designed from an identification result that is not "
                     "a success: check the model first")
    ctrl = ServoController(design, name=name)
    # an identified sandwich's choices are checked around the model, for
    # a reference travelling 20 of its bands (and the compensation for
    # one travelling the record's output spread, which can be far less)
    checked = comp and result is not None
    check = sdata.checked_model(model, response, notes)
    r = sd.design_reference(model, 20, dt) if checked else None
    if checked and band_by_default and band_fraction > 0 and \
            not helps_on_model(ctrl, check,
                               [r, sd.record_reference(result, dt)]):
        # the compensation must at least help on the model it came from
        sc = scalar_index(ctrl)
        ctrl._p[sc + BAND.start:sc + BAND.stop] = 0.0
        ctrl.__dict__['band_fraction'] = ctrl._design['band_fraction'] = 0.0
        ctrl._design['_scalars'][BAND] = 0.0
        ctrl._ix[IX_ADAPT] = ctrl._ix[IX_BLEND] = 0
        ctrl.__dict__['adapts'] = ctrl._design['adapts'] = False
        ctrl.__dict__['blends'] = ctrl._design['blends'] = False
        notes.append(f"compensation turned off: with it, tracking on the "
                     f"identified model itself (20 bands, or the record's "
                     f"spread) was over {HARM:g} times worse than without "
                     f"(pass band_fraction to force it)")

    def redo(**kw):
        with warnings.catch_warnings(), inner():  # a failed result: warned
            warnings.simplefilter('ignore', IdentificationWarning)  # once
            return servo_controller(source, **{**asked, **kw})
    own = (feedback_checked(ctrl, redo, check, mbar * check.L1 * check.L2,
                            r) if checked and feedback_from == 'auto'
           and P is lin_model else None)
    if own is not None:
        ctrl = own
    elif checked and feedforward_from == 'auto' and lin_model is not None:
        ctrl = feedforward_checked(ctrl, redo, check, ff_model, r)
    record = None if result is None else sd.record_reference(result, dt)
    moves = ([dict(feedback_from=f) for f in ('baseline', 'model')]
             if feedback_from == 'auto' and comp else [])
    if record is not None and outermost():
        ctrl = bounded_checked(ctrl, redo, check, record, moves,
                               set_keywords(asked, _DEFAULTS))
    ctrl.reset()                # the checks ran it: it starts at rest
    return ctrl


#: servo_controller's defaults, for the keywords a user set
_DEFAULTS = {k: p.default for k, p in
             inspect.signature(servo_controller).parameters.items()}
#: with an integrating L1, the band jump is spread over at least this many
#: time constants 1/w_c of the loop's crossover (chosen on the tuning
#: drives of benchmarks/bench_servo.py, where it cut the input activity and
#: kept or lowered the error on every speed loop)
JUMP_CROSSOVERS = 2.0
#: but over no more samples than this (each half of it is preview)
JUMP_MOST = 500
