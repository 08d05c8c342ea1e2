r"""The sandwich system L1 -> backlash -> L2 of Section 2.

Mapping between eq. (2.1) and python-control
--------------------------------------------
Eq. (2.1) writes L1 as the difference equation

.. math:: x(k) = -\sum_{i=1}^{n_a} a_i x(k-i)
                 + \sum_{j=0}^{n_b} b_j u(k-q_1-j),

which is the transfer function, in python-control's descending powers
of z, with :math:`n = \max(n_a, q_1 + n_b)`,

.. math:: L_1(z) = \frac{b_0 z^{n-q_1} + b_1 z^{n-q_1-1} + \dots
                         + b_{n_b} z^{n-q_1-n_b}}
                        {z^n + a_1 z^{n-1} + \dots + a_{n_a} z^{n-n_a}}.

So the delay :math:`q_1` is the relative degree (a pole at zero per
sample of delay), :math:`b_0` is the leading non-zero numerator
coefficient and trailing zeros of either polynomial are dropped. The
paper's :math:`x(k) = -0.1x(k-1) - 0.2x(k-2) + 1.5u(k-1)` is
``ct.tf([1.5, 0], [1, 0.1, 0.2], dt)``: note the trailing 0, since
``[1.5]`` alone would mean two samples of delay. L2 maps v to y the same
way with :math:`(c, d, q_2)` in place of :math:`(a, b, q_1)`.
"""

import numbers

import numpy as np
import control as ct

from .backlash import Backlash
from ._kernel import (simulate_kernel, companion_kernel, batch_kernel,
                      companion_form, batch_signals, theta_batch,
                      SimulationResponse)
from ._coefficients import (declare_orders, difference_coefficients,
                           difference_equation, tf_from_coefficients,
                           tf_to_ss, signed_theta, SignedTheta)
from .._checks import (check_discrete_siso_tf, check_order, check_signal,
                       check_vector, common_dt, check_name, check_label,
                       check_bool, check_dt, check_option, check_timepts,
                       named_copy, warn, SimulationWarning)

__all__ = ['SandwichSystem', 'theta_labels']

#: The keys `SandwichSystem.copy_with` accepts besides the blocks.
_BACKLASH_KEYS = ('m1', 'm2', 'D1', 'D2')
_COEFFICIENT_KEYS = ('a', 'b', 'c', 'd', 'q1', 'q2') + _BACKLASH_KEYS


