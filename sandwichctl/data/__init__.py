"""Test plants and data sets.

- `synthetic`: seeded random sandwich identification cases
  (`random_case`, `random_family`) and excitation signals
  (`excitation`), for benchmarks and tests.
- `drive`: a physically simulated servo drive with play in its ball-screw
  nut (`servo_drive`, `drive_case`): data that no sandwich model fits
  exactly.
- `emps`: measured data of the EMPS ball-screw axis (`load_emps`): two
  experiments, as python-control records.
"""

from . import synthetic, drive, emps
from .synthetic import *
from .drive import *
from .emps import *

__all__ = synthetic.__all__ + drive.__all__ + emps.__all__
