"""Input/output data in python-control's types, one or several experiments.

Every function that takes measured data (`identify`, `identify_linear`,
`refine`, `compare`, `residuals`, `select_structure`) reads it through
`as_experiments`, so they all accept the same forms:

- ``u, y``: two 1-D arrays of the same length (one experiment), as two
  arguments or as one ``(u, y)`` pair;
- a `control.TimeResponseData` with one input and one output (for
  example from ``ct.input_output_response`` or a logged record wrapped as
  ``ct.TimeResponseData(t, y, inputs=u)``); its time vector gives dt;
- a list of either: several experiments, each from its own initial state,
  whose costs are summed. They must share dt; their lengths may differ.

A record with NaN or inf, a time vector that is not evenly spaced, a dt
that does not match the time vector, a continuous-time ``dt=0`` and
experiments with different sampling times are refused with a message
that says which experiment and what was wrong.
"""

import numbers

import numpy as np
import control as ct

from .._checks import check_signal, is_finite_real

__all__ = ['Experiments', 'as_experiments']


class Experiments(list):
    """A list of (u, y) pairs of 1-D float arrays, with their ``dt``.

    Built by `as_experiments`; ``len(data)`` is the number of experiments
    and ``data.n_samples`` the total number of samples.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> data = sw.as_experiments([(np.arange(4.), np.ones(4)),
    ...                           (np.arange(3.), np.zeros(3))], dt=0.1)
    >>> len(data), data.n_samples, data.dt
    (2, 7, 0.1)
    """

    def __init__(self, pairs, dt, _checked=False):
        if not _checked:             # built by a user: read as any data
            try:
                # a record or one (u, y) pair is one experiment as it is:
                # list() made a record's (time, outputs) the pair
                if not isinstance(pairs, (ct.TimeResponseData, tuple)):
                    pairs = list(pairs)
            except TypeError:
                raise TypeError(f"pairs must be a list of (u, y) pairs; got "
                                f"{type(pairs).__name__}") from None
            data = as_experiments(pairs, dt=dt)
            pairs, dt = list(data), data.dt
        super().__init__(pairs)
        self.dt = dt

    @property
    def n_samples(self):
        """Total number of samples over the experiments."""
        return sum(u.size for u, _ in self)

    @property
    def u(self):
        """The inputs, one array per experiment."""
        return [u for u, _ in self]

    @property
    def y(self):
        """The outputs, one array per experiment."""
        return [y for _, y in self]


def _is_signal(value):
    """True for a 1-D array-like of numbers (one signal), or a column of
    them (N, 1)."""
    if isinstance(value, ct.TimeResponseData):
        return False
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return arr.ndim == 1 or (arr.ndim == 2 and arr.shape[1] == 1)


def _nested(value):
    """True for a list or tuple that holds arrays or sequences of more
    than one sample (several signals, of equal lengths or not), not
    numbers or the one-sample rows of a column."""
    return (isinstance(value, (list, tuple)) and len(value) > 0
            and any(np.ndim(v) > 0 and np.size(v) > 1 for v in value))


def _time_step(t, where):
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2 or not np.all(np.isfinite(t)):
        raise ValueError(f"{where}: the time vector must be a finite 1-D "
                         f"array of at least 2 points")
    steps = np.diff(t)
    # the mean step, rounded to 12 significant digits (t = 0.005 k read
    # back gives 0.005, not 0.004999999999999893), or to fewer where the
    # times' own rounding leaves fewer (epoch times of 1.7e9 s: 6 at 1 ms)
    span = float(t[-1] - t[0])
    ulp = float(np.spacing(np.max(np.abs(t))))
    digits = (12 if not span > 0 else
              int(min(12, max(1, np.floor(-np.log10(2 * ulp / span))))))
    mean = span / (t.size - 1)
    step = float(f"{mean:.{digits}g}")
    if abs(step - mean) > 2 * ulp / (t.size - 1):   # rounded too far
        step = float(f"{mean:.12g}")
    if not step > 0:
        raise ValueError(f"{where}: the time vector must increase; got a "
                         f"step of {step:g}")
    # each time read to its last bit: absolute (epoch) times of 1.7e9 s
    # carry 2.4e-7 s of rounding, more than 1e-6 of a 1 ms step
    if np.max(np.abs(steps - step)) > max(1e-6 * step, 8 * ulp):
        bad = int(np.argmax(np.abs(steps - step)))
        raise ValueError(
            f"{where}: the time vector is not evenly spaced (step {bad} is "
            f"{steps[bad]:g}, the others {step:g}); a discrete-time model "
            f"needs a sampled record: resample it first")
    return step


