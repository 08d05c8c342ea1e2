"""Identification: estimate a sandwich system from input/output data.

- `result`: `IdentificationResult`, returned by every identifier.
- `recursive`: the paper's recursive methods (bundle, gradient) and the
  recursive prediction-error estimator, as the streaming
  `RecursiveIdentifier`.
- `batch`: `refine`, the batch output-error refinement of a model on a
  whole record.
- `pipeline`: `identify`, which chains them.

The private modules hold the compiled parts: `_predictor` (the model
output and its sensitivities, the stability predicate), `_recursive` (the
per-sample steps) and `_qp` (the piqp wrapper).
"""

from . import result, recursive, batch, pipeline
from .result import *
from .recursive import *
from .batch import *
from .pipeline import *

__all__ = result.__all__ + recursive.__all__ + batch.__all__ + pipeline.__all__
