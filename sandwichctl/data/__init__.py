"""Test plants and data sets.

- `synthetic`: seeded random sandwich identification cases
  (`random_case`, `random_family`) and excitation signals
  (`excitation`), for benchmarks and tests.
- `drive`: a physically simulated servo drive with play in its ball-screw
  nut (`servo_drive`, `drive_case`): data that no sandwich model fits
  exactly.
"""

from . import synthetic, drive
from .synthetic import *
from .drive import *

__all__ = synthetic.__all__ + drive.__all__
