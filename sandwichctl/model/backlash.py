r"""The backlash-like hysteresis of eq. (2.2), as a pure function and as a
python-control nonlinear I/O system.

Eq. (2.2) with the switching functions of eq. (2.4) reads

.. math::

    v(k) = \begin{cases}
      m_1 (x(k) - D_1) & x(k) > v(k-1)/m_1 + D_1 \text{ and } x(k) > x(k-1)
                         \quad\text{(increase zone)}\\
      m_2 (x(k) + D_2) & x(k) < v(k-1)/m_2 - D_2 \text{ and } x(k) < x(k-1)
                         \quad\text{(decrease zone)}\\
      v(k-1)           & \text{otherwise} \quad\text{(memory zone)}
    \end{cases}

`backlash_step` is the only implementation of this equation in the
package; the python-control system, the simulation kernel, the
identifiers and the compensator all call it.

Crossing slope lines
--------------------
When :math:`m_1 \ne m_2` the lines :math:`v = m_1(x - D_1)` and
:math:`v = m_2(x + D_2)` meet at

.. math:: x^\ast = \frac{m_1 D_1 + m_2 D_2}{m_1 - m_2}.

On the far side of :math:`x^\ast` (:math:`x < x^\ast` if :math:`m_1 < m_2`,
:math:`x > x^\ast` if :math:`m_1 > m_2`) the increase line lies *above*
the decrease line and the band between them is empty. Eq. (2.2) stays
well defined there because each zone also asks for the direction of
motion: a rising input follows the increase line, a falling one the
decrease line, and v(k) jumps between the lines when the direction
reverses. The clamp form ``clip(v(k-1), m1*(x-D1), m2*(x+D2))`` agrees
with eq. (2.2) only where :math:`m_1(x-D_1) \le m_2(x+D_2)`; sandwichctl
always follows eq. (2.2). See `Backlash.crossing`.
"""

import math

import numba
import numpy as np
import control as ct

from .._checks import (check_positive, check_nonnegative, check_signal,
                       check_finite, check_bool, check_dt, check_name,
                       check_label, check_labels, named_copy,
                       warn_overflow)

__all__ = ['Backlash', 'backlash_response', 'INCREASE', 'MEMORY', 'DECREASE']

#: Zone codes returned by `backlash_response` (eq. (2.2)).
INCREASE, MEMORY, DECREASE = 1, 0, -1


@numba.njit(cache=True, inline='always')
def backlash_step(x, x_prev, v_prev, m1, m2, D1, D2):
    """One step of eq. (2.2): return ``(v, zone)``.

    `zone` is 1 in the increase zone, -1 in the decrease zone and 0 in the
    memory zone (eq. (2.4): g1 = 1, g2 = 1, or neither).
    """
    if x > x_prev and x > v_prev / m1 + D1:
        return m1 * (x - D1), 1
    if x < x_prev and x < v_prev / m2 - D2:
        return m2 * (x + D2), -1
    return v_prev, 0


@numba.njit(cache=True)
def _backlash_loop(x, m1, m2, D1, D2, x_prev, v_prev, v, zone):
    for k in range(x.size):
        v_prev, z = backlash_step(x[k], x_prev, v_prev, m1, m2, D1, D2)
        x_prev = x[k]
        v[k] = v_prev
        zone[k] = z


