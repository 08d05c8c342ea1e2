"""What `servo_controller` accepts as its model: an identification
result is unwrapped to its model, and a transfer function is checked for
a design (discrete, SISO, strictly proper, stable or with one integrator,
and a gain the design's squares do not overflow); its options; and the
checks of `ServoController`'s per-sample inputs and output."""

import math

import numpy as np
import control as ct

from . import _servo_design as sd
from ._servo_kernel import servo_step
from ..model.sandwich import SandwichSystem
from .._checks import (DATA_RANGE, MAX_ORDER, IdentificationWarning,
                       check_finite, check_gain, check_int, check_name,
                       check_option, check_real, warn)

__all__ = []


def unwrap_model(model):
    """The model of a result, and the result itself (or None); a result
    whose fields the design reads are malformed is refused."""
    inner = getattr(model, 'model', None)
    if isinstance(inner, (SandwichSystem, ct.TransferFunction)) and \
            not isinstance(model, (SandwichSystem, ct.TransferFunction)):
        _check_result(model)
        return inner, model
    return model, None


def warn_result(result, operating_point):
    """Whether `result` (an identification result, or None) failed, with
    an IdentificationWarning if so, and another where it was identified
    about offsets (``offsets='mean'`` or ``'estimate'``) and the design
    was given no operating point: its model is about the offsets, and raw
    values of that record fed to the controller would be off by them."""
    failed = result is not None and not getattr(result, 'success', True)
    if failed:
        warn(f"servo_controller: designing from an identification result "
             f"that is not a success ({getattr(result, 'message', '')}); "
             f"check the model, or re-identify, before closing the loop",
             IdentificationWarning)
    offsets = getattr(result, 'offsets', None)
    if not isinstance(offsets, dict) or tuple(operating_point) != (0, 0):
        return failed
    pairs = list(zip(offsets.get('u', ()), offsets.get('y', ())))
    if not any(a or b for a, b in pairs):
        return failed
    u0, y0 = pairs[0]
    warn(f"servo_controller: the result was identified with offsets="
         f"{offsets.get('method')!r}, so its model is about (u0, y0) = "
         f"({u0:.6g}, {y0:.6g}) of its {'first ' if len(pairs) > 1 else ''}"
         f"record; pass operating_point=(u0, y0) to feed the controller "
         f"raw values of that record (the default (0, 0) takes them as "
         f"deviations from it)", IdentificationWarning)
    return failed


def _check_result(result):
    """ValueError naming the field of an identification result (or an
    object that passes for one) that the design cannot read."""
    for key in ('residuals', 'yhat', 'errors'):
        value = getattr(result, key, None)
        if value is not None:
            _arrays(f"model.{key}", [value], 1)
    success = getattr(result, 'success', True)
    if not isinstance(success, (bool, np.bool_)):
        raise ValueError(f"model.success must be True or False; got "
                         f"{success!r:.60}")
    linear = getattr(result, 'linear', None)
    if linear is None:
        return
    if not isinstance(linear, dict):
        raise ValueError(f"model.linear must be a dict (the linear baseline "
                         f"of an identification result); got "
                         f"{type(linear).__name__}")
    base = linear.get('model')
    if base is not None and not isinstance(base, ct.TransferFunction):
        raise ValueError(f"model.linear['model'] must be a TransferFunction "
                         f"or None; got {type(base).__name__}")
    fits = [('model.fit', getattr(result, 'fit', None)),
            ("model.linear['fit']", linear.get('fit'))]
    for where, value in fits + [("model.linear['noise']",
                                 linear.get('noise'))]:
        if value is not None and np.isnan(check_real(where, value)):
            raise ValueError(f"{where} must be a number; got nan")
    for key, count in (('error_bands', 2), ('relative_error', 3)):
        value = linear.get(key)
        if value is not None:
            _arrays(f"model.linear[{key!r}]", value, count)


def _arrays(where, parts, count):
    """Require `count` numeric 1-D arrays of one length."""
    try:
        arrays = [np.asarray(part) for part in parts]
    except (TypeError, ValueError):
        arrays = []
    if not (len(arrays) == count and all(
            a.ndim == 1 and a.dtype.kind in 'iufc'
            and a.size == arrays[0].size for a in arrays)):
        raise ValueError(f"{where} must be {count} numeric 1-D array"
                         f"{'s of one length' if count > 1 else ''} (as "
                         f"identify returns it); got {parts!r:.80}")


