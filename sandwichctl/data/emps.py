"""EMPS: measured data of an electro-mechanical positioning system.

EMPS is a prismatic axis: a DC motor drives a carriage through a ball
screw, under closed-loop position control. It is the standard EMPS
nonlinear system-identification benchmark, and its nonlinearity comes
from friction and from the play of the screw. `load_emps` returns its
two experiments as python-control records:

- **estimation**: the benchmark's ``DATA_EMPS`` run;
- **validation**: a separate run (``DATA_EMPS_PULSES``) with force-pulse
  disturbances.

Each has 4,969 samples at dt = 0.005 s:

- input u: the motor force reference [V], with the disturbance pulses of
  the validation run converted to the same units;
- output y: the carriage velocity [m/s], the first difference of the
  measured position.

Both signals were decimated by 5 from 1 kHz with a zero-phase FIR filter.
The means are **not** removed and nothing is scaled: offsets and units
are left to the user, as with a machine's own logs.

**Attribution.** The data are those of the EMPS benchmark: A. Janot,
M. Gautier and M. Brunot, "Data set and reference models of EMPS",
Workshop on Nonlinear System Identification Benchmarks, Eindhoven, 2019.
They were preprocessed as in M. Forgione's ``sysid-neural-continuous``
repository (``examples/EMPS``, github.com/forgi86); `EmpsData.note`
records the provenance and the processing.
"""

from importlib import resources
from typing import NamedTuple

import numpy as np
import control as ct

__all__ = ['load_emps', 'EmpsData']

_FILE = 'emps.npz'
_INPUT = 'force [V]'
_OUTPUT = 'velocity [m/s]'


class EmpsData(NamedTuple):
    """The EMPS experiments, from `load_emps`.

    It unpacks like a tuple: ``estimation, validation, note = data``.

    Attributes
    ----------
    estimation : control.TimeResponseData
        The estimation experiment: input 'force [V]', output
        'velocity [m/s]', time in seconds from 0.
    validation : control.TimeResponseData
        The validation experiment (a separate run with force pulses),
        labelled the same way.
    note : str
        Provenance and processing of the data.
    """

    estimation: ct.TimeResponseData
    validation: ct.TimeResponseData
    note: str

    @property
    def dt(self):
        """Sampling time [s] of both experiments (0.005)."""
        return float(self.estimation.time[1] - self.estimation.time[0])

    def __repr__(self):
        est, val = self.estimation, self.validation
        return (f"EmpsData: estimation ({est.time.size} samples) and "
                f"validation ({val.time.size} samples) experiments, dt = "
                f"{self.dt:g} s; input {est.input_labels[0]!r}, output "
                f"{est.output_labels[0]!r}")


def _record(u, y, dt, title):
    t = dt * np.arange(u.size)
    return ct.TimeResponseData(t, y, inputs=u, input_labels=[_INPUT],
                               output_labels=[_OUTPUT], sysname='EMPS',
                               title=title, issiso=True)


def load_emps():
    """Load the EMPS estimation and validation experiments.

    The data ship with sandwichctl (module documentation for what they
    are and where they come from).

    Returns
    -------
    EmpsData
        ``estimation`` and ``validation`` (each a
        `control.TimeResponseData` with one input, the force reference in
        V, and one output, the carriage velocity in m/s, 4,969 samples at
        dt = 0.005 s, means not removed) and ``note``.

    Examples
    --------
    >>> import numpy as np
    >>> import sandwichctl as sw
    >>> est, val, note = sw.data.load_emps()
    >>> est.input_labels, est.output_labels
    (['force [V]'], ['velocity [m/s]'])
    >>> bool(np.all(np.isfinite(val.outputs)))
    True
    >>> data = sw.as_experiments([est, val])     # two experiments
    >>> len(data), data.dt
    (2, 0.005)
    """
    path = resources.files(__package__).joinpath(_FILE)
    with resources.as_file(path) as file, np.load(file) as npz:
        dt = float(npz['dt'])
        note = str(npz['note'])
        est = _record(npz['u_est'], npz['y_est'], dt,
                      'EMPS estimation experiment')
        val = _record(npz['u_val'], npz['y_val'], dt,
                      'EMPS validation experiment (force pulses)')
    return EmpsData(est, val, note)
