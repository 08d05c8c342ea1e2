r"""The compensator of a whole sandwich system.

A compensator placed in front of a sandwich system L1 -> backlash -> L2
cancels the backlash and L1, so that a linear controller only sees L2:

.. code-block:: text

          compensator (SandwichCompensator)     plant (SandwichSystem)
    v_d ─► B^-1 ─x_d─► z^-q1 L1^-1 ─u─►  L1 ─x─► backlash ─v─► L2 ─► y
           (BacklashInverse) (causal_inverse)

With an exact model, ``x(k) = x_d(k - q1)`` and ``v(k) = v_d(k - q1)``, so
the compensated plant from v_d to y is the linear system
:math:`z^{-q_1} L_2(z)` (`SandwichCompensator.design_plant`). The two
inverses are in module `inverse`.
"""

import warnings

import numba
import numpy as np
import control as ct

from .inverse import BacklashInverse, _causal_inverse, _inverse_step
from ..model._coefficients import tf_to_ss
from ..model._kernel import _ss_output, _ss_update
from ..model.sandwich import (SandwichSystem, _settling_samples,
                              _warn_divergence)
from .._checks import (check_positive, check_bool, check_name, check_label,
                       check_signal, check_vector, check_timepts,
                       named_copy)

__all__ = ['SandwichCompensator', 'sandwich_compensator', 'linearized_plant']


