"""The options of each identification method, in one place (private).

Each method has one frozen dataclass: its fields are the options with
their defaults, `__post_init__` checks them, and the docstring documents
them. `method_options` builds the one of a method from keyword arguments
and refuses, naming the method, an option that does not apply to it, as
python-control's keyword checks do. `identify` and `RecursiveIdentifier`
read their options only through these classes.
"""

import dataclasses
import numbers

import numpy as np

from .result import MIN_FIT
from .._checks import (MOST_ROUNDS, MOST_SAMPLES, MOST_STARTS, check_bool,
                       check_finite, check_int, check_nonnegative,
                       check_option, check_positive, check_tolerance)

__all__ = []

#: The methods of `identify`: the output-error search and the recursive
#: methods.
RECURSIVE = ('bundle', 'gradient', 'rpem')
METHODS = ('oe',) + RECURSIVE


#: Where `identify` puts the integrators (``integrator_block=``): 'auto'
#: searches every block with a pole, 'L1' and 'L2' fill that block first.
INTEGRATOR_BLOCKS = ('auto', 'L1', 'L2')

#: The blocks `identify` can keep minimum-phase (``minimum_phase=``).
MINIMUM_PHASE = ('L1',)


def check_minimum_phase(value):
    """``minimum_phase`` checked: None (also for False) or 'L1'."""
    if value is None or (isinstance(value, (bool, np.bool_)) and not value):
        return None
    if isinstance(value, str) and value in MINIMUM_PHASE:
        return str(value)
    raise ValueError(f"minimum_phase must be None, False or one of "
                     f"{list(MINIMUM_PHASE)} (the block whose zeros are "
                     f"kept inside the unit circle); got {value!r}")


class _Options:
    """Base of the option classes: frozen, checked on construction."""

    method = None

    def _set(self, name, value):
        object.__setattr__(self, name, value)

    def as_dict(self):
        """The options as a plain dict (in field order)."""
        return {f.name: getattr(self, f.name)
                for f in dataclasses.fields(self)}


@dataclasses.dataclass(frozen=True)
class OEOptions(_Options):
    """Options of ``identify(..., method='oe')``; docs/algorithm.md explains
    the steps they tune.

    Attributes
    ----------
    integrators : int or 'auto'
        Poles fixed at z = 1 (step 3); 'auto' decides by AIC when the
        linear fit has a real pole above 0.9.
    integrator_block : {'auto', 'L1', 'L2'}
        Where the integrators go: 'auto' searches each block with a pole
        (step 3).
    initial_state : {'zero', 'estimate'}
        Each experiment from rest, or its past values estimated.
    minimum_phase : {None, 'L1'}
        'L1' keeps L1's zeros inside the unit circle (`MINIMUM_PHASE`).
    widths : sequence of float
        Relative backlash widths the nested starts open to (step 4): at
        least one, each in (0, 10).
    max_splits : int
        Most pole/zero splits of the linear fit screened (step 4).
    sp_iter, sp_starts, n_random, seed : int
        Series-parallel iterations, screened starts they run from, random
        starts and their seed (step 5).
    screen_iter, keep, screen_samples : int
        Iterations of the screening runs, starts kept to converge, and the
        leading samples the screening uses (step 6).
    max_iter : int
    tol : float
        Levenberg-Marquardt's iterations and relative tolerance to
        convergence (0 < tol < 1).
    refits : int
        L2 re-fits per converged start (step 7).
    smooth : bool
        The path through smoothed backlashes (step 8).
    relocate, hops : int
        Rounds of relocations (step 9) and hops (step 10).
    min_fit : float
        The fit (percent) a model must exceed to succeed.
    """

    integrators: object = 'auto'
    integrator_block: str = 'auto'
    initial_state: str = 'zero'
    minimum_phase: object = None
    widths: tuple = (0.05, 0.25)
    screen_iter: int = 8
    keep: int = 3
    max_iter: int = 200
    tol: float = 1e-8
    min_fit: float = MIN_FIT
    sp_iter: int = 15
    sp_starts: int = 4
    n_random: int = 6
    seed: int = 0
    refits: int = 2
    max_splits: int = 16
    hops: int = 4
    relocate: int = 3
    smooth: bool = True
    screen_samples: int = 2000

    method = 'oe'
    #: The fields that are arguments of `identify` itself; the others tune
    #: the search (``res.options``).
    ARGUMENTS = ('integrators', 'integrator_block', 'initial_state',
                 'minimum_phase')
    _MINIMA = dict(screen_iter=1, sp_iter=0, sp_starts=0, n_random=0, seed=0,
                   keep=1, refits=0, max_splits=1, hops=0, relocate=0,
                   screen_samples=100, max_iter=1)
    #: the most of each count: a typo (hops=10**6) would run for hours
    _MAXIMA = dict(screen_iter=MOST_ROUNDS, sp_iter=MOST_ROUNDS,
                   max_iter=MOST_ROUNDS, screen_samples=MOST_SAMPLES,
                   seed=None)

    def __post_init__(self):
        k = self.integrators
        if not ((isinstance(k, str) and k == 'auto')
                or (isinstance(k, numbers.Integral)
                    and not isinstance(k, bool) and k >= 0)):
            raise ValueError(f"integrators must be an integer >= 0 or "
                             f"'auto'; got {k!r}")
        self._set('integrators', k if isinstance(k, str) else int(k))
        if k == 0 and self.integrator_block in ('L1', 'L2'):
            raise ValueError(f"integrator_block={self.integrator_block!r} "
                             f"says where the integrator goes, and "
                             f"integrators=0 asks for none: leave "
                             f"integrator_block out")
        if not (isinstance(self.integrator_block, str)
                and self.integrator_block in INTEGRATOR_BLOCKS):
            raise ValueError(f"integrator_block must be one of "
                             f"{list(INTEGRATOR_BLOCKS)}; got "
                             f"{self.integrator_block!r}")
        check_option('initial_state', self.initial_state,
                     ('zero', 'estimate'))
        self._set('minimum_phase', check_minimum_phase(self.minimum_phase))
        widths = self.widths
        if np.ndim(widths) != 1 or not len(widths) or not all(
                isinstance(w, numbers.Real) and not isinstance(
                    w, (bool, np.bool_)) and 0 < w < 10 for w in widths):
            raise ValueError(f"widths must be a non-empty sequence of "
                             f"relative widths in (0, 10) (the backlash "
                             f"widths the starts open to); got {widths!r}")
        self._set('widths', tuple(float(w) for w in widths))
        for name, minimum in self._MINIMA.items():
            self._set(name, check_int(name, getattr(self, name), minimum,
                                      self._MAXIMA.get(name, MOST_STARTS)))
        self._set('smooth', check_bool('smooth', self.smooth))
        self._set('tol', check_tolerance('tol', self.tol))
        self._set('min_fit', check_finite('min_fit', self.min_fit))
        if not self.min_fit < 100:
            raise ValueError(f"min_fit must be below 100 (a fit in percent "
                             f"is at most 100); got {self.min_fit!r}")

    def search(self):
        """The search's options as a dict (``res.options``)."""
        return {f.name: getattr(self, f.name)
                for f in dataclasses.fields(self)
                if f.name not in self.ARGUMENTS}


