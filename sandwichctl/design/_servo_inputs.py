"""What `servo_controller` accepts as its model: an identification
result is unwrapped to its model, and a transfer function is checked for
a design (discrete, SISO, strictly proper, stable or with one integrator,
and a gain the design's squares do not overflow)."""

import numpy as np
import control as ct

from . import _servo_design as sd
from ..model.sandwich import SandwichSystem
from .._checks import DATA_RANGE

__all__ = []


def unwrap_model(model):
    """The model of a result, and the result itself (or None)."""
    inner = getattr(model, 'model', None)
    if isinstance(inner, (SandwichSystem, ct.TransferFunction)) and \
            not isinstance(model, (SandwichSystem, ct.TransferFunction)):
        return inner, model
    return model, None


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
    gain = np.max(np.abs(num)) / np.max(np.abs(den))
    lo, hi = DATA_RANGE
    if not lo <= gain <= hi:
        what = 'overflow' if gain > hi else 'underflow'
        raise ValueError(
            f"{name} has a gain of order {gain:.1e} (largest numerator "
            f"over largest denominator coefficient), outside {lo:g} .. "
            f"{hi:g}: the design squares it, which would {what} double "
            f"precision; rescale u or y (other units)")
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
