"""sandwichctl: sandwich systems with backlash-like hysteresis for python-control.

A sandwich system is a linear block L1, a backlash, and a linear block L2
in series. sandwichctl models them as python-control I/O systems,
simulates them fast, identifies them from data with the nonsmooth
recursive method of the paper in ``shared/paper`` (and better estimators),
and designs inverse-backlash compensators.

>>> import control as ct
>>> import sandwichctl as sw
"""

from . import examples, study
from . import xystudy
from .backlash import *
from .sandwich import *
from .compensate import *
from .descfcn import *
from .validation import *
from .plotting import *
from .io import *
from .identify import *
from .refine import *

__version__ = '0.1.0'