class SandwichSystem(ct.InterconnectedSystem):
    r"""Sandwich system: linear L1, backlash (eq. (2.2)), linear L2.

    The object *is* a python-control interconnected I/O system (input 'u',
    output 'y'), so ``ct.input_output_response``, ``ct.interconnect`` and
    ``ct.feedback`` accept it. Its state vector is
    ``[L1 states, x(k-1), v(k-1), L2 states]`` where the L1 and L2 states
    are those of ``ct.ss(L1)`` and ``ct.ss(L2)``; see `state_labels`.

    Parameters
    ----------
    L1, L2 : control.TransferFunction
        SISO, proper, discrete-time transfer functions with the same dt.
        L1 maps u to x and L2 maps v to y.
    backlash : Backlash
        The backlash between them. Its dt must agree (or be True).
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Names of the input and output signals (default 'u' and 'y').
    orders : dict, optional
        Declared orders of eq. (2.1), a dict with some of na, nb, nc, nd
        (and q1, q2, which must match the transfer functions): the
        coefficient vectors are padded with zeros up to them, so that
        `theta` has the length an identifier with these orders uses.
        Default: the orders read from L1 and L2.

    Attributes
    ----------
    L1, L2 : control.TransferFunction
        The linear blocks, as given.
    backlash : Backlash
        The backlash block.
    orders : dict
        na, nb, nc, nd, q1, q2 read from L1 and L2 (eq. (2.1)).

    See Also
    --------
    SandwichSystem.from_coefficients : build from the paper's coefficients.
    SandwichSystem.from_theta : build from the parameter vector (2.5).
    step_response : step response with a chosen amplitude.

    Notes
    -----
    The system is nonlinear, so python-control's linear-only functions
    (``ct.poles``, ``ct.bode_plot``, ``ct.dcgain``, ...) do not apply to
    it; they do apply to `L1` and `L2`. ``ct.step_response(plant,
    timepts)`` works but needs explicit time points and gives the unit
    step only: with a backlash the response depends on the amplitude (a
    step smaller than the dead band moves nothing), so use
    ``sw.step_response(plant, amplitude=...)``.

    The object pickles (``pickle``, ``copy.deepcopy``) with its name,
    signal names and declared orders; the copy simulates bit for bit like
    the original.

    Examples
    --------
    >>> import control as ct, sandwichctl as sw
    >>> L1 = ct.tf([1.5, 0], [1, 0.1, 0.2], 1)
    >>> L2 = ct.tf([2, -0.1], [1, 1.2, 0.32], 1)
    >>> plant = sw.SandwichSystem(L1, sw.Backlash(1, 1.2, 0.5, 0.6), L2)
    >>> plant.orders
    {'na': 2, 'nb': 0, 'nc': 2, 'nd': 1, 'q1': 1, 'q2': 1}
    >>> print(plant)  # doctest: +NORMALIZE_WHITESPACE
    SandwichSystem sys...: u -> y, dt = 1
      L1: x(k) = -0.1 x(k-1) - 0.2 x(k-2) + 1.5 u(k-1)
      B:  v(k) = backlash(x(k)) with m1 = 1, m2 = 1.2, D1 = 0.5, D2 = 0.6
      L2: y(k) = -1.2 y(k-1) - 0.32 y(k-2) + 2 v(k-1) - 0.1 v(k-2)
    >>> plant.normalized().theta.round(4)
    array([ 1.2   ,  0.32  ,  0.1   ,  0.2   ,  3.    ,  3.6   ,  0.3333,
            0.4   , -0.05  ])
    """

    def __init__(self, L1, backlash, L2, name=None, inputs='u', outputs='y',
                 orders=None):
        num1, den1 = check_discrete_siso_tf('L1', L1)
        num2, den2 = check_discrete_siso_tf('L2', L2)
        name = check_name('name', name)
        inputs = check_label('inputs', inputs, 'input')
        outputs = check_label('outputs', outputs, 'output')
        if not isinstance(backlash, Backlash):
            raise TypeError(
                f"backlash must be a sandwichctl.Backlash (e.g. "
                f"sw.Backlash(m1, m2, D1, D2)); got {type(backlash).__name__}")
        dt = common_dt('L1', L1.dt, 'L2', L2.dt)
        dt = common_dt('L1/L2', dt, 'backlash', backlash.dt)
        self._L1, self._L2 = L1, L2
        self._coef1 = difference_coefficients(num1, den1)
        self._coef2 = difference_coefficients(num2, den2)
        if orders is not None:
            self._coef1, self._coef2 = declare_orders(
                orders, self._coef1, self._coef2)
        bl = Backlash(backlash.m1, backlash.m2, backlash.D1, backlash.D2,
                      dt=dt, name='backlash')
        self._backlash_values = bl._values
        ss1 = tf_to_ss(L1, inputs='u', outputs='x', name='L1')
        ss2 = tf_to_ss(L2, inputs='v', outputs='y', name='L2')
        self._matrices = tuple(
            np.ascontiguousarray(np.asarray(M, dtype=float))
            for sys in (ss1, ss2) for M in (sys.A, sys.B, sys.C, sys.D))
        super().__init__(
            [ss1, bl, ss2],
            connections=[['backlash.x', 'L1.x'], ['L2.v', 'backlash.v']],
            inplist=['L1.u'], outlist=['L2.y'], inputs=inputs,
            outputs=outputs, dt=dt, name=name)

    copy = named_copy            # its name checked

    def __reduce__(self):
        # python-control's state-space blocks hold closures, which pickle
        # cannot store: rebuild from plain data instead (the transfer
        # functions, the backlash parameters, the names, the orders).
        return (_rebuild_sandwich, (type(self), self._L1, self._L2,
                                    self._backlash_values, self.dt,
                                    self.name, self.input_labels[0],
                                    self.output_labels[0], self.orders))

    def _settling_samples(self):
        """Samples for the slowest linear mode to settle (step_response)."""
        return _settling_samples([self._L1, self._L2],
                                 self._coef1[2] + self._coef2[2])

    # ------------------------------------------------------------------
    # Parts and parametrisation
    # ------------------------------------------------------------------
    @property
    def L1(self):
        """Input linear block u -> x (a ct.TransferFunction)."""
        return self._L1

    @property
    def L2(self):
        """Output linear block v -> y (a ct.TransferFunction)."""
        return self._L2

    @property
    def backlash(self):
        """The backlash block (a sw.Backlash)."""
        return Backlash(*self._backlash_values, dt=self.dt)

    @property
    def coefficients(self):
        """Coefficients of eq. (2.1) as a dict.

        Keys a, b, c, d (arrays, ``b[0]`` = b0 and ``d[0]`` = d0), q1, q2
        and the backlash parameters m1, m2, D1, D2.
        """
        a, b, q1 = self._coef1
        c, d, q2 = self._coef2
        m1, m2, D1, D2 = self._backlash_values
        return {'a': a.copy(), 'b': b.copy(), 'c': c.copy(), 'd': d.copy(),
                'q1': q1, 'q2': q2, 'm1': m1, 'm2': m2, 'D1': D1, 'D2': D2}

    @property
    def orders(self):
        """Orders and delays of eq. (2.1): dict with na, nb, nc, nd, q1, q2.

        nb and nd count the coefficients after b0 and d0, as in eq. (2.1).
        """
        a, b, q1 = self._coef1
        c, d, q2 = self._coef2
        return {'na': a.size, 'nb': b.size - 1, 'nc': c.size,
                'nd': d.size - 1, 'q1': q1, 'q2': q2}

    @property
    def gain_sign(self):
        """Sign of the overall gain, +1 or -1 (the sign of b0 * d0).

        The backlash has positive slopes, so the sign of the whole
        sandwich is the sign of the product of the leading coefficients of
        L1 and L2.
        """
        return 1 if self._coef1[1][0] * self._coef2[1][0] > 0 else -1

    def poles(self):
        """The poles of L1 and of L2 (the backlash is static, with
        memory), so ``ct.poles(sys)`` works.

        >>> import sandwichctl as sw
        >>> sw.examples.paper_plant().poles().size
        4
        """
        return np.concatenate([self._L1.poles(), self._L2.poles()])

    def zeros(self):
        """The zeros of L1 and of L2 (``ct.zeros(sys)``)."""
        return np.concatenate([self._L1.zeros(), self._L2.zeros()])

    def dcgain(self):
        """Refused, with the reason: a sandwich has no single DC gain.

        At rest after a constant u, y depends on the way it came: where
        x stopped inside the dead band, after any overshoot, holds v. The
        linear model an engineer designs for is
        ``sw.linearized_plant(sys)`` (the mean slope), whose
        ``ct.dcgain`` is the large-signal gain.

        >>> import control as ct, sandwichctl as sw
        >>> plant = sw.examples.paper_plant()
        >>> round(float(ct.dcgain(sw.linearized_plant(plant))), 3)
        0.957
        """
        raise TypeError(
            f"{self.name} has no single DC gain: at rest, y depends on the "
            f"way it came across the backlash's dead band; "
            f"ct.dcgain(sw.linearized_plant(sys)) is the large-signal gain "
            f"of its mean slope")

    @property
    def is_normalized(self):
        """True if b0 = 1 and d0 = +1 or -1 (the signed normalisation)."""
        return self._coef1[1][0] == 1.0 and abs(self._coef2[1][0]) == 1.0

    def normalized(self):
        """Equivalent system with b0 = 1 and d0 = ±1 (Sections 2 and 5).

        The gains are absorbed into the backlash: with ``x = b0 x'`` and
        ``y = L2'[d0 v]``, the slopes become ``m * abs(b0) * abs(d0)`` and
        the thresholds ``D / abs(b0)``. If b0 < 0 the mirror symmetry
        ``B(m1, m2, D1, D2)(-x) = -B(m2, m1, D2, D1)(x)`` swaps the two
        lines. The sign of the overall gain stays in d0 (`gain_sign`): a
        positive-gain system gets the paper's b0 = d0 = 1, a negative-gain
        one b0 = 1, d0 = -1. From zero initial state, the output is the
        same as the original's; the name, the signal names and the
        declared orders are kept.

        Examples
        --------
        >>> import control as ct, sandwichctl as sw
        >>> plant = sw.SandwichSystem(ct.tf([0.5, 0], [1, -0.5], 1),
        ...                           sw.Backlash(1, 1, 0.2, 0.2),
        ...                           ct.tf([-2], [1, 0.3], 1), name='axis')
        >>> norm = plant.normalized()
        >>> norm.coefficients['d'], norm.gain_sign, norm.name
        (array([-1.]), -1, 'axis')
        """
        co = self.coefficients
        b0, d0 = co['b'][0], co['d'][0]
        m1, m2, D1, D2 = co['m1'], co['m2'], co['D1'], co['D2']
        if b0 < 0:
            m1, m2, D1, D2 = m2, m1, D2, D1
        sb, sd = abs(b0), abs(d0)
        with np.errstate(over='ignore', under='ignore'):
            m1, m2 = m1 * sb * sd, m2 * sb * sd
        if not (np.isfinite(m1) and np.isfinite(m2) and m1 > 0 < m2):
            raise ValueError(f"the normalised slopes m * |b0| * |d0| leave a "
                             f"float (b0 = {b0:.3g}, d0 = {d0:.3g}): rescale "
                             f"L1's and L2's gains")
        return SandwichSystem.from_coefficients(
            a=co['a'], b=co['b'] / b0, c=co['c'],
            d=co['d'] / sd * (1.0 if b0 > 0 else -1.0),
            m1=m1, m2=m2, D1=D1 / sb, D2=D2 / sb,
            q1=co['q1'], q2=co['q2'], dt=self.dt, name=self.name,
            inputs=self.input_labels[0], outputs=self.output_labels[0])

    def copy_with(self, **changes):
        """Return a new SandwichSystem with some parts or coefficients changed.

        For example a perturbed plant for a robustness check:
        ``plant.copy_with(D1=1.2 * plant.backlash.D1)``.

        Parameters
        ----------
        **changes
            Any of the coefficients of eqs. (2.1)-(2.2), as in
            `coefficients`: a, b, c, d, q1, q2, m1, m2, D1, D2; or whole
            blocks: L1, L2 (``ct.TransferFunction``), backlash (a
            `Backlash`); and name. Blocks and coefficients cannot be
            changed in one call.

        Returns
        -------
        SandwichSystem
            The sampling time, the signal names, the name (unless given)
            and the declared orders are kept; a changed coefficient array
            declares its own order.

        Examples
        --------
        >>> import sandwichctl as sw
        >>> plant = sw.examples.paper_plant()
        >>> wider = plant.copy_with(D1=0.6, D2=0.7, name='wider')
        >>> wider.coefficients['D1'], wider.coefficients['D2']
        (0.6, 0.7)
        >>> wider.L1 is plant.L1, wider.name
        (True, 'wider')
        """
        blocks = sorted(set(changes) & {'L1', 'L2', 'backlash'})
        coefs = sorted(set(changes) & set(_COEFFICIENT_KEYS))
        unknown = sorted(set(changes) - set(blocks) - set(coefs) - {'name'})
        if unknown:
            raise TypeError(
                f"copy_with got unknown key(s) {unknown}; expected some of "
                f"{', '.join(_COEFFICIENT_KEYS)}, L1, L2, backlash, name")
        if blocks and coefs:
            raise ValueError(f"copy_with got blocks {blocks} and coefficients "
                             f"{coefs}; change one kind or the other")
        labels = dict(name=changes.pop('name', self.name),
                      inputs=self.input_labels[0],
                      outputs=self.output_labels[0])
        if not set(coefs) <= set(_BACKLASH_KEYS):
            co = self.coefficients
            co.update(changes)
            return type(self).from_coefficients(dt=self.dt, **co, **labels)
        backlash = (self.backlash.copy_with(**changes) if coefs else
                    changes.get('backlash', self.backlash))
        L1, L2 = changes.get('L1', self.L1), changes.get('L2', self.L2)
        keep = (['na', 'nb'] if L1 is self.L1 else []) + (
            ['nc', 'nd'] if L2 is self.L2 else [])
        return type(self)(L1, backlash, L2, **labels,
                          orders={k: self.orders[k] for k in keep} or None)

    @property
    def theta(self):
        """Parameter vector of eq. (2.5) of the normalised system.

        Order: c1..c_nc, a1..a_na, m1, m2, D1, D2, b1..b_nb, d1..d_nd.
        For a positive gain this is the paper's theta (b0 = d0 = 1), a
        plain array. For a negative gain (`gain_sign` = -1) it is the same
        vector of the signed normalisation b0 = 1, d0 = -1, where the d_j
        are relative to d0; the vector has no entry for d0, so it is
        returned as an array that carries ``sign = -1`` (it prints as
        ``theta([...], sign=-1)``). Either way
        ``SandwichSystem.from_theta(sys.theta, **sys.orders, dt=sys.dt)``
        rebuilds ``sys.normalized()``. Copies and arithmetic keep the
        sign; ``np.asarray(theta)`` and a file do not, so pass
        ``sign=sys.gain_sign`` to `from_theta` when rebuilding from those.
        """
        sys = self if self.is_normalized else self.normalized()
        co = sys.coefficients
        theta = np.concatenate([co['c'], co['a'],
                                [co['m1'], co['m2'], co['D1'], co['D2']],
                                co['b'][1:], co['d'][1:] * co['d'][0]])
        return signed_theta(theta, self.gain_sign)

    @property
    def theta_labels(self):
        """Names of the entries of `theta`, e.g. ['c1', ..., 'd1']."""
        o = self.orders
        return theta_labels(o['na'], o['nb'], o['nc'], o['nd'])

    @classmethod
    def from_coefficients(cls, a, b, c, d, m1, m2, D1, D2, q1=1, q2=1,
                          dt=True, name=None, inputs='u', outputs='y'):
        """Build a sandwich from the coefficients of eqs. (2.1)-(2.2).

        Parameters
        ----------
        a : array_like
            a_1, ..., a_na of L1 (may be empty).
        b : array_like
            b_0, ..., b_nb of L1; b_0 must be non-zero.
        c : array_like
            c_1, ..., c_nc of L2 (may be empty).
        d : array_like
            d_0, ..., d_nd of L2; d_0 must be non-zero.
        m1, m2, D1, D2 : float
            Backlash parameters (see `Backlash`).
        q1, q2 : int, optional
            Delays of L1 and L2 in samples (default 1).
        dt : float or True, optional
            Sampling time (default True: discrete, unspecified).
        name : str, optional
            System name.
        inputs, outputs : str, optional
            Names of the input and output signals.

        The orders are those of the given coefficient arrays, trailing
        zeros included (see `SandwichSystem`'s ``orders``); the transfer
        functions leave trailing zeros out, so they have no extra poles at
        z = 0.

        Examples
        --------
        >>> import sandwichctl as sw
        >>> plant = sw.SandwichSystem.from_coefficients(
        ...     a=[0.1, 0.2], b=[1.5], c=[1.2, 0.32], d=[2, -0.1],
        ...     m1=1, m2=1.2, D1=0.5, D2=0.6, q1=1, q2=1, dt=1)
        >>> plant.L1.num[0][0], plant.L1.den[0][0]
        (array([1.5, 0. ]), array([1. , 0.1, 0.2]))
        """
        dt = check_dt('dt', dt)
        backlash = Backlash(m1, m2, D1, D2, dt=dt)
        L1, a, b = tf_from_coefficients('a', a, 'b', b, 'q1', q1, dt)
        L2, c, d = tf_from_coefficients('c', c, 'd', d, 'q2', q2, dt)
        orders = {'na': a.size, 'nb': b.size - 1, 'nc': c.size,
                  'nd': d.size - 1}
        return cls(L1, backlash, L2, name=name,
                   inputs=inputs, outputs=outputs, orders=orders)

    @classmethod
    def from_theta(cls, theta, na, nb, nc, nd, q1=1, q2=1, dt=True,
                   name=None, sign=None):
        """Build the normalised sandwich (b0 = 1, d0 = sign) from eq. (2.5).

        The inverse of `theta`: ``SandwichSystem.from_theta(sys.theta,
        **sys.orders, dt=sys.dt)`` is ``sys.normalized()``, for a negative
        gain too (the `theta` of such a system, or of its identification
        result, carries ``sign = -1``).

        Parameters
        ----------
        theta : array_like, shape (nc + na + 4 + nb + nd,)
            c1..c_nc, a1..a_na, m1, m2, D1, D2, b1..b_nb, d1..d_nd.
        na, nb, nc, nd : int
            Orders of eq. (2.1).
        q1, q2 : int, optional
            Delays (default 1).
        dt : float or True, optional
            Sampling time.
        name : str, optional
            System name.
        sign : {1, -1}, optional
            Sign of the overall gain, d0. Default: the sign `theta` carries
            (-1 for the `theta` of a negative-gain system), else 1 (the
            paper's b0 = d0 = 1). A plain array has no sign: pass
            ``sign=-1`` to rebuild a negative-gain system from one.

        Examples
        --------
        >>> import control as ct, sandwichctl as sw
        >>> plant = sw.SandwichSystem(ct.tf([0.5, 0], [1, -0.5], 1),
        ...                           sw.Backlash(1, 1, 0.2, 0.2),
        ...                           ct.tf([-2], [1, 0.3], 1))
        >>> plant.theta
        theta([ 0.3, -0.5,  1. ,  1. ,  0.4,  0.4], sign=-1)
        >>> same = sw.SandwichSystem.from_theta(plant.theta, **plant.orders)
        >>> same.gain_sign, same.coefficients['d']
        (-1, array([-1.]))
        """
        carried = getattr(theta, 'sign', None) if isinstance(
            theta, SignedTheta) else None
        if sign is None:
            sign = 1 if carried is None else carried
        check_option('sign', sign, (1, -1))
        if carried is not None and sign != carried:
            raise ValueError(
                f"sign={sign} but theta comes from a system whose gain has "
                f"sign {carried} (theta carries it); leave sign out, or "
                f"pass np.asarray(theta) to rebuild with another sign")
        na, nb, nc, nd = (check_order(n, v) for n, v in
                          zip(('na', 'nb', 'nc', 'nd'), (na, nb, nc, nd)))
        theta = check_vector('theta', theta, nc + na + 4 + nb + nd)
        c, a = theta[:nc], theta[nc:nc + na]
        m1, m2, D1, D2 = theta[nc + na:nc + na + 4]
        b = np.concatenate([[1.0], theta[nc + na + 4:nc + na + 4 + nb]])
        d = sign * np.concatenate([[1.0], theta[nc + na + 4 + nb:]])
        return cls.from_coefficients(a, b, c, d, m1, m2, D1, D2, q1, q2,
                                     dt=dt, name=name)

    # ------------------------------------------------------------------
    # Simulation
    # ------------------------------------------------------------------
    def simulate(self, inputs, initial_state=None, timepts=None,
                 internal=False, return_states=False):
        """Fast simulation of the sandwich (compiled kernel).

        Gives the same result as ``ct.input_output_response(self, timepts,
        inputs, initial_state)`` (to rounding), about four orders of
        magnitude faster.

        Parameters
        ----------
        inputs : array_like, shape (N,)
            Input u(0), ..., u(N-1).
        initial_state : array_like or None, optional
            Full state at k = 0, laid out as `state_labels` says:
            ``[L1 states, x(-1), v(-1), L2 states]``. Default zeros.
        timepts : array_like, optional
            Time points, only used to label the result; default
            ``dt * arange(N)``. They must be evenly spaced by dt (one per
            sample); other time points raise ValueError.
        internal : bool, optional
            If True, the outputs are the three signals y, x and v (rows in
            that order); otherwise just y.
        return_states : bool, optional
            Also store the state trajectory in the result, as
            ``resp.states`` (memory N x nstates). Without it
            ``resp.states`` raises AttributeError saying so.

        Returns
        -------
        control.TimeResponseData
            ``resp.outputs`` is y (or y, x, v); ``resp.final_state`` is the
            state after the last sample, ready to continue the simulation.

        Warns
        -----
        SimulationWarning
            If the output stops being finite (an unstable system driven
            into overflow); the message gives the first sample affected.

        Examples
        --------
        >>> import numpy as np, sandwichctl as sw
        >>> plant = sw.examples.paper_plant()
        >>> resp = plant.simulate(np.ones(4), internal=True)
        >>> print(resp.outputs[1])            # x = L1[u]
        [0.    1.5   1.35  1.065]
        """
        u = check_signal('inputs', inputs)
        state = self._initial_state(initial_state)
        internal = check_bool('internal', internal)
        return_states = check_bool('return_states', return_states)
        n = u.size
        step = 1.0 if self.dt is True else float(self.dt)
        if timepts is not None:
            timepts = check_timepts('timepts', timepts, n, self.dt)
        y = np.empty(n)
        x, v = (np.empty(n), np.empty(n)) if internal else (y[:0], y[:0])
        states = np.empty((n if return_states else 0, self.nstates))
        comp = self.__dict__.get('_companion', False)
        if comp is False:                 # first call: read the form once
            comp = self._companion = companion_form(*self._matrices)
        if comp is not None:
            # the kernel fills the time points and copies u, or neither
            t = np.empty(n if timepts is None else 0)
            u_copy = np.empty(n) if timepts is None else u.copy()
            bad = companion_kernel(u, *comp, *self._backlash_values, state,
                                   y, x, v, states, step, t, u_copy)
            timepts = t if timepts is None else timepts
        else:                             # another realisation
            simulate_kernel(u, *self._matrices, *self._backlash_values,
                            state, y, x, v, states)
            timepts = step * np.arange(n) if timepts is None else timepts
            u_copy = u.copy()
            bad = 0 if not np.all(np.isfinite(y)) else -1
        if bad >= 0 or not np.all(np.isfinite(state)):
            _warn_divergence(self.name, y, state, timepts)
        outputs = np.vstack([y, x, v]) if internal else y.reshape(1, n)
        labels = ['y', 'x', 'v'] if internal else self.output_labels
        # built on the first sample, then given the whole arrays: this
        # saves TimeResponseData's copies of arrays made here
        resp = SimulationResponse(
            timepts[:1], outputs[:, :1],
            states[:1].T if return_states else None, u_copy[:1],
            issiso=not internal, output_labels=labels,
            input_labels=self.input_labels,
            state_labels=self.state_labels if return_states else None,
            sysname=self.name, title=f"Simulation of {self.name}")
        resp.t, resp.y, resp.u = timepts, outputs, u_copy.reshape(1, n)
        if return_states:
            resp.x = states.T
        resp.final_state = state
        return resp

    def simulate_batch(self, inputs, thetas=None, initial_state=None):
        """Simulate many input signals and/or parameter sets at once.

        One compiled call, parallel over the rows with numba's threads
        (``numba.set_num_threads``); each row is exactly the output of one
        `simulate` call, whatever the number of threads.

        Parameters
        ----------
        inputs : array_like, shape (B, N) or (N,)
            One input signal per row; a 1-D array is one signal.
        thetas : array_like, shape (P, len(theta)) or (len(theta),), optional
            Parameter vectors of eq. (2.5) in this system's `theta_labels`
            order, one per row: a row stands for ``SandwichSystem.from_theta(
            row, **self.orders, dt=self.dt, sign=self.gain_sign)``. Default:
            this system itself.
        initial_state : array_like, optional
            Full state at k = 0 of every run, as for `simulate` (default
            zeros); not accepted with `thetas`.

        Returns
        -------
        numpy.ndarray, shape (max(B, P), N)
            Row b is the output y for signal b and parameter set b. A
            single signal (B = 1) is shared by every parameter set, and a
            single parameter set by every signal; otherwise B must equal P.

        Examples
        --------
        >>> import numpy as np, sandwichctl as sw
        >>> plant = sw.examples.paper_plant()
        >>> u = np.ones((3, 4)) * [[1.0], [2.0], [0.2]]
        >>> plant.simulate_batch(u)[1]
        array([ 0.  ,  0.  ,  5.  , -1.25])
        >>> thetas = [plant.theta, plant.theta * 1.1]
        >>> plant.simulate_batch(np.ones(4), thetas).shape
        (2, 4)
        """
        U = batch_signals(inputs)
        if thetas is None:
            params = self.__dict__.get('_companion', False)
            if params is False:
                params = self._companion = companion_form(*self._matrices)
            state = self._initial_state(initial_state)
            if params is None:            # not a companion realisation
                return np.stack([self.simulate(r, state).outputs for r in U])
            params = tuple(np.array([p]) for p in params) + (
                np.array([self._backlash_values]),)
        else:
            if not (initial_state is None or np.ndim(initial_state) == 0
                    and initial_state == 0):
                raise ValueError("initial_state is not accepted with thetas "
                                 "(the runs start at rest)")
            params = theta_batch(thetas, self.orders, self.gain_sign)
            state = np.zeros(params[0].shape[1] + 2 + params[3].shape[1])
        S, P = U.shape[0], params[0].shape[0]
        if S > 1 and P > 1 and S != P:
            raise ValueError(f"inputs has {S} signals but thetas {P} "
                             f"parameter sets; give one of either or as "
                             f"many of both")
        Y = np.empty((max(S, P), U.shape[1]))
        batch_kernel(U, *params, state, Y)
        if not np.all(np.isfinite(Y)):
            rows = np.flatnonzero(~np.all(np.isfinite(Y), axis=1))
            warn(f"the batch simulation of {self.name} diverged in rows "
                 f"{rows[:10].tolist()}: a system is unstable or an input "
                 f"too large for it", SimulationWarning)
        return Y

    def _initial_state(self, initial_state):
        if initial_state is None or (
                isinstance(initial_state, (numbers.Real, np.number))
                and not isinstance(initial_state, (bool, np.bool_))
                and initial_state == 0):
            return np.zeros(self.nstates)
        return check_vector('initial_state', initial_state, self.nstates)

    # ------------------------------------------------------------------
    # Display
    # ------------------------------------------------------------------
    def __str__(self):
        co = self.coefficients
        dt = 'True (unspecified)' if self.dt is True else f"{self.dt:g}"
        return (
            f"SandwichSystem {self.name}: {self.input_labels[0]} -> "
            f"{self.output_labels[0]}, dt = {dt}\n"
            f"  L1: {difference_equation('x', 'u', co['a'], co['b'], co['q1'])}\n"
            f"  B:  v(k) = backlash(x(k)) with m1 = {co['m1']:.6g}, "
            f"m2 = {co['m2']:.6g}, D1 = {co['D1']:.6g}, D2 = {co['D2']:.6g}\n"
            f"  L2: {difference_equation('y', 'v', co['c'], co['d'], co['q2'])}")

    __repr__ = __str__