# ----------------------------------------------------------------------
# Compensator for a whole sandwich
# ----------------------------------------------------------------------
class SandwichCompensator(ct.InterconnectedSystem):
    r"""Inverse compensator of a sandwich: backlash inverse, then L1 inverse.

    An interconnected python-control system with input v_d (the backlash
    output wanted) and output u (the plant input). Put it in front of the
    plant; a controller designed for `design_plant` then sees a linear plant.
    Its state vector is ``[x_prev, v_prev, L1-inverse states]``; from zero
    state in front of a plant at rest, the loop is consistent. Build it with
    `sandwich_compensator`.

    Parameters
    ----------
    model : SandwichSystem
        The model to invert.
    smoothing, band_fraction, approximate : optional
        See `sandwich_compensator`.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'u'.

    Attributes
    ----------
    model : SandwichSystem
        The model the compensator inverts (known or identified).
    backlash_inverse : BacklashInverse
        The backlash inverse, v_d -> x_d.
    L1_inverse : control.TransferFunction
        :math:`z^{-q_1} L_1^{-1}` (see `causal_inverse`), x_d -> u.
    design_plant : control.TransferFunction
        :math:`z^{-q_1} L_2`: the plant from v_d to y once compensated
        (exactly, if the model is exact and `is_exact`).
    delay : int
        q1, the delay between v_d and v.

    Notes
    -----
    `simulate` runs the compensator alone, fast; as a python-control
    system it also works with ``ct.input_output_response`` and
    ``ct.interconnect``. It pickles (``pickle``, ``copy.deepcopy``) with
    its names, and the copy simulates bit for bit like the original.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> comp = sw.sandwich_compensator(sw.examples.paper_plant())
    >>> v_d = np.array([0.0, 1.0, 2.0, 2.0, 1.0])
    >>> print(comp.simulate(v_d).outputs.round(4))
    [0.     1.     1.7667 2.0333 0.6556]
    >>> slow = ct.input_output_response(comp, np.arange(5), v_d)
    >>> bool(np.allclose(slow.outputs, comp.simulate(v_d).outputs))
    True
    """

    def __init__(self, model, smoothing=0.0, band_fraction=1.0,
                 approximate=False, name=None, inputs='v_d', outputs='u'):
        if not isinstance(model, SandwichSystem):
            raise TypeError(
                f"model must be a sandwichctl.SandwichSystem (known or "
                f"identified, e.g. sw.examples.paper_plant()); got "
                f"{type(model).__name__}")
        co = model.coefficients
        approximate = check_bool('approximate', approximate)
        name = check_name('name', name)
        inputs = check_label('inputs', inputs, 'input')
        outputs = check_label('outputs', outputs, 'output')
        band_fraction = check_positive('band_fraction', band_fraction)
        if band_fraction > 1:
            raise ValueError(f"band_fraction must be in (0, 1] (the share of "
                             f"the model's band to compensate); got "
                             f"{band_fraction!r}")
        self._model = model
        self._band_fraction = band_fraction
        self._approximate = bool(approximate)
        # named parts, so that their names survive pickling
        self._L1_inverse, reflected = _causal_inverse(model.L1, approximate,
                                                      name='L1_inverse')
        self._exact_L1 = not reflected
        self._delay = co['q1']
        self._design_plant = ct.tf(
            model.L2.num[0][0], np.polymul(model.L2.den[0][0],
                                           np.eye(1, co['q1'] + 1)[0]),
            model.dt, name='design_plant')
        inv = BacklashInverse(co['m1'], co['m2'], band_fraction * co['D1'],
                              band_fraction * co['D2'],
                              smoothing=smoothing, dt=model.dt,
                              name='backlash_inverse', inputs='v_d',
                              outputs='x_d')
        self._inverse = inv
        with np.errstate(all='ignore'), warnings.catch_warnings():
            # scipy's normalisation overflows on an L1 gain of 1e-310
            warnings.simplefilter('ignore', RuntimeWarning)
            lin = tf_to_ss(self._L1_inverse, inputs='x_d', outputs='u',
                           name='L1_inverse')
        self._matrices = tuple(np.ascontiguousarray(np.asarray(M, float))
                               for M in (lin.A, lin.B, lin.C, lin.D))
        if not all(np.all(np.isfinite(M)) for M in self._matrices):
            raise ValueError("model.L1's gain is too small to invert: the "
                             "state-space form of L1^-1 overflows a float "
                             "(rescale u or x)")
        super().__init__(
            [inv, lin],
            connections=[['L1_inverse.x_d', 'backlash_inverse.x_d']],
            inplist=['backlash_inverse.v_d'], outlist=['L1_inverse.u'],
            inputs=inputs, outputs=outputs, dt=model.dt, name=name)

    copy = named_copy            # its name checked

    def __reduce__(self):
        # the python-control state-space block holds closures, which
        # pickle cannot store: rebuild from the model and the options
        return (type(self), (self._model, self.smoothing,
                             self._band_fraction, self._approximate,
                             self.name, self.input_labels[0],
                             self.output_labels[0]))

    def _settling_samples(self):
        """Samples for the L1 inverse's slowest pole to decay (step)."""
        return _settling_samples([self._L1_inverse], 0)

    def simulate(self, inputs, initial_state=None, timepts=None,
                 internal=False):
        """Fast simulation of the compensator alone (compiled kernel).

        The same result as ``ct.input_output_response(self, timepts,
        inputs, initial_state)`` (to rounding), much faster; like
        `SandwichSystem.simulate`.

        Parameters
        ----------
        inputs : array_like, shape (N,)
            The wanted backlash output v_d(0), ..., v_d(N-1) (often
            called r when the compensator is driven directly).
        initial_state : array_like, optional
            State at k = 0, ``[x_prev, v_prev, L1-inverse states]`` as
            `state_labels` says; default zeros (consistent with a plant at
            rest).
        timepts : array_like, optional
            Time points, evenly spaced by dt; default ``dt * arange(N)``.
        internal : bool, optional
            If True, the outputs are u, x_d and v_hat (the plant input,
            the backlash input the inverse asks for, and the backlash
            output it expects); otherwise just u.

        Returns
        -------
        control.TimeResponseData
            ``resp.outputs`` is u (or u, x_d, v_hat); ``resp.final_state``
            is the state after the last sample.
        """
        v_d = check_signal('inputs', inputs)
        internal = check_bool('internal', internal)
        n = v_d.size
        if initial_state is None or (np.isscalar(initial_state)
                                     and not isinstance(initial_state, bool)
                                     and initial_state == 0):
            state = np.zeros(self.nstates)
        else:
            state = check_vector('initial_state', initial_state,
                                 self.nstates)
        step = 1.0 if self.dt is True else float(self.dt)
        timepts = (step * np.arange(n) if timepts is None else
                   check_timepts('timepts', timepts, n, self.dt))
        u, x_d, v_hat = np.empty(n), np.empty(n), np.empty(n)
        inv = self._inverse
        _compensator_kernel(v_d, inv.m1, inv.m2, inv.D1, inv.D2,
                            inv.smoothing, *self._matrices, state, u, x_d,
                            v_hat)
        _warn_divergence(self.name, u, state, timepts)
        outputs = np.vstack([u, x_d, v_hat]) if internal else u
        labels = (['u', 'x_d', 'v_hat'] if internal
                  else self.output_labels)
        resp = ct.TimeResponseData(
            timepts, outputs, None, v_d, issiso=not internal,
            output_labels=labels, input_labels=self.input_labels,
            sysname=self.name, title=f"Simulation of {self.name}")
        resp.final_state = state
        return resp

    model = property(lambda self: self._model,
                     doc="The inverted model (a SandwichSystem).")
    backlash_inverse = property(lambda self: self._inverse,
                                doc="The backlash inverse (v_d -> x_d).")
    L1_inverse = property(lambda self: self._L1_inverse,
                          doc="z^-q1 L1^-1 (x_d -> u), a TransferFunction.")
    design_plant = property(lambda self: self._design_plant,
                            doc="z^-q1 L2: the compensated plant v_d -> y.")
    delay = property(lambda self: self._delay, doc="q1 (samples).")
    smoothing = property(lambda self: self._inverse.smoothing,
                         doc="Smoothing width of the backlash inverse.")
    band_fraction = property(lambda self: self._band_fraction,
                             doc="Share of the model's thresholds inverted.")
    approximate = property(lambda self: self._approximate,
                           doc="Whether a non-minimum-phase L1 may be "
                               "inverted approximately.")

    # The protocol through which compiled loops (closed_loop_response,
    # export_c) run a compensator: a backlash inverse, then a linear
    # state-space block.
    @property
    def inverse_parameters(self):
        """(m1, m2, D1, D2, smoothing) of the backlash inverse as run."""
        inv = self._inverse
        return (inv.m1, inv.m2, inv.D1, inv.D2, inv.smoothing)

    @property
    def linear_matrices(self):
        """(A, B, C, D) arrays of the linear block after the inverse
        (:math:`z^{-q_1} L_1^{-1}`), as the compiled loops run it."""
        return self._matrices

    @property
    def is_exact(self):
        """True if the compensation is exact for an exact model.

        False if the backlash inverse is smoothed, compensates only part of
        the band, or L1's inverse had to be approximated (non-minimum-phase
        L1).
        """
        return (self.smoothing == 0 and self._band_fraction == 1
                and self._exact_L1)

    def __str__(self):
        return (f"<SandwichCompensator>: {self.name}, "
                f"{self.input_labels[0]} -> {self.output_labels[0]}, "
                f"dt = {self.dt}\n  {self._inverse!r}\n"
                f"  L1 inverse z^-{self._delay} L1^-1 = "
                f"{_tf_text(self._L1_inverse)}"
                + ("  (approximate: non-minimum-phase L1)"
                   if not self._exact_L1 else ""))

    __repr__ = __str__