@dataclasses.dataclass(frozen=True)
class _RecursiveCommon(_Options):
    """Options every recursive method has: m_min (lower bound of the
    slopes) and divergence_limit (an estimate beyond it has diverged)."""

    m_min: float = 1e-6
    divergence_limit: float = 1e6

    def _check_common(self):
        self._set('m_min', check_positive('m_min', self.m_min))
        self._set('divergence_limit', check_positive(
            'divergence_limit', self.divergence_limit))

    def _check_predictor(self):
        if self.predictor not in ('series-parallel', 'parallel'):
            raise ValueError(f"predictor must be 'series-parallel' or "
                             f"'parallel'; got {self.predictor!r}")


@dataclasses.dataclass(frozen=True)
class BundleOptions(_RecursiveCommon):
    """Options of the paper's bundle method (paper symbols; see
    `RecursiveIdentifier`): eta0, k1, delta, q, q_star, gamma, eta_max,
    rho, n_ls, step_bound, full_step_test, predictor, m_min,
    divergence_limit."""

    eta0: float = 0.015
    k1: int = 6
    delta: float = 1e-4
    q: float = 0.1
    q_star: float = 0.5
    gamma: float = 0.5
    eta_max: float = None
    rho: float = 0.5
    n_ls: int = 10
    step_bound: bool = False
    full_step_test: bool = False
    predictor: str = 'series-parallel'

    method = 'bundle'

    def __post_init__(self):
        self._check_predictor()
        self._check_common()
        self._set('k1', check_int('k1', self.k1, 1, MOST_STARTS))
        eta0 = check_positive('eta0', self.eta0)
        if eta0 > 1:
            raise ValueError(f"eta0 must be in (0, 1] (eq. (3.7)); got "
                             f"{eta0}")
        self._set('eta0', eta0)
        self._set('delta', check_positive('delta', self.delta))
        self._check_steps(eta0)
        self._set('n_ls', check_int('n_ls', self.n_ls, 0, MOST_STARTS))
        self._set('step_bound', check_bool('step_bound', self.step_bound))
        self._set('full_step_test',
                  check_bool('full_step_test', self.full_step_test))

    def _check_steps(self, eta0):
        """q, q_star, gamma, eta_max and rho of the line search."""
        q = check_finite('q', self.q)
        if not 0 < q < 0.5:
            raise ValueError(f"q must be in (0, 0.5) (eq. (3.7)); got {q}")
        q_star = check_finite('q_star', self.q_star)
        if not q < q_star < 1:
            raise ValueError(f"q_star must be in (q, 1) = ({q}, 1) (eq. "
                             f"(3.7)); got {q_star}")
        self._set('q', q)
        self._set('q_star', q_star)
        self._set('gamma', check_nonnegative('gamma', self.gamma))
        eta_max = eta0 if self.eta_max is None else check_positive(
            'eta_max', self.eta_max)
        if not eta0 <= eta_max <= 1:
            raise ValueError(f"eta_max must be in [eta0, 1] = [{eta0}, 1]; "
                             f"got {eta_max}")
        self._set('eta_max', eta_max)
        rho = check_finite('rho', self.rho)
        if not 0 < rho < 1:
            raise ValueError(f"rho must be in (0, 1); got {rho}")
        self._set('rho', rho)


