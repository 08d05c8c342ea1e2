"""Levenberg-Marquardt on the output-error cost (`_lm`)."""

import types

import numpy as np

from sandwichctl.identification._lm import _damped_step


def _flat(n):
    """A parametrisation of n free parameters whose cost never falls below
    the current one, so that the damping grows until it gives up."""
    return types.SimpleNamespace(
        bounds=lambda phi, m_min: (np.full(n, -np.inf), np.full(n, np.inf)),
        clip=lambda phi, m_min: phi, stable=lambda phi: True,
        cost=lambda phi, u, y, sp: 2.0)


def test_a_huge_jacobian_gives_up_without_overflowing():
    """Columns of 1e150 (a Jacobian near an unstable candidate of the
    search) make J'J's diagonal 1e300: the damping used to grow past where
    mu times it overflows, and numpy's RuntimeWarning reached the user of
    identify (random_case 1661745229 of family 6). Now the step gives up
    where the damped matrix stops being finite, with the same outcome as
    before: no step. Under pytest any warning fails the test."""
    Jf = np.diag([1e150, 3e149])
    r = np.array([1.0, -1.0])
    trial, cost, mu = _damped_step(
        _flat(2), np.zeros(2), Jf, r, 1e-3, cost=1.0, free=slice(None),
        m_min=1e-9, data=(None, None, False))
    assert trial is None and cost is None
    assert np.isfinite(mu) and 1e-3 < mu < 1e12
