"""sandwichctl: sandwich systems with backlash-like hysteresis for python-control.

A sandwich system is a linear block L1, a backlash, and a linear block L2
in series. sandwichctl models them as python-control I/O systems,
simulates them fast, identifies them from data with the nonsmooth
recursive method of the paper in ``shared/paper`` (and better estimators),
and designs inverse-backlash compensators.

The package is organised in rooms, each a subpackage; every public name
is also available here (``sw.identify``, ``sw.SandwichSystem``, ...):

- `model`: the backlash, the sandwich system and its simulation;
- `identification`: recursive (paper) and batch identifiers, results;
- `design`: inverses, compensator, closed loop, describing function;
- `tools`: validation, plotting, model files;
- `data`: test plants and data sets (seeded random sandwich cases, a
  physically simulated servo drive);
- `paper`: the paper's example plants and its Section 5 and 6 studies
  (``sw.paper.section5``, ...); ``sw.examples`` is `paper.examples`.

Warnings have their own categories, so they can be filtered:
`SandwichWarning` (every warning of the package), its subclasses
`IdentificationWarning` (and its subclass `ExcitationWarning`) and
`SimulationWarning`.

Dependencies run one way: `paper` uses `identification`, `design` and
`tools`, which use `model`.

>>> import control as ct
>>> import sandwichctl as sw
"""

from . import model, tools, identification, design, data, paper
from .model import *
from .tools import *
from .identification import *
from .design import *
from .paper import examples
from ._checks import (SandwichWarning, IdentificationWarning,
                      ExcitationWarning, SimulationWarning)

__version__ = '0.1.0'

__all__ = (model.__all__ + tools.__all__ + identification.__all__
           + design.__all__ + _checks.__all__
           + ['data', 'examples', 'paper'])
