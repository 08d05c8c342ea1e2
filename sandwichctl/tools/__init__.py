"""Tools around a model: validation against data, plots, and files.

- `validation`: fit measures and `compare` (simulated against measured).
- `plotting`: `plot_hysteresis`.
- `io`: `save_model` and `load_model` (JSON).
- `experiments`: measured data as arrays, python-control records or lists
  of experiments (`as_experiments`), read the same way by every function.
"""

from . import experiments, validation, plotting, io
from .experiments import *
from .validation import *
from .plotting import *
from .io import *

__all__ = (experiments.__all__ + validation.__all__ + plotting.__all__
           + io.__all__)