#: Readings of "the nonsmooth points are omitted" (Section 5) for the
#: gradient baseline, see `RecursiveIdentifier`.
NONSMOOTH_READINGS = ('skip', 'subgradient')


@dataclasses.dataclass(frozen=True)
class GradientOptions(_RecursiveCommon):
    """Options of the gradient baseline: mu (step size), nonsmooth
    ('skip' or 'subgradient'; skip_nonsmooth=True/False is its older
    spelling, and both may be given only if they agree), predictor,
    m_min, divergence_limit."""

    mu: float = 0.009
    nonsmooth: str = None
    skip_nonsmooth: bool = None
    predictor: str = 'series-parallel'

    method = 'gradient'

    def __post_init__(self):
        self._check_predictor()
        self._check_common()
        self._set('mu', check_positive('mu', self.mu))
        reading = 'skip' if self.nonsmooth is None else self.nonsmooth
        if reading not in NONSMOOTH_READINGS:
            raise ValueError(f"nonsmooth must be one of "
                             f"{NONSMOOTH_READINGS}; got {reading!r}")
        old = self.skip_nonsmooth
        if old is not None:
            implied = ('skip' if check_bool('skip_nonsmooth', old)
                       else 'subgradient')
            if self.nonsmooth is not None and reading != implied:
                raise ValueError(
                    f"skip_nonsmooth={old} means nonsmooth={implied!r}, but "
                    f"nonsmooth={reading!r} was given; pass only nonsmooth")
            reading = implied
        self._set('nonsmooth', reading)
        self._set('skip_nonsmooth', reading == 'skip')


@dataclasses.dataclass(frozen=True)
class RPEMOptions(_RecursiveCommon):
    """Options of the recursive prediction-error estimator: lam0,
    lam_start (forgetting factors in (0, 1]), P0, p_max, max_step,
    warmup, m_min, err_limit, divergence_limit."""

    lam0: float = 0.99
    lam_start: float = 0.95
    P0: float = 10.0
    p_max: float = 1e6
    max_step: float = 0.5
    warmup: int = 0
    err_limit: float = 1e6

    method = 'rpem'

    def __post_init__(self):
        for name in ('lam0', 'lam_start'):
            val = check_finite(name, getattr(self, name))
            if not 0 < val <= 1:
                raise ValueError(f"{name} must be in (0, 1]; got {val}")
            self._set(name, val)
        for name in ('P0', 'p_max', 'max_step', 'm_min', 'err_limit',
                     'divergence_limit'):
            self._set(name, check_positive(name, getattr(self, name)))
        self._set('warmup', check_int('warmup', self.warmup, 0,
                                       MOST_SAMPLES))


#: The option class of each method.
OPTIONS = {'oe': OEOptions, 'bundle': BundleOptions,
           'gradient': GradientOptions, 'rpem': RPEMOptions}


def method_options(method, options):
    """The options of `method` from the dict `options`: TypeError naming
    the method for one that does not apply to it."""
    if not isinstance(method, str) or method not in OPTIONS:
        raise ValueError(f"method must be one of {list(METHODS)}; got "
                         f"{method!r}")
    cls = OPTIONS[method]
    valid = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(options) - set(valid))
    if unknown:
        raise TypeError(f"unknown option(s) {unknown} for method={method!r} "
                        f"(they do not apply to it); valid options are "
                        f"{sorted(valid)}")
    return cls(**options)
