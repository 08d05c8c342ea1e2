"""Argument checks shared by the public functions (private module).

Every check raises ``ValueError`` or ``TypeError`` with a message that
names the argument, says what was received and what is expected.
"""

import numbers

import numpy as np
import control as ct

__all__ = []


def check_positive(name, value):
    """Return `value` as float, requiring 0 < value < inf."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value) or value <= 0:
        raise ValueError(
            f"{name} must be a finite number > 0; got {value!r}")
    return value


def check_nonnegative(name, value):
    """Return `value` as float, requiring 0 <= value < inf."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value) or value < 0:
        raise ValueError(
            f"{name} must be a finite number >= 0; got {value!r}")
    return value


def check_finite(name, value):
    """Return `value` as float, requiring it to be finite."""
    value = _as_real_scalar(name, value)
    if not np.isfinite(value):
        raise ValueError(f"{name} must be finite; got {value!r}")
    return value


def check_int(name, value, minimum=0):
    """Return `value` as int, requiring an integer >= `minimum`."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(
            f"{name} must be an integer >= {minimum}; got "
            f"{type(value).__name__} {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}; "
                         f"got {value}")
    return int(value)


def check_signal(name, values, length=None):
    """Return a finite 1-D float array, rejecting other shapes and NaN/inf.

    A scalar is not accepted: signals are sequences of samples.
    """
    if _is_str(values):
        raise TypeError(f"{name} must be an array of numbers; got a string")
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be an array of numbers; got "
                        f"{type(values).__name__}") from None
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()          # a row or column vector is fine
    if arr.ndim != 1:
        raise ValueError(
            f"{name} must be a 1-D array of samples; got shape {arr.shape}")
    if arr.size == 0:
        raise ValueError(f"{name} must contain at least one sample; got 0")
    if length is not None and arr.size != length:
        raise ValueError(
            f"{name} must have {length} samples; got {arr.size}")
    bad = ~np.isfinite(arr)
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise ValueError(
            f"{name} must be finite; sample {first} is {float(arr[first])}")
    return np.ascontiguousarray(arr)


def check_vector(name, values, length):
    """Return a finite 1-D float array of exactly `length` entries."""
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1 or arr.size != length:
        raise ValueError(
            f"{name} must be a 1-D array of length {length}; "
            f"got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite; got {arr}")
    return arr.copy()


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
    num = np.trim_zeros(np.atleast_1d(np.asarray(sys.num[0][0], float)), 'f')
    den = np.trim_zeros(np.atleast_1d(np.asarray(sys.den[0][0], float)), 'f')
    if num.size == 0:
        raise ValueError(f"{name} has a zero numerator; a sandwich block "
                         f"must pass its input on")
    if num.size > den.size:
        raise ValueError(
            f"{name} is improper (numerator degree {num.size - 1} > "
            f"denominator degree {den.size - 1}); a causal difference "
            f"equation needs deg(num) <= deg(den)")
    if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        raise ValueError(f"{name} has non-finite coefficients")
    return num / den[0], den / den[0]


def common_dt(name1, dt1, name2, dt2):
    """Return the common sampling time of two discrete systems."""
    if dt1 is True:
        return dt2
    if dt2 is True or dt1 == dt2:
        return dt1
    raise ValueError(
        f"{name1} and {name2} must have the same sampling time; got "
        f"dt={dt1!r} and dt={dt2!r}")


def _as_real_scalar(name, value):
    if isinstance(value, bool) or not isinstance(
            value, (numbers.Real, np.floating, np.integer)):
        arr = np.asarray(value) if not _is_str(value) else None
        if arr is None or arr.ndim != 0 or not np.isrealobj(arr):
            raise TypeError(f"{name} must be a real number; got "
                            f"{type(value).__name__} {value!r}")
        value = arr.item()
    return float(value)


def _is_str(value):
    return isinstance(value, (str, bytes))


def check_dt(name, dt):
    """A discrete sampling time: a positive number or True (unspecified)."""
    if dt is None or dt is False or (dt is not True and not dt > 0):
        raise ValueError(f"{name} must be a positive sampling time or True "
                         f"(discrete, unspecified); got {dt!r}. The backlash "
                         f"and its inverse are discrete-time maps")
    return dt
