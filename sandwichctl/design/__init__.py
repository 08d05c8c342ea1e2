"""Control design: cancel the backlash, and close the loop around it.

- `inverse`: the backlash inverse and the causal inverse of a linear block.
- `compensator`: `sandwich_compensator`, the two inverses in front of a
  plant, and `linearized_plant`, the model without its backlash.
- `closedloop`: a linear tracking controller, the closed loop (fast and as
  a python-control system), and the with/without comparison.
- `descfcn`: the backlash's describing function and limit cycles.
- `export`: a servo controller or a compensator as dependency-free C.
"""

from . import (inverse, compensator, references, servo, loop, closedloop,
               descfcn, export)
from .inverse import *
from .compensator import *
from .references import *
from .servo import *
from .loop import *
from .closedloop import *
from .descfcn import *
from .export import *

__all__ = (inverse.__all__ + compensator.__all__ + references.__all__
           + servo.__all__ + loop.__all__
           + closedloop.__all__
           + descfcn.__all__ + export.__all__)
