"""Control design: cancel the backlash, and close the loop around it.

- `inverse`: the backlash inverse and the causal inverse of a linear block.
- `compensator`: `sandwich_compensator`, the two inverses in front of a
  plant, and `linearized_plant`, the model without its backlash.
- `references`: reference signals for closed loops (`steps_and_sines`,
  `servo_reference`).
- `tracking`: a linear PI (plus feedforward) `tracking_controller`.
- `servo`: `servo_controller`, a controller designed from an identified
  model that steps one sample at a time (with `_servo_design`, its design
  steps, and `_servo_kernel`, its compiled step).
- `loop`: the loop of a servo controller around any plant, and
  `servo_metrics`.
- `closedloop`: `closed_loop_response` and `closed_loop_system`, and
  `plot_loop`, a servo loop's sensitivity.
- `demo`: `closed_loop_demo`, the same plant with and without
  compensation.
- `descfcn`: the backlash's describing function and limit cycles.
- `export`: a servo controller or a compensator as dependency-free C.
"""

from . import (inverse, compensator, references, tracking, servo, loop,
               closedloop, demo, descfcn, export)
from .inverse import *
from .compensator import *
from .references import *
from .tracking import *
from .servo import *
from .loop import *
from .closedloop import *
from .demo import *
from .descfcn import *
from .export import *

__all__ = (inverse.__all__ + compensator.__all__ + references.__all__
           + tracking.__all__ + servo.__all__ + loop.__all__
           + closedloop.__all__ + demo.__all__
           + descfcn.__all__ + export.__all__)