@numba.njit(cache=True)
def _compensator_kernel(v_d, m1, m2, D1, D2, width, A, B, C, D, state, u,
                        x_d, v_hat):
    """Backlash inverse then L1 inverse, one sample at a time.

    `state` is ``[x_prev, v_prev, L1-inverse states]`` at k = 0 and is
    overwritten with the state after the last sample.
    """
    x_prev = state[0]
    v_prev = state[1]
    s = state[2:].copy()
    work = np.empty(s.size)
    for k in range(v_d.size):
        x_prev, v_prev = _inverse_step(v_d[k], x_prev, v_prev, m1, m2, D1,
                                       D2, width)
        u[k] = _ss_output(A, B, C, D, s, x_prev)
        _ss_update(A, B, s, x_prev, work)
        x_d[k] = x_prev
        v_hat[k] = v_prev
    state[0] = x_prev
    state[1] = v_prev
    state[2:] = s


def _tf_text(tf):
    num = ' '.join(f"{c:+.4g}" for c in tf.num[0][0])
    den = ' '.join(f"{c:+.4g}" for c in tf.den[0][0])
    return f"[{num}] / [{den}]"


def sandwich_compensator(model, smoothing=0.0, band_fraction=1.0,
                         approximate=False, name=None, inputs='v_d',
                         outputs='u'):
    r"""Inverse compensator for a sandwich system, ready for ct.interconnect.

    The compensator is the backlash inverse of `model` followed by the
    causal inverse :math:`z^{-q_1} L_1^{-1}` of its L1 (see the module
    notes). With an exact model, the compensated plant from v_d to y is the
    linear :math:`z^{-q_1} L_2` (``comp.design_plant``), so any linear
    design method applies.

    Parameters
    ----------
    model : SandwichSystem
        The model to invert: known, or identified (e.g. ``res.model`` of the
        identifier, which is normalised; any equivalent representation gives
        the same compensated plant).
    smoothing : float, optional
        Smoothing width of the backlash inverse, in units of the model's v
        (default 0: exact).
    band_fraction : float, optional
        Share of the model's thresholds D1, D2 that the inverse compensates,
        in (0, 1] (default 1). An over-estimated band (or one shifted by
        the identification error) makes the loop hunt across it: the output
        error stays tiny, but u chatters by the width of the band at every
        sample. A fraction slightly below 1 (e.g. 0.95) leaves a small
        residual dead band instead, which integral action handles.
    approximate : bool, optional
        If L1 is non-minimum-phase: False (default) raises ValueError, True
        uses the stable approximate inverse of `causal_inverse`.
    name : str, optional
        System name.
    inputs, outputs : str, optional
        Signal names; default 'v_d' and 'u'.

    Returns
    -------
    SandwichCompensator

    Raises
    ------
    TypeError
        If `model` is not a `SandwichSystem`.
    ValueError
        If L1 is non-minimum-phase and `approximate` is False, if
        `smoothing` < 0, or if `band_fraction` is not in (0, 1].

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> plant = sw.examples.paper_plant()
    >>> comp = sw.sandwich_compensator(plant)
    >>> P = comp.design_plant                 # z^-1 L2
    >>> P.num[0][0], P.den[0][0]
    (array([ 2. , -0.1]), array([1.  , 1.2 , 0.32, 0.  ]))
    >>> v_d = np.array([0.0, 1.0, 2.0, 2.0, 1.0, -1.0, 0.5])
    >>> u = ct.input_output_response(comp, np.arange(7), v_d).outputs
    >>> v = plant.simulate(u, internal=True).outputs[2]
    >>> print(v)                              # v(k) = v_d(k - 1)
    [ 0.  0.  1.  2.  2.  1. -1.]
    """
    return SandwichCompensator(model, smoothing=smoothing,
                               band_fraction=band_fraction,
                               approximate=approximate, name=name,
                               inputs=inputs, outputs=outputs)


def linearized_plant(model):
    r"""The sandwich with its backlash replaced by its mean slope.

    :math:`\bar m L_1 L_2` with :math:`\bar m = (m_1 + m_2)/2`: the linear
    model an engineer would design for without a backlash compensator (the
    dead band is ignored; integral action removes its static offset). The
    result is the same for every equivalent representation of the model.

    Parameters
    ----------
    model : SandwichSystem
        Known or identified model.

    Returns
    -------
    control.TransferFunction

    Examples
    --------
    >>> import control as ct, sandwichctl as sw
    >>> P = sw.linearized_plant(sw.examples.paper_plant())
    >>> round(float(ct.dcgain(P)), 4)     # 1.1 * (1.5/1.3) * (1.9/2.52)
    0.957
    """
    _check_model('model', model)
    co = model.coefficients
    return 0.5 * (co['m1'] + co['m2']) * model.L1 * model.L2


def _check_model(name, model):
    if not isinstance(model, SandwichSystem):
        raise TypeError(f"{name} must be a sandwichctl.SandwichSystem; got "
                        f"{type(model).__name__}")
