"""The step response of a nonlinear system, `step_response`: the
counterpart of ``ct.step_response`` for a sandwich, whose response
depends on the step's height."""

import numpy as np
import control as ct

from .._checks import (check_finite, check_finite_system, check_timepts,
                       check_vector, MOST_SAMPLES)

__all__ = ['step_response']


def step_response(sys, timepts=None, amplitude=1.0, initial_state=None):
    r"""Response of a sandwich (or compensator) to a step of given height.

    The nonlinear counterpart of ``ct.step_response``: the response of a
    system with a backlash depends on the step's height (a step smaller
    than the dead band moves nothing), so `amplitude` is an argument, and
    the time points are chosen from the linear blocks when not given.

    Parameters
    ----------
    sys : SandwichSystem or SandwichCompensator or control.InputOutputSystem
        A single-input system. sandwichctl's systems are simulated with
        their compiled ``simulate``; any other discrete python-control
        system with ``ct.input_output_response``.
    timepts : array_like or float, optional
        Time points (evenly spaced by ``sys.dt``), or the final time. By
        default, long enough for the slowest pole of the linear blocks to
        decay to 0.1% (at least 20 samples, at most 10,000; 100 samples
        past the delays if a block has an integrator or is unstable).
    amplitude : float, optional
        Height of the step applied at t = 0 (default 1).
    initial_state : array_like, optional
        Initial state (default zeros: the system at rest).

    Returns
    -------
    control.TimeResponseData
        As from `SandwichSystem.simulate`; ``resp.plot()`` draws it.

    Raises
    ------
    TypeError
        If `sys` is not a single-input python-control system.
    ValueError
        If `sys` is a linear system with NaN or inf coefficients,
        `amplitude` is not finite, the time points are not spaced by dt,
        or no time points are given for a system whose settling time
        cannot be told.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> small = sw.step_response(plant, timepts=range(5), amplitude=0.2)
    >>> print(small.outputs)                  # inside the dead band
    [0. 0. 0. 0. 0.]
    >>> resp = sw.step_response(plant, amplitude=2.0)
    >>> resp.time.size, round(float(resp.outputs[-1]), 2)
    (34, 1.88)
    """
    if not isinstance(sys, ct.InputOutputSystem) or sys.ninputs != 1:
        raise TypeError(
            f"sys must be a single-input python-control system (e.g. a "
            f"sw.SandwichSystem); got {type(sys).__name__}"
            + (f" with {sys.ninputs} inputs"
               if isinstance(sys, ct.InputOutputSystem) else ""))
    if not sys.isdtime(strict=True):
        raise ValueError(f"sys must be discrete-time; got dt={sys.dt!r}. "
                         f"For a continuous system use ct.step_response")
    check_finite_system('sys', sys)
    amplitude = check_finite('amplitude', amplitude)
    step = 1.0 if sys.dt is True else float(sys.dt)
    if timepts is None:
        settle = getattr(sys, '_settling_samples', None)
        if settle is None and isinstance(sys, ct.LTI):
            timepts = ct.step_response(sys).time
        elif settle is None:
            raise ValueError(
                f"timepts is required for a {type(sys).__name__}: its "
                f"settling time cannot be told from linear blocks")
        else:
            timepts = step * np.arange(settle())
    elif np.ndim(timepts) == 0:
        tfinal = check_finite('timepts', timepts)
        if not 0 <= tfinal / step < MOST_SAMPLES:
            raise ValueError(f"timepts (a final time) must be in [0, "
                             f"{MOST_SAMPLES:.0e} dt); got {tfinal}")
        timepts = step * np.arange(int(np.floor(tfinal / step + 1e-9)) + 1)
    else:
        timepts = check_vector('timepts', timepts)
        timepts = check_timepts('timepts', timepts, timepts.size, sys.dt)
    u = np.full(len(timepts), amplitude)
    x0 = 0 if initial_state is None else initial_state
    if hasattr(sys, 'simulate'):
        resp = sys.simulate(u, initial_state=initial_state, timepts=timepts)
    elif isinstance(sys, ct.LTI):
        resp = ct.forced_response(sys, timepts, u, x0)
    else:
        resp = ct.input_output_response(sys, timepts, u, x0)
    resp.title = f"Step response of {sys.name} (amplitude {amplitude:g})"
    return resp
