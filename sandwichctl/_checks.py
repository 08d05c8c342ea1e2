"""Argument checks and warning categories shared by the package (private).

Every public function checks its arguments at the door with these
functions. Each check raises ``TypeError`` (wrong kind of object: a
string, None, a boolean or a complex number where a real number is
expected) or ``ValueError`` (right kind, wrong value: NaN, a negative
order, a wrong shape) with a message that names the argument, says what
was received and what is expected.

The warning categories are public (``sw.SandwichWarning``, ...) so that
users can filter them; `warn` issues one with the stack level of the
user's own line.
"""

import contextlib
import functools
import numbers
import os
import sys
import threading
import warnings

import numpy as np
import control as ct
from threadpoolctl import threadpool_limits

__all__ = ['SandwichWarning', 'IdentificationWarning', 'ExcitationWarning',
           'SimulationWarning']

#: Largest order or delay (in samples) accepted anywhere: a linear block
#: of eq. (2.1) with more states than this is a typo (``q1=10**6``) that
#: would otherwise take minutes and gigabytes before failing.
MAX_ORDER = 1000

#: Most samples a generated signal or record may have (800 MB of
#: float64): more is a typo (``n=10**13``) that would otherwise fail with
#: numpy's MemoryError of terabytes.
MOST_SAMPLES = 10 ** 8

#: Most iterations of a search's loops (``max_iter``, ``screen_iter``,
#: ``sp_iter``) and most starts, hops, rounds or kept candidates
#: (``n_random``, ``hops``, ``n_starts``, a bundle's ``k1``, ...): more is
#: a typo (``hops=10**6``) that would run for hours, or allocate
#: gigabytes, before failing.
MOST_ROUNDS = 100_000
MOST_STARTS = 1000

#: A free pole of a linear output-error fit beyond this radius is pinned
#: at the stability boundary: the fit stopped there (the identifiers flag
#: it; a servo design does not design on such a baseline).
PINNED = 1 - 1e-5

#: Peak magnitudes of data the identifiers accept: their least-squares
#: costs are sums of squares (and of products of u and y), which overflow
#: or underflow double precision far outside this range (1e200 does).
DATA_RANGE = (1e-100, 1e100)


# ----------------------------------------------------------------------
# Warning categories
# ----------------------------------------------------------------------
class SandwichWarning(UserWarning):
    """Base class of every warning sandwichctl issues.

    Silence them all with
    ``warnings.simplefilter('ignore', sw.SandwichWarning)``, or turn them
    into errors with ``'error'``.
    """


class IdentificationWarning(SandwichWarning, RuntimeWarning):
    """An identification finished, but its result needs care.

    For example: the estimate diverged or hit an iteration limit, some
    parameters are poorly determined by the data, or the data do not
    support the backlash. ``res.success`` and ``res.message`` say more.
    It is also a RuntimeWarning, as these warnings were before.
    """


class ExcitationWarning(IdentificationWarning):
    """The input does not excite the system enough to identify it.

    For example: the backlash of the model hardly leaves its memory zone
    (the input amplitude is smaller than the dead band), or the input is
    constant over most of the record.
    """


class SimulationWarning(SandwichWarning, RuntimeWarning):
    """A simulation produced non-finite values (an unstable system or an
    input too large), or was asked for something it can only approximate.
    """


_PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__)) + os.sep
_CONTROL_DIR = os.path.dirname(os.path.abspath(ct.__file__)) + os.sep
#: a context manager's exit runs in contextlib's frame (a warning told at
#: the end of a block, `_recursive.one_qp_warning`)
_CONTEXTLIB = os.path.abspath(contextlib.__file__)


def user_stacklevel():
    """Stack level of the first frame outside sandwichctl and python-control.

    Called from the function that warns, so that ``warnings.warn(...,
    stacklevel=user_stacklevel())`` points at the user's line however deep
    in the package the warning is raised (python-control frames are
    skipped too, for systems simulated by ``ct.input_output_response``).
    """
    frame = sys._getframe(1)       # the function that is about to warn
    level = 1
    while frame is not None:
        path = os.path.abspath(frame.f_code.co_filename)
        if not (path.startswith(_PACKAGE_DIR)
                or path.startswith(_CONTROL_DIR) or path == _CONTEXTLIB):
            return level
        frame = frame.f_back
        level += 1
    return 1