def theta_labels(na, nb, nc, nd, q1=0, q2=0):
    """Names of the entries of the parameter vector of eq. (2.5).

    The delays q1 and q2 name no parameter; they are taken (and checked)
    so that ``theta_labels(**plant.orders)`` works.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.theta_labels(na=2, nb=0, nc=2, nd=1)
    ['c1', 'c2', 'a1', 'a2', 'm1', 'm2', 'D1', 'D2', 'd1']
    """
    na, nb, nc, nd, _, _ = (check_order(n, v) for n, v in zip(
        ('na', 'nb', 'nc', 'nd', 'q1', 'q2'), (na, nb, nc, nd, q1, q2)))
    return ([f"c{i}" for i in range(1, nc + 1)]
            + [f"a{i}" for i in range(1, na + 1)]
            + ['m1', 'm2', 'D1', 'D2']
            + [f"b{i}" for i in range(1, nb + 1)]
            + [f"d{i}" for i in range(1, nd + 1)])


def _rebuild_sandwich(cls, L1, L2, backlash_values, dt, name, inputs,
                      outputs, orders):
    """Unpickle a SandwichSystem (see SandwichSystem.__reduce__)."""
    return cls(L1, Backlash(*backlash_values, dt=dt), L2, name=name,
               inputs=inputs, outputs=outputs, orders=orders)


