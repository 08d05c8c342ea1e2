"""The model: the backlash of eq. (2.2), the sandwich system of eq. (2.1)
and its compiled simulation kernel.

This room depends on nothing else in the package (only on the shared
argument checks); every other room builds on it.
"""

from . import backlash, sandwich, response
from .backlash import *
from .sandwich import *
from .response import *

__all__ = backlash.__all__ + sandwich.__all__ + response.__all__
