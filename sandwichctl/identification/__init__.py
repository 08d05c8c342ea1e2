"""Identification: estimate a sandwich system from input/output data.

- `result`: `IdentificationResult`, returned by every identifier.
- `recursive`: the paper's recursive methods (bundle, gradient) and the
  recursive prediction-error estimator, as the streaming
  `RecursiveIdentifier`.
- `linear`: `identify_linear`, the linear output-error baseline (MATLAB
  ``oe`` semantics) every sandwich fit is reported against.
- `batch`: `refine`, the batch output-error refinement of a model on a
  whole record.
- `pipeline`: `identify`, the output-error search (method 'oe') or the
  recursive methods.
- `fleet`: `identify_many`, `identify` over many data sets in parallel
  (local processes or a dask cluster).
- `structure`: `select_structure`, which identifies a small grid of
  orders and delays (and the linear models they nest) and ranks them in
  a `StructureTable`.

The private modules hold the parts: `_data` (reading and scaling the
data), `_options` (each method's options), `_predictor` (the model output
and its sensitivities, the stability predicate), `_recursive` (the
compiled per-sample steps), `_problem` (the scaled output-error problem
and its parametrisation), `_lm` (the Levenberg-Marquardt solver),
`_linear` (the linear output-error core), `_search` (the output-error
search, one method per step of the algorithm page), `_starts` (every
start of the search), `_smooth` (the smoothed-backlash continuation) and
`_qp` (the piqp wrapper).
"""

from . import result, recursive, linear, batch, pipeline, structure, fleet
from .result import *
from .recursive import *
from .linear import *
from .batch import *
from .pipeline import *
from .fleet import *
from .structure import *

__all__ = (result.__all__ + recursive.__all__ + linear.__all__
           + batch.__all__ + pipeline.__all__ + structure.__all__
           + fleet.__all__)