def check_plant_tf(name, sys):
    """(num, den) of the transfer function `sys` a design may use (see
    the module notes); `name` says which in an error."""
    if not isinstance(sys, ct.TransferFunction) or not sys.issiso() or \
            not sys.isdtime(strict=True):
        what = type(sys).__name__
        if isinstance(sys, ct.TransferFunction):
            what = (f"a TransferFunction with {sys.ninputs} input(s) and "
                    f"{sys.noutputs} output(s)" if not sys.issiso() else
                    f"a TransferFunction with dt={sys.dt!r} (not "
                    f"discrete-time; discretize it with ct.c2d or "
                    f"sys.sample)")
        raise TypeError(
            f"{name} must be a sandwichctl.SandwichSystem, a discrete SISO "
            f"control.TransferFunction, or an identification result "
            f"holding one (sw.identify / sw.identify_linear); got {what}")
    num, den = sys.num[0][0].astype(float), sys.den[0][0].astype(float)
    num = np.trim_zeros(num, 'f')
    if num.size == 0 or not np.all(np.isfinite(num)) or \
            not np.all(np.isfinite(den)):
        raise ValueError(f"{name} must have finite, non-zero coefficients")
    if num.size >= den.size:
        raise ValueError(f"{name} must have at least one sample of delay "
                         f"(strictly proper); with none the loop is "
                         f"algebraic")
    check_gain(name, num, den, "the design squares it, which would {what} "
               "double precision")
    zeros = np.roots(num) if num.size > 1 else np.zeros(0)
    if np.any(sd.at_one(zeros)):
        raise ValueError(
            f"{name} has a zero at z = 1 (zeros {sd._fmt_roots(zeros)}): "
            f"its gain at DC is zero, so no input holds its output at a "
            f"constant reference. A plant that differentiates (position in, "
            f"speed out) is servoed on its integrated output; else "
            f"re-identify with fewer zeros")
    poles = np.roots(den) if den.size > 1 else np.zeros(0)
    one = sd.at_one(poles)
    if one.sum() > 1 or np.any(np.abs(poles[~one]) >= 1.0):
        raise ValueError(
            f"{name} must be stable or have one integrator (a pole at "
            f"z = 1, as a speed-in, position-out axis); got poles "
            f"{sd._fmt_roots(poles)}. Re-identify with integrators=1 (a "
            f"speed-in, position-out axis) or integrators=0, or with "
            f"fewer poles")
    if np.any(np.abs(poles[one] - 1.0) > 1e-12):
        # the integrator exactly at 1: at 1 - 1e-8 the grid would reach
        # down to 1e-9 rad/sample, where the plant's gain is 10 times
        # below its integrator's, and the bandwidth would come out 8 times
        # too high (random drive 18 of benchmarks/bench_servo.py)
        den = den[0] * np.real(np.poly(np.where(one, 1.0, poles)))
    return num, den


#: samples of reference preview the feedforward may use by default
MAX_PREVIEW = 20
#: the entries of a design that `ServoController` is built from
DESIGN_KEYS = frozenset(('_fb', '_pre', '_post', '_linear', '_ps', '_other',
                         '_scalars', '_lead', 'preview', 'compensates',
                         'adapts', 'blends', 'dt', 'operating_point'))
#: the largest magnitude of r_ahead and y a ServoController takes (the
#: identifiers' bound on data, `_checks.DATA_RANGE`)
INPUT_MOST = DATA_RANGE[1]