def _one(item, where):
    """(u, y, dt or None) of one experiment."""
    if isinstance(item, ct.TimeResponseData):
        if item.ninputs != 1 or item.noutputs != 1:
            raise ValueError(
                f"{where}: the TimeResponseData must have one input and one "
                f"output; got {item.ninputs} inputs and {item.noutputs} "
                f"outputs")
        if getattr(item, 'ntraces', 0) not in (0, 1):
            raise ValueError(f"{where}: the TimeResponseData has "
                             f"{item.ntraces} traces; pass them as a list "
                             f"of experiments")
        t = np.asarray(item.time, dtype=float)
        u = np.squeeze(np.asarray(item.inputs))
        y = np.squeeze(np.asarray(item.outputs))
        step = _time_step(t, where)
        return (check_signal(f"{where} inputs", u, length=t.size),
                check_signal(f"{where} outputs", y, length=t.size), step)
    if isinstance(item, (tuple, list)) and len(item) == 2:
        u = check_signal(f"{where} u", item[0])
        y = check_signal(f"{where} y", item[1])
        if u.size != y.size:
            raise ValueError(f"{where}: u and y must have the same length; "
                             f"got {u.size} and {y.size} samples")
        return u, y, None
    raise TypeError(
        f"{where} must be a (u, y) pair of arrays or a "
        f"control.TimeResponseData; got {type(item).__name__}")


def _check_dt(dt):
    if dt is None or dt is True:
        return dt
    if isinstance(dt, bool) or not isinstance(dt, numbers.Real):
        raise TypeError(f"dt must be a positive number or True; got "
                        f"{type(dt).__name__} {dt!r}")
    if dt == 0:
        raise ValueError("dt = 0 is a continuous-time record; sandwichctl "
                         "identifies discrete-time models from sampled "
                         "data: give the sampling time")
    if not (is_finite_real(dt) and dt > 0):
        raise ValueError(f"dt must be a finite sampling time > 0 or True; "
                         f"got {dt!r}")
    return float(dt)


def as_experiments(u, y=None, dt=None):
    """Read measured data in any of the accepted forms (module docstring).

    Parameters
    ----------
    u : array_like, tuple, control.TimeResponseData or list
        The input (with `y`), one ``(u, y)`` pair, a record, or a list of
        experiments.
    y : array_like, optional
        The output, when `u` is an array.
    dt : float or True, optional
        Sampling time. With records it must match their time vectors
        (default: taken from them); with arrays it defaults to True
        (discrete, unspecified).

    Returns
    -------
    Experiments

    Raises
    ------
    ValueError, TypeError
        With the experiment and what is wrong.

    Examples
    --------
    >>> import numpy as np, control as ct, sandwichctl as sw
    >>> t = 0.01 * np.arange(100)
    >>> rec = ct.TimeResponseData(t, np.cos(t), inputs=np.sin(t))
    >>> data = sw.as_experiments([rec, rec])
    >>> len(data), data.dt
    (2, 0.01)
    >>> len(sw.as_experiments((np.sin(t), np.cos(t))))      # one (u, y)
    1
    """
    if isinstance(u, Experiments) and y is None and dt is None:
        dt = u.dt                       # its own sampling time
    dt = _check_dt(dt)
    if y is not None:
        if _nested(u) or _nested(y):
            raise TypeError(
                f"u and y are lists of {len(u) if _nested(u) else len(y)} "
                f"arrays; give several experiments as one list of (u, y) "
                f"pairs, e.g. [(u1, y1), (u2, y2)], without y")
        if isinstance(u, (ct.TimeResponseData, list, tuple)) and not \
                np.ndim(u) == 1:
            raise TypeError("give either u and y as arrays, or one record "
                            "(or list of records) without y")
        items, names = [(u, y)], ['the data']
    elif isinstance(u, ct.TimeResponseData):
        items, names = [u], ['the record']
    elif (isinstance(u, (list, tuple)) and len(u) == 2
          and _is_signal(u[0]) and _is_signal(u[1])):
        items, names = [tuple(u)], ['the data']
    elif isinstance(u, (list, tuple)):
        if len(u) == 0:
            raise ValueError("the list of experiments is empty")
        items = list(u)
        names = [f"experiment {i}" for i in range(len(items))]
    else:
        raise TypeError(
            f"data must be u and y arrays, a (u, y) pair, a "
            f"control.TimeResponseData or a list of experiments; got "
            f"{type(u).__name__} without y")
    pairs, steps = [], []
    for item, where in zip(items, names):
        uu, yy, step = _one(item, where)
        pairs.append((uu, yy))
        steps.append((where, step))
    found = [(w, s) for w, s in steps if s is not None]
    if found:
        ref_where, ref = found[0]
        for where, step in found[1:]:
            if abs(step - ref) > 1e-6 * ref:
                raise ValueError(
                    f"{where} is sampled at dt = {step:g} but {ref_where} at "
                    f"dt = {ref:g}; experiments must share the sampling time")
        if dt is not None and dt is not True and abs(dt - ref) > 1e-6 * ref:
            raise ValueError(f"dt = {dt:g} does not match the records' time "
                             f"step {ref:g}")
        dt = ref
    return Experiments(pairs, True if dt is None else dt, _checked=True)
