"""The paper's studies, reproduced with the toolbox.

- `examples`: the paper's plants and excitations (Section 5's plant
  (5.1)-(5.2) and its Gaussian input, Section 6's X-Y stage axis) and
  `add_noise`. Also reachable as ``sw.examples``.
- `section5`: the Section 5 simulation study behind ``python -m
  sandwichctl demo`` (Figs. 2 and 3).
- `section6`: the Section 6 X-Y stage study.

Nothing in the toolbox imports this room: it sits on top of
identification and control design.
"""

from . import examples, section5, section6

__all__ = ['examples', 'section5', 'section6']