def _settling_samples(blocks, delay):
    """Samples for the slowest pole of `blocks` to decay to 0.1%."""
    radius = 0.0
    for sys in blocks:
        den = np.trim_zeros(np.asarray(sys.den[0][0], float), 'f')
        if den.size > 1:
            radius = max(radius, float(np.max(np.abs(np.roots(den)))))
    if radius >= 1.0:                     # integrator or unstable
        return 100 + delay
    if radius == 0.0:                     # finite impulse response
        return 20 + delay
    tau = -1.0 / np.log(radius)
    return int(min(max(np.ceil(7.0 * tau) + delay, 20), 10_000))


def _warn_divergence(name, y, state, timepts):
    """SimulationWarning if the simulated output stopped being finite."""
    if np.isfinite(y[-1]) and np.all(np.isfinite(state)) \
            and np.all(np.isfinite(y)):
        return
    bad = ~np.isfinite(y)
    if not bad.any():
        warn(f"the simulation of {name} ended with a non-finite state: the "
             f"system is unstable or the input too large for it",
             SimulationWarning)
        return
    k = int(np.flatnonzero(bad)[0])
    warn(f"the simulation of {name} diverged: the output is {y[k]} from "
         f"sample {k} (t = {timepts[k]:g}) on; the system is unstable or "
         f"the input too large for it", SimulationWarning)