def backlash_response(x, m1, m2, D1, D2, x_prev=0.0, v_prev=0.0,
                      return_zones=False):
    """Backlash output for a whole input sequence (eq. (2.2)).

    Parameters
    ----------
    x : array_like, shape (N,)
        Backlash input x(0), ..., x(N-1).
    m1, m2 : float
        Slopes of the increase and decrease lines, 0 < m < inf.
    D1, D2 : float
        Thresholds (half-widths) of the increase and decrease lines, >= 0.
    x_prev, v_prev : float, optional
        The memory: x(-1) and v(-1). Default 0, 0.
    return_zones : bool, optional
        Also return the zone of every sample (1 increase, 0 memory,
        -1 decrease).

    Returns
    -------
    v : ndarray, shape (N,)
        Backlash output.
    zones : ndarray of int8, shape (N,)
        Only if `return_zones` is True.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.backlash_response([0.0, 1.0, 2.0, 1.5, 0.0], 1, 1, 0.5, 0.5)
    array([0. , 0.5, 1.5, 1.5, 0.5])
    """
    m1 = check_positive('m1', m1)
    m2 = check_positive('m2', m2)
    D1 = check_nonnegative('D1', D1)
    D2 = check_nonnegative('D2', D2)
    x = check_signal('x', x)
    x_prev = check_finite('x_prev', x_prev)
    v_prev = check_finite('v_prev', v_prev)
    return_zones = check_bool('return_zones', return_zones)
    v = np.empty_like(x)
    zones = np.empty(x.size, dtype=np.int8)
    _backlash_loop(x, m1, m2, D1, D2, x_prev, v_prev, v, zones)
    warn_overflow(v, "the backlash output", "(m1 * x or m2 * x beyond "
                  "1.8e308): rescale x or the slopes")
    return (v, zones) if return_zones else v


def _backlash_functions(m1, m2, D1, D2):
    """Update and output functions of one backlash (parameters fixed)."""
    def update(t, state, inp, params):
        x, x_prev, v_prev = finite_step(t, inp, state)
        v, _ = backlash_step(x, x_prev, v_prev, m1, m2, D1, D2)
        return np.array([x, v])

    def output(t, state, inp, params):
        v, _ = backlash_step(*finite_step(t, inp, state), m1, m2, D1, D2)
        return np.array([v])
    return update, output


def finite_step(t, inp, state):
    """(x, x_prev, v_prev): a backlash block's input and memory through
    python-control (at time t), as floats; one not finite raises (a NaN
    would stick in the memory, or make python-control report an algebraic
    loop)."""
    x = float(inp[0])
    if not math.isfinite(x):
        raise ValueError(f"an input of the backlash is not finite ({x!r}); "
                         f"its memory cannot hold it")
    x_prev, v_prev = float(state[0]), float(state[1])
    if not (math.isfinite(x_prev) and math.isfinite(v_prev)):
        raise ValueError(f"the memory of a backlash block (x_prev, v_prev) "
                         f"is not finite at t={t!r}: ({x_prev!r}, "
                         f"{v_prev!r}); give a finite initial state (X0)")
    return x, x_prev, v_prev