def warn(message, category=SandwichWarning):
    """Issue `message` as `category`, attributed to the user's line."""
    warnings.warn(message, category, stacklevel=user_stacklevel())


def warn_overflow(values, what, why):
    """SimulationWarning where `values` (the output of `what`) stop being
    finite: from the first such sample, and `why` (cause and remedy)."""
    bad = ~np.isfinite(values)
    if bad.any():
        warn(f"{what} overflows double precision from sample "
             f"{int(np.flatnonzero(bad)[0])} on {why}", SimulationWarning)


# ----------------------------------------------------------------------
# Scalars
# ----------------------------------------------------------------------
def check_positive(name, value):
    """Return `value` as float, requiring 0 < value < inf."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value) or value <= 0:
        raise ValueError(
            f"{name} must be a finite number > 0; got {value!r}")
    return value


def check_tolerance(name, value):
    """Return `value` as float, requiring 0 < value < 1: a relative
    tolerance (1 or more would stop an iteration before its first step)."""
    value = check_positive(name, value)
    if value >= 1:
        raise ValueError(f"{name} must be below 1 (a relative tolerance); "
                         f"got {value!r}")
    return value


def check_nonnegative(name, value):
    """Return `value` as float, requiring 0 <= value < inf."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value) or value < 0:
        raise ValueError(
            f"{name} must be a finite number >= 0; got {value!r}")
    return value


def is_finite_real(value):
    """Whether the real number `value` is finite as a float (an integer
    beyond the floats is not; numpy's isfinite refuses one)."""
    try:
        return bool(np.isfinite(float(value)))
    except OverflowError:
        return False


def check_finite(name, value):
    """Return `value` as float, requiring it to be finite."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite; got {value!r}")
    return value


#: scalar types a per-sample call (a controller's or a drive's step) takes
#: with a bare float(), skipping `check_real`: float() gives what
#: check_real would for each of them
PLAIN_REALS = frozenset((float, int, np.float64, np.float32, np.int64))


def check_real(name, value):
    """Return `value` as float, requiring a real number (NaN and inf pass:
    the caller says what they mean for it)."""
    return _as_real_scalar(name, value)


def check_rng(name, seed):
    """numpy's generator of `seed` (None, an integer >= 0, a seed sequence
    or a Generator), refused with a message naming it."""
    try:
        if isinstance(seed, (bool, np.bool_)):
            raise TypeError("a bool is no seed")
        return np.random.default_rng(seed)
    except (TypeError, ValueError) as exc:
        kind = TypeError if isinstance(exc, TypeError) else ValueError
        raise kind(f"{name} must be None, an integer >= 0 or a "
                   f"numpy.random.Generator; got {type(seed).__name__} "
                   f"{seed!r}") from None


def check_int(name, value, minimum=0, maximum=None):
    """Return `value` as int, requiring an integer in [minimum, maximum].

    Booleans and floats (even 2.0) are refused: an order or a length is
    counted, not measured.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(
            value, numbers.Integral):
        raise TypeError(
            f"{name} must be an integer >= {minimum}; got "
            f"{type(value).__name__} {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}; "
                         f"got {value}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{name} must be an integer <= {maximum}; got "
                         f"{value}")
    return int(value)


def check_order(name, value):
    """An order or delay of eq. (2.1): an integer in [0, MAX_ORDER]."""
    return check_int(name, value, 0, MAX_ORDER)


