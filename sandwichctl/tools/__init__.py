"""Tools around a model: validation against data, plots, and files.

- `validation`: fit measures and `compare` (simulated against measured).
- `residuals`: residual auto- and cross-correlation with confidence bands
  (`residuals`, as MATLAB's ``resid``).
- `plotting`: `plot_hysteresis`.
- `io`: `save_model` and `load_model` (JSON).
- `experiments`: measured data as arrays, python-control records or lists
  of experiments (`as_experiments`), read the same way by every function.
"""

from . import experiments, validation, plotting, io
# the module shares its name with its function, which the star import
# below puts in its place; keep the module under a private name
from . import residuals as _residuals
from .experiments import *
from .validation import *
from .residuals import *
from .plotting import *
from .io import *

__all__ = (experiments.__all__ + validation.__all__ + _residuals.__all__
           + plotting.__all__ + io.__all__)