class Backlash(ct.NonlinearIOSystem):
    r"""Backlash-like hysteresis of eq. (2.2) as a discrete-time I/O system.

    The system has one input x, one output v and two states that hold the
    memory, x(k-1) and v(k-1). Its output is a pure function of (state,
    input), so python-control may evaluate it as often as it likes; the
    memory is set with ``initial_state`` like any other state.

    Parameters
    ----------
    m1, m2 : float
        Slopes of the increase and decrease lines, 0 < m1, m2 < inf.
    D1, D2 : float
        Thresholds of the increase and decrease lines, 0 <= D < inf. The
        increase line is v = m1 (x - D1), the decrease line v = m2 (x + D2).
    dt : float or True, optional
        Sampling time; True (default) means discrete with unspecified
        sampling time, which adopts the sampling time of the systems it is
        connected to.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'x' and 'v'.
    states : list of str, optional
        State names; default ['x_prev', 'v_prev'].

    Raises
    ------
    TypeError
        If a parameter is not a real number (a boolean, a string, None),
        `name` is not a string, or a signal name is not a string.
    ValueError
        If a parameter is out of range or not finite, `dt` is not a
        finite positive number or True, or two input names are given for
        the one input.

    See Also
    --------
    backlash_response : the same map over a whole sequence.
    SandwichSystem : L1, this backlash, and L2 in series.

    Notes
    -----
    Where the slope lines cross (m1 != m2) the model follows eq. (2.2)
    exactly; see `crossing` and the module notes.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> bl = sw.Backlash(1.0, 1.0, 0.5, 0.5, dt=1)
    >>> resp = ct.input_output_response(bl, np.arange(5), [0, 1, 2, 1.5, 0])
    >>> print(resp.outputs)
    [0.  0.5 1.5 1.5 0.5]
    """

    def __init__(self, m1, m2, D1, D2, dt=True, name=None, inputs='x',
                 outputs='v', states=('x_prev', 'v_prev')):
        self._values = (check_positive('m1', m1), check_positive('m2', m2),
                        check_nonnegative('D1', D1),
                        check_nonnegative('D2', D2))
        dt = check_dt('dt', dt)
        name = check_name('name', name)
        inputs = check_label('inputs', inputs, 'input')
        outputs = check_label('outputs', outputs, 'output')
        states = check_labels('states', states, 2)
        update, output = _backlash_functions(*self._values)
        super().__init__(update, output, inputs=inputs, outputs=outputs,
                         states=states, dt=dt, name=name)

    copy = named_copy            # its name checked

    def __reduce__(self):
        # The update and output functions are closures, which pickle
        # cannot store: rebuild from the parameters and the names instead.
        return (type(self), (*self._values, self.dt, self.name,
                             self.input_labels[0], self.output_labels[0],
                             list(self.state_labels)))

    # Read-only parameters. They are not python-control ``params``: an
    # interconnection merges the params of all its blocks into one dict,
    # so two backlashes (a plant and its model, say) would silently share
    # one set of parameters.
    m1 = property(lambda self: self._values[0], doc="Increase slope.")
    m2 = property(lambda self: self._values[1], doc="Decrease slope.")
    D1 = property(lambda self: self._values[2], doc="Increase threshold.")
    D2 = property(lambda self: self._values[3], doc="Decrease threshold.")

    @property
    def crossing(self):
        """The x where the two slope lines cross, or None if m1 == m2.

        Beyond this point the band between the lines is empty and eq. (2.2)
        switches between the lines with the direction of motion.
        """
        if self.m1 == self.m2:
            return None
        return ((self.m1 * self.D1 + self.m2 * self.D2)
                / (self.m1 - self.m2))

    def response(self, x, x_prev=0.0, v_prev=0.0, return_zones=False):
        """Output for a whole input sequence; see `backlash_response`."""
        return backlash_response(x, self.m1, self.m2, self.D1, self.D2,
                                 x_prev, v_prev, return_zones)

    def copy_with(self, **changes):
        """Return a new Backlash with some of m1, m2, D1, D2 changed.

        The sampling time, the name and the signal names are kept.
        """
        values = dict(zip(('m1', 'm2', 'D1', 'D2'), self._values))
        unknown = set(changes) - set(values)
        if unknown:
            raise TypeError(f"unknown backlash parameter(s) {sorted(unknown)};"
                            f" expected some of m1, m2, D1, D2")
        values.update(changes)
        return type(self)(dt=self.dt, name=self.name,
                          inputs=self.input_labels[0],
                          outputs=self.output_labels[0],
                          states=list(self.state_labels), **values)

    def __repr__(self):
        return (f"Backlash(m1={self.m1:.6g}, m2={self.m2:.6g}, "
                f"D1={self.D1:.6g}, D2={self.D2:.6g}, dt={self.dt!r}, "
                f"name={self.name!r})")

    def __str__(self):
        return (f"<Backlash>: {self.name}\n"
                f"  v = m1 (x - D1) rising, v = m2 (x + D2) falling, "
                f"else held (eq. 2.2)\n"
                f"  m1 = {self.m1:.6g}, m2 = {self.m2:.6g}, "
                f"D1 = {self.D1:.6g}, D2 = {self.D2:.6g}\n"
                f"  dt = {self.dt}")
