"""Ready-made plants and signals from the paper.

`paper_plant` is the simulation example of Section 5, eqs. (5.1)-(5.2).
"""

import numpy as np

from .sandwich import SandwichSystem
from ._validation import check_int, check_positive

__all__ = ['paper_plant', 'paper_input', 'add_noise', 'PAPER_THETA0']

#: Starting point theta_0 of the Section 5 study (order of eq. (2.5)).
PAPER_THETA0 = np.array([0, 0, 0, 0, 0.1, 0.1, 0.1, 0.1, 0.0])


def paper_plant(dt=1, name='paper'):
    """The sandwich system of Section 5 (eqs. (5.1) and (5.2)).

    L1: x(k) = -0.1 x(k-1) - 0.2 x(k-2) + 1.5 u(k-1), i.e.
    ``ct.tf([1.5, 0], [1, 0.1, 0.2], dt)``; backlash m1 = 1, m2 = 1.2,
    D1 = 0.5, D2 = 0.6; L2: y(k) = -1.2 y(k-1) - 0.32 y(k-2) + 2 v(k-1)
    - 0.1 v(k-2), i.e. ``ct.tf([2, -0.1], [1, 1.2, 0.32], dt)``.

    Its normalised form (b0 = d0 = 1) has theta = (c1, c2, a1, a2, m1, m2,
    D1, D2, d1) = (1.2, 0.32, 0.1, 0.2, 3, 3.6, 1/3, 0.4, -0.05).

    Parameters
    ----------
    dt : float or True, optional
        Sampling time (default 1).
    name : str, optional
        System name.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> sw.examples.paper_plant().normalized().theta.round(4)
    array([ 1.2   ,  0.32  ,  0.1   ,  0.2   ,  3.    ,  3.6   ,  0.3333,
            0.4   , -0.05  ])
    """
    return SandwichSystem.from_coefficients(
        a=[0.1, 0.2], b=[1.5], c=[1.2, 0.32], d=[2.0, -0.1],
        m1=1.0, m2=1.2, D1=0.5, D2=0.6, q1=1, q2=1, dt=dt, name=name)


def paper_input(n, variance=0.49, seed=None):
    """The Section 5 excitation: white Gaussian noise of variance 0.49.

    Parameters
    ----------
    n : int
        Number of samples.
    variance : float, optional
        Variance of u (default 0.49, the paper's sigma^2).
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.
    """
    n = check_int('n', n, minimum=1)
    variance = check_positive('variance', variance)
    rng = np.random.default_rng(seed)
    return np.sqrt(variance) * rng.standard_normal(n)


def add_noise(y, snr, seed=None):
    """Add white Gaussian output noise at a given signal-to-noise ratio.

    The SNR is the variance ratio var(y) / var(noise), the natural
    reading of Section 5's "SNR equal to 46.5".

    Parameters
    ----------
    y : array_like
        Noise-free output.
    snr : float
        Variance ratio, > 0.
    seed : int or numpy.random.Generator, optional
        Seed for `numpy.random.default_rng`.

    Returns
    -------
    ndarray
        y plus noise of variance var(y) / snr.

    Examples
    --------
    >>> import numpy as np, sandwichctl as sw
    >>> y = np.sin(np.arange(100000) * 0.1)
    >>> noisy = sw.examples.add_noise(y, 46.5, seed=0)
    >>> round(float(np.var(y) / np.var(noisy - y)))
    46
    """
    y = np.asarray(y, dtype=float)
    snr = check_positive('snr', snr)
    rng = np.random.default_rng(seed)
    return y + rng.standard_normal(y.shape) * np.sqrt(np.var(y) / snr)