def check_bool(name, value):
    """Return `value` as bool, requiring True or False (numpy's too)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be True or False; got "
                        f"{type(value).__name__} {value!r}")
    return bool(value)


def check_option(name, value, allowed):
    """Return `value`, requiring one of `allowed` (ValueError lists them)."""
    if isinstance(value, (bool, np.bool_)) and not any(
            isinstance(a, bool) for a in allowed):
        ok = False
    elif isinstance(value, np.ndarray) and value.ndim:
        ok = False                 # `in` would compare elementwise
    else:
        try:
            ok = bool(value in allowed)
        except (TypeError, ValueError):    # unhashable, or ambiguous
            ok = False
    if not ok:
        choices = ', '.join(repr(a) for a in allowed)
        raise ValueError(f"{name} must be one of {choices}; got {value!r}")
    return value


def check_name(name, value):
    """A system name: a string or None."""
    if value is not None and not isinstance(value, str):
        raise TypeError(f"{name} must be a string or None; got "
                        f"{type(value).__name__} {value!r}")
    return value


def named_copy(self, name=None, use_prefix_suffix=True):
    """A copy of the system, with a new name.

    python-control's ``copy``, its arguments checked first (a name that
    is not a string failed inside python-control's name handling).

    Parameters
    ----------
    name : str, optional
        Name of the copy. By default the system's own name with
        python-control's prefix and suffix (``'name$copy'``) if
        `use_prefix_suffix`, else a generic ``'sys[<id>]'``.
    use_prefix_suffix : bool, optional
        See `name` (default True).

    Returns
    -------
    object
        The copy, of the system's own class.

    Raises
    ------
    TypeError
        If `name` is not a string or None, or `use_prefix_suffix` is not
        True or False.
    """
    check_name('name', name)
    check_bool('use_prefix_suffix', use_prefix_suffix)
    return ct.InputOutputSystem.copy(self, name, use_prefix_suffix)


def check_label(name, value, what='signal'):
    """The name of the single input, output or signal of a SISO system.

    A string, or a list or tuple holding exactly one string; returns the
    string.
    """
    if isinstance(value, (list, tuple)):
        if len(value) != 1:
            raise ValueError(
                f"{name} must name the one {what} of this system; got "
                f"{len(value)} names {list(value)!r}")
        value = value[0]
    if not isinstance(value, str) or not value:
        raise TypeError(f"{name} must be a non-empty string (the {what}'s "
                        f"name); got {type(value).__name__} {value!r}")
    return value


def check_labels(name, value, count):
    """A list of exactly `count` distinct non-empty strings."""
    if isinstance(value, str) or not isinstance(value, (list, tuple)):
        raise TypeError(f"{name} must be a list of {count} strings; got "
                        f"{type(value).__name__} {value!r}")
    if len(value) != count:
        raise ValueError(f"{name} must hold {count} names; got "
                         f"{len(value)}: {list(value)!r}")
    for item in value:
        if not isinstance(item, str) or not item:
            raise TypeError(f"{name} must hold non-empty strings; got "
                            f"{type(item).__name__} {item!r}")
    if len(set(value)) != count:
        raise ValueError(f"{name} must hold distinct names; got "
                         f"{list(value)!r}")
    return list(value)


def check_dt(name, dt):
    """A discrete sampling time: a finite number > 0, or True (unspecified).

    Returns it unchanged (an integer stays an integer, as in
    python-control).
    """
    if dt is True:
        return dt
    if isinstance(dt, (bool, np.bool_)) or dt is None or not isinstance(
            dt, (numbers.Real, np.floating, np.integer)):
        raise TypeError(
            f"{name} must be a positive sampling time or True (discrete, "
            f"unspecified); got {type(dt).__name__} {dt!r}. sandwichctl's "
            f"systems are discrete-time")
    if not (is_finite_real(dt) and dt > 0):
        raise ValueError(
            f"{name} must be a positive sampling time (finite, > 0) or True "
            f"(discrete, unspecified); got {dt!r}")
    return dt.item() if isinstance(dt, np.generic) else dt


# ----------------------------------------------------------------------
# Arrays
# ----------------------------------------------------------------------
def _real_array(name, values, what):
    """`values` as a float array; refuse strings, None, bool and complex."""
    if _is_str(values) or values is None:
        raise TypeError(f"{name} must be {what}; got "
                        f"{type(values).__name__} {values!r}")
    if isinstance(values, ct.TimeResponseData):
        raise TypeError(f"{name} must be {what}; got a TimeResponseData "
                        f"(pass resp.inputs or resp.outputs)")
    if np.ma.is_masked(values):
        raise ValueError(f"{name} has {int(np.ma.count_masked(values))} "
                         f"masked values, whose data would be used as if "
                         f"measured; fill them (values.filled(...)) or cut "
                         f"the record into experiments around them")
    try:
        raw = np.asarray(values)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be {what}; got "
                        f"{type(values).__name__}") from None
    if raw.dtype.kind == 'c':
        raise TypeError(f"{name} must be real; got complex values (take "
                        f".real explicitly if the imaginary part is "
                        f"rounding)")
    if raw.dtype.kind == 'b':
        raise TypeError(f"{name} must hold numbers; got booleans")
    if raw.dtype.kind not in 'iuf':
        try:
            items = raw.ravel().tolist()
        except Exception:                       # pragma: no cover
            items = []
        for item in items:
            if (item is None or _is_str(item) or isinstance(item, bool)
                    or isinstance(item, complex)
                    or not isinstance(item, (numbers.Real, np.generic))):
                raise TypeError(f"{name} must hold real numbers; got "
                                f"{type(item).__name__} {item!r}")
        try:
            raw = raw.astype(float)
        except (TypeError, ValueError):
            raise TypeError(f"{name} must be {what}; got "
                            f"{type(values).__name__}") from None
        except OverflowError:
            raise ValueError(f"{name} holds an integer too large for a "
                             f"float") from None
    return np.asarray(raw, dtype=float)


def check_signal(name, values, length=None, of=None):
    """Return a finite 1-D float array, rejecting other shapes and NaN/inf.

    A row or column vector (shape (1, N) or (N, 1)) is accepted as the N
    samples it holds; other 2-D shapes, scalars, complex or boolean
    arrays are refused. With `length`, it must have that many samples
    (as the signal named `of`, when given: the message names both).
    """
    arr = _real_array(name, values, 'an array of numbers')
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()          # a row or column vector is fine
    if arr.ndim != 1:
        raise ValueError(
            f"{name} must be a 1-D array of samples; got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must contain at least one sample; got 0")
    if length is not None and arr.size != length:
        raise ValueError(
            f"{name} must have {length} samples"
            + ("" if of is None else f", as many as {of}")
            + f"; got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} must be finite; sample {first} is {float(arr[first])}")
    return np.ascontiguousarray(arr)


def check_vector(name, values, length=None):
    """Return a finite 1-D float array (of exactly `length` entries)."""
    arr = _real_array(name, values, 'a sequence of numbers')
    if arr.ndim != 1 or (length is not None and arr.size != length):
        want = f" of length {length}" if length is not None else ""
        raise ValueError(
            f"{name} must be a 1-D array{want}; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr}")
    return arr.copy()


def check_reference(name, values):
    """A finite, non-zero reference vector to divide by (relative errors)."""
    arr = check_vector(name, values)
    if not np.any(arr):
        raise ValueError(
            f"{name} is zero, so an error relative to it is undefined; "
            f"compare with a non-zero reference, or use the absolute error "
            f"np.linalg.norm(theta_hat - {name})")
    return arr


def check_model_output(yhat, what):
    """Refuse a model's simulated or predicted output `yhat` (`what` names
    it) that is not finite or is beyond the data the tools take (above
    ``DATA_RANGE[1]`` in magnitude): the model is unstable."""
    bad = ~(np.abs(yhat) <= DATA_RANGE[1])
    if bad.any():
        raise ValueError(
            f"{what} is not finite or above {DATA_RANGE[1]:g} in magnitude "
            f"(first bad sample {int(np.flatnonzero(bad)[0])}); the model "
            f"is probably unstable, or its gain does not suit the data's "
            f"units")


def check_data_scale(name, parts, sums='the least-squares costs', low=True,
                     back='scale the model back'):
    """Refuse data (one array or a list of experiments) whose `sums` of
    squares would overflow or underflow double precision.

    A signal whose peak magnitude is outside `DATA_RANGE` (with `low`
    False, above it: a tiny signal passes) is refused with the remedy:
    rescale it, and `back`; an all-zero signal passes (other checks speak
    about excitation).
    """
    parts = parts if isinstance(parts, (list, tuple)) else [parts]
    peak = max(float(np.max(np.abs(part))) for part in parts)
    lo, hi = DATA_RANGE
    if peak and not (lo if low else 0) <= peak <= hi:
        what = 'overflow' if peak > hi else 'underflow'
        where = f"outside {lo:g} .. {hi:g}" if low else f"above {hi:g}"
        raise ValueError(
            f"{name} has peak magnitude {peak:.3g}, {where}: {sums} (sums "
            f"of squares) would {what} double precision; rescale {name} "
            f"(e.g. {name} / {peak:.0e}, other units) and {back}")


def check_parameter_count(orders, n_samples):
    """Refuse orders with more parameters than sqrt(N) (`identify`).

    The output-error search's work grows steeply with the number of
    parameters p = na + nb + nc + nd + 4 (na = nc = 20 on 2,000 samples
    takes about 15 s, na = nc = 40 over a minute), and p**2 > N leaves
    each parameter poorly determined anyway.
    """
    p = orders['na'] + orders['nb'] + orders['nc'] + orders['nd'] + 4
    if p * p > n_samples:
        big = max(('na', 'nb', 'nc', 'nd'), key=orders.get)
        raise ValueError(
            f"the orders give p = {p} parameters (na + nb + nc + nd + 4; "
            f"the largest is {big} = {orders[big]}) but the data have N = "
            f"{n_samples} samples, which allow at most "
            f"{int(np.sqrt(n_samples))} (p**2 <= N); lower the orders "
            f"(sw.select_structure compares candidates) or give at least "
            f"{p * p} samples")


def check_axes(name, ax):
    """None or a matplotlib Axes (anything with ``plot``) to draw on."""
    if ax is not None and not callable(getattr(ax, 'plot', None)):
        raise TypeError(
            f"{name} must be a matplotlib Axes (e.g. fig, ax = "
            f"plt.subplots(), then {name}=ax) or None for the current "
            f"axes; got {type(ax).__name__} {ax!r}")
    return ax


def check_timepts(name, timepts, length, dt):
    """Evenly spaced time points, `length` of them, with spacing `dt`.

    A simulation of a discrete system advances one sample per step, so
    time points must be ``t0 + dt * arange(N)``; anything else is refused
    rather than silently reinterpreted.
    """
    t = check_signal(name, timepts, length=length)
    if t.size < 2:
        return t
    step = np.diff(t)
    if np.any(step <= 0):
        k = int(np.flatnonzero(step <= 0)[0])
        raise ValueError(f"{name} must increase; t[{k + 1}] = {t[k + 1]} "
                         f"<= t[{k}] = {t[k]}")
    h = (t[-1] - t[0]) / (t.size - 1)
    # rounding of t0 + k h grows with the size of t
    tol = max(1e-6 * h, 8 * np.finfo(float).eps * np.max(np.abs(t)))
    if np.max(np.abs(step - h)) > tol:
        k = int(np.argmax(np.abs(step - h)))
        raise ValueError(
            f"{name} must be evenly spaced (one per sample); the step "
            f"t[{k + 1}] - t[{k}] = {step[k]:.6g} differs from the mean "
            f"step {h:.6g}")
    if dt is not True and abs(h - float(dt)) > max(1e-6 * float(dt), tol):
        raise ValueError(
            f"{name} has spacing {h:.6g} but the system samples every "
            f"dt = {dt!r}; pass t0 + dt * np.arange(N) (or resample the "
            f"data)")
    return t


def check_discrete_siso_tf(name, sys):
    """Check that `sys` is a proper, discrete-time, SISO TransferFunction.

    Returns the numerator and denominator as 1-D float arrays in
    descending powers of z, with leading zeros removed and the
    denominator scaled so that its leading coefficient is 1.
    """
    if not isinstance(sys, ct.TransferFunction):
        raise TypeError(
            f"{name} must be a control.TransferFunction (e.g. "
            f"ct.tf([1.5, 0], [1, 0.1, 0.2], dt)); got "
            f"{type(sys).__name__}")
    if sys.ninputs != 1 or sys.noutputs != 1:
        raise ValueError(
            f"{name} must be SISO; got {sys.noutputs} outputs and "
            f"{sys.ninputs} inputs")
    if not sys.isdtime(strict=True):
        raise ValueError(
            f"{name} must be discrete-time (dt > 0 or dt=True); got "
            f"dt={sys.dt!r}. Discretise it first, e.g. with "
            f"ct.sample_system({name}, Ts)")
    if sys.dt is not True and not np.isfinite(sys.dt):
        raise ValueError(f"{name} must have a finite sampling time; got "
                         f"dt={sys.dt!r}")
    raw_num = np.atleast_1d(np.asarray(sys.num[0][0]))
    raw_den = np.atleast_1d(np.asarray(sys.den[0][0]))
    if np.iscomplexobj(raw_num) or np.iscomplexobj(raw_den):
        raise ValueError(f"{name} has complex coefficients; a sandwich "
                         f"block must be real")
    check_finite_system(name, sys)
    num = np.trim_zeros(raw_num.astype(float), 'f')
    den = np.trim_zeros(raw_den.astype(float), 'f')
    if num.size == 0:
        raise ValueError(f"{name} has a zero numerator; a sandwich block "
                         f"must pass its input on")
    if den.size - 1 > MAX_ORDER:
        raise ValueError(f"{name} has order {den.size - 1}; sandwichctl "
                         f"accepts at most {MAX_ORDER}")
    if num.size > den.size:
        raise ValueError(
            f"{name} is improper (numerator degree {num.size - 1} > "
            f"denominator degree {den.size - 1}); a causal difference "
            f"equation needs deg(num) <= deg(den)")
    return num / den[0], den / den[0]


def check_finite_system(name, sys):
    """Refuse a linear python-control system with a NaN or inf coefficient
    (a TransferFunction's numerator or denominator, a StateSpace's A, B,
    C, D, an FRD's response); other systems pass unchanged."""
    if isinstance(sys, ct.TransferFunction):
        parts = [c for rows in (sys.num, sys.den) for row in rows
                 for c in row]
    elif isinstance(sys, ct.StateSpace):
        parts = [sys.A, sys.B, sys.C, sys.D]
    elif isinstance(sys, ct.FrequencyResponseData):
        parts = [sys.fresp]
    else:
        return sys
    if not all(np.all(np.isfinite(np.asarray(part))) for part in parts):
        raise ValueError(f"{name} has non-finite coefficients (NaN or "
                         f"inf); a system's coefficients must be finite "
                         f"numbers")
    return sys


def check_gain(name, num, den, why):
    """Refuse a transfer function num/den (1-D arrays) whose gain, the
    largest numerator over the largest denominator coefficient, is
    outside `DATA_RANGE`: `why` says what it would break, ``{what}`` in
    it reading 'overflow' or 'underflow'."""
    gain = np.max(np.abs(num)) / np.max(np.abs(den))
    lo, hi = DATA_RANGE
    if not lo <= gain <= hi:
        what = 'overflow' if gain > hi else 'underflow'
        raise ValueError(
            f"{name} has a gain of order {gain:.1e} (largest numerator "
            f"over largest denominator coefficient), outside {lo:g} .. "
            f"{hi:g}: {why.format(what=what)}; rescale u or y (other "
            f"units)")


def common_dt(name1, dt1, name2, dt2):
    """Return the common sampling time of two discrete systems (equal to
    rounding, 1e-9 relative, as python-control takes them: 0.1 * 3 and
    0.3 are one sampling time; the first is returned)."""
    if dt1 is True:
        return dt2
    if dt2 is True or dt1 == dt2:
        return dt1
    both = all(isinstance(d, numbers.Real) and not isinstance(d, bool)
               for d in (dt1, dt2))
    if both and dt1 > 0 and abs(dt1 - dt2) <= 1e-9 * abs(dt1):
        return dt1
    raise ValueError(
        f"{name1} and {name2} must have the same sampling time; got "
        f"dt={dt1!r} and dt={dt2!r}")


def _as_real_scalar(name, value):
    if isinstance(value, (bool, np.bool_, np.timedelta64)) or \
            not isinstance(value, (numbers.Real, np.floating, np.integer)):
        if np.ma.is_masked(value):     # np.ma.masked read as its 0.0
            raise ValueError(f"{name} is masked (np.ma.masked), a value "
                             f"that is missing; give a number")
        arr = None
        if not _is_str(value) and value is not None:
            try:
                arr = np.asarray(value)
            except Exception:
                arr = None
        if (arr is None or arr.ndim != 0 or arr.dtype.kind not in 'iuf'):
            raise TypeError(f"{name} must be a real number; got "
                            f"{type(value).__name__} {value!r}")
        value = arr.item()
    try:
        return float(value)
    except OverflowError:
        raise ValueError(f"{name} is too large for a float; got "
                         f"{value!r:.40}...") from None


def _is_str(value):
    return isinstance(value, (str, bytes))


# ----------------------------------------------------------------------
# Progress bars
# ----------------------------------------------------------------------
def progress_bar(enabled, **kwargs):
    """A tqdm bar: the notebook widget in Jupyter, text in a terminal.

    ``tqdm.auto`` is imported only when a bar is asked for, so that a
    notebook without ipywidgets sees no warning unless it shows progress;
    otherwise a disabled plain bar is returned (it does nothing).
    """
    if isinstance(enabled, _SharedBar):
        return enabled.part(kwargs.get('total') or 0)
    if enabled:
        from tqdm.auto import tqdm
        return tqdm(**kwargs)
    from tqdm import tqdm
    return tqdm(disable=True, **kwargs)


def close_filled(bar):
    """Close a search's `bar` full. Its total is what the search's steps
    said they would run, an upper bound: a step that ends early ticks
    less (130 of 132 planned), and tqdm's notebook widget closed short of
    its total turns red. A share of a shared bar fills on its close."""
    if not isinstance(bar, _SharedBar):
        rest = (bar.total or 0) - bar.n
        if rest > 0:
            bar.update(rest)
    bar.close()


#: Units of the shared bar per search (`shared_progress`).
SHARE_UNITS = 100


@contextlib.contextmanager
def shared_progress(task, n, desc):
    """Within: the `n` searches run on `task` (its ``progress`` True), on
    threads at once or one after the other, count on one bar, not on `n`
    bars that overwrite one another's line.

    The bar's total, `n` shares of `SHARE_UNITS`, is known when it is
    made (tqdm's notebook widget keeps the total it was made with): a
    search's `progress_bar` starts its share, its ticks fill it in
    proportion to the total it planned, and its ``close`` fills the rest.
    A search that raises leaves its share unfilled.
    """
    if not (task.progress is True and n > 1):
        yield
        return
    bar = progress_bar(True, total=n * SHARE_UNITS, desc=desc, leave=False,
                       bar_format='{l_bar}{bar}| [{elapsed}<{remaining}]')
    task.progress = _SharedBar(bar)
    try:
        yield
    finally:
        task.progress = True
        bar.close()


class _SharedBar:
    """A tqdm bar that threads share (`shared_progress`), one share of
    `SHARE_UNITS` per search. A search runs, and ticks, on one thread, so
    each thread keeps the state of the search it runs: its planned total,
    the ticks so far and the units shown."""

    def __init__(self, bar):
        self.bar, self.lock = bar, threading.Lock()
        self.local = _Part()

    def part(self, total):
        """A search's start, `total` ticks planned: this bar."""
        self.local.total, self.local.ticks, self.local.shown = total, 0, 0
        return self

    def update(self, n=1):
        """`n` ticks of the search on this thread."""
        part = self.local
        part.ticks += n
        if part.total > 0:
            self._show(SHARE_UNITS * part.ticks // part.total)

    def close(self):
        """One search's end: its share filled; the bar stays until every
        search has ended."""
        self._show(SHARE_UNITS)

    def _show(self, units):
        part = self.local
        step = min(units, SHARE_UNITS) - part.shown
        if step > 0:
            part.shown += step
            with self.lock:
                self.bar.update(step)


class _Part(threading.local):
    """The state of a thread's search on a `_SharedBar`: ticks planned,
    ticks so far, units shown."""
    total = ticks = shown = 0


def serial_blas(func):
    """Decorator: run `func` with the BLAS library on one thread.

    The identifiers multiply small matrices (N x p with p ~ 10) thousands
    of times; a multi-threaded BLAS gains nothing on them and, on a busy
    machine, loses several times over to thread hand-offs. threadpoolctl
    sets the limit for the call and restores it after.
    """
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api='blas'):
            return func(*args, **kwargs)
    return wrapper
