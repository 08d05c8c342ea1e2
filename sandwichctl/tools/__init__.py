"""Tools around a model: validation against data, plots, and files.

- `validation`: fit measures and `compare` (simulated against measured).
- `plotting`: `plot_hysteresis`.
- `io`: `save_model` and `load_model` (JSON).
"""

from . import validation, plotting, io
from .validation import *
from .plotting import *
from .io import *

__all__ = validation.__all__ + plotting.__all__ + io.__all__