def check_options(modulus_margin, feedforward, feedforward_from,
                  feedback_from, adapt, crossover_limit, max_preview, name,
                  operating_point):
    """`servo_controller`'s options checked: (modulus_margin, adapt,
    crossover_limit, max_preview, name, (u0, y0)) as the design uses
    them."""
    mm = check_finite('modulus_margin', modulus_margin)
    if not 0 < mm < 1:
        raise ValueError(f"modulus_margin must be in (0, 1); got {mm!r}")
    check_option('feedforward', feedforward, ('preview', 'zpetc', None))
    for key, choice in (('feedforward_from', feedforward_from),
                        ('feedback_from', feedback_from)):
        check_option(key, choice, ('auto', 'model', 'baseline'))
    adapt = bool(adapt) if isinstance(adapt, np.bool_) else adapt
    if not (adapt is None or isinstance(adapt, bool)):    # 0 == False
        raise ValueError(f"adapt must be one of None, True, False; got "
                         f"{adapt!r}")
    if crossover_limit is not None:
        crossover_limit = check_finite('crossover_limit', crossover_limit)
        if not 0.1 <= crossover_limit <= 1000:
            raise ValueError(f"crossover_limit must be in [0.1, 1000] "
                             f"plant bandwidths; got {crossover_limit!r}")
    max_preview = check_int('max_preview', max_preview, 0, MAX_ORDER)
    if feedforward is None and max_preview != MAX_PREVIEW:
        raise ValueError("max_preview sets the feedforward's preview, and "
                         "feedforward=None turns it off: leave it out")
    name = check_name('name', name)
    if isinstance(operating_point, (str, bytes)) or \
            np.ndim(operating_point) != 1 or np.size(operating_point) != 2:
        raise ValueError(f"operating_point must be a pair (u0, y0); got "
                         f"{operating_point!r}")
    u0, y0 = (check_level('operating_point', v) for v in operating_point)
    return mm, adapt, crossover_limit, max_preview, name, (u0, y0)


def check_level(name, value):
    """`value` as a finite float of at most `INPUT_MOST` in magnitude (an
    operating point: the controller adds it to u and takes it from y,
    whose steps refuse larger ones)."""
    v = check_finite(name, value)
    if not abs(v) <= INPUT_MOST:
        raise ValueError(f"{name} must be at most {INPUT_MOST:g} in "
                         f"magnitude, as the controller's inputs; got {v!r}")
    return v


def overflow(k):
    """Raise for an input that overflowed the controller at sample k (the
    caller has put its memory back)."""
    where = '' if k is None else f" at sample {k}"
    raise OverflowError(
        f"u overflowed{where}: r_ahead or y is too large for the "
        f"controller's gains (scale the data as the design's model was "
        f"identified); the controller's memory is unchanged")


def check_inputs(r, y, where):
    """Raise unless r_ahead and y (floats) are finite and at most
    `INPUT_MOST` in magnitude: a larger finite value would sit in the
    preview's delay line and overflow the samples after it."""
    if not (abs(r) <= INPUT_MOST and abs(y) <= INPUT_MOST):
        raise ValueError(f"r_ahead and y must be finite and at most "
                         f"{INPUT_MOST:g} in magnitude; got r_ahead={r!r}, "
                         f"y={y!r}{where}")


def check_input_arrays(r_ahead, y):
    """`check_inputs` on the sequences of `ServoController.run`."""
    if r_ahead.size:
        k = int(np.argmax(np.maximum(np.abs(r_ahead), np.abs(y))))
        check_inputs(float(r_ahead[k]), float(y[k]), f" at sample {k} (the "
                     f"controller's memory is unchanged)")


def finite_inputs(t, u):
    """(r_ahead, y) of python-control's input vector `u` at time t, as
    floats; not finite raises, as `ServoController.step` does."""
    vec = np.asarray(u, dtype=float).ravel()
    if vec.size != 2:
        raise ValueError(f"the controller's input vector must be [r_ahead, "
                         f"y], 2 entries; got {vec.size} at t={t!r}")
    r, y = float(vec[0]), float(vec[1])
    check_inputs(r, y, f" at t={t!r}")
    return r, y


def python_step(p, ix, n, t, x, u):
    """(next state, output) of python-control's state x (n entries) and
    input vector u at time t (`ServoController`'s update and output
    functions); inputs, state or output not finite, or of another size,
    raise."""
    s = np.array(x, dtype=float)
    if s.shape != (n,):
        raise ValueError(f"the controller's state must have {n} entries "
                         f"(ctrl.nstates); got shape {s.shape} at t={t!r}")
    if not np.all(np.isfinite(s)):
        raise ValueError(f"the controller's state must be finite; got "
                         f"{np.count_nonzero(~np.isfinite(s))} entries that "
                         f"are not at t={t!r} (check X0)")
    out = servo_step(p, ix, s, *finite_inputs(t, u))
    if not math.isfinite(out):
        raise OverflowError(f"u overflowed at t={t!r}: r_ahead or y is too "
                            f"large for the controller's gains, or the loop "
                            f"diverged")
    return s, out
