r"""The scaled output-error problem and its parametrisation (private).

The batch identifiers (`refine`, `identify`) minimise the output-error
cost (2.6) in a *reduced* parameter vector phi of a `Parametrisation`:

- the data are scaled (`Problem`: u / su, s y / sy), so the numbers the
  optimiser sees do not depend on the data's units, and the sign s of the
  overall gain is taken out of the parameters (the backlash slopes stay
  positive);
- poles fixed at z = 1 (integrators) are factored out of L1's or L2's
  denominator, ``A(q) = (1 - q^-1)^i A'(q)``, so that only A' is free and
  only A' must stay stable;
- output offsets and initial conditions per experiment, when estimated,
  follow the model's parameters in phi.

The full parameter vector of eq. (2.5), theta, is the affine image
``theta = t0 + T phi``: the Jacobian of the simulated output with respect
to phi is ``J_theta T``. The solver is `_lm.lm`; `Problem.result` maps its
output to an `IdentificationResult` in the user's units and judges it
(`result.verdict`).
"""

import numpy as np

from ._data import scale as _scale, scaled
from ._predictor import (simulate_with_sensitivities, oe_output, sp_output,
                         smooth_output, is_stable, init_sizes, oe_signals)
from .result import (IdentificationResult, backlash_significance,
                     whiteness, verdict, judge, poorly_determined,
                     MIN_FIT)
from ..model.sandwich import SandwichSystem

__all__ = []

#: Free poles are kept inside |z| < 1 - STABILITY_MARGIN.
STABILITY_MARGIN = 1e-4
#: Zeros of L1 and L2 are kept inside |z| < ZERO_RADIUS (or the start's
#: largest zero times 1.5, if larger): with b0 = d0 = 1 a zero escaping to
#: infinity trades for a vanishing slope m and a growing width D, a
#: degenerate valley that looks like one more sample of delay.
ZERO_RADIUS = 20.0
#: With a minimum-phase L1 (``identify(..., minimum_phase='L1')``), L1's
#: zeros are kept inside |z| < MINIMUM_PHASE_RADIUS.
MINIMUM_PHASE_RADIUS = 1 - 1e-3


def integrator_poly(i):
    """Coefficients of (1 - q^-1)^i, ascending powers of q^-1."""
    p = np.ones(1)
    for _ in range(i):
        p = np.convolve(p, [1.0, -1.0])
    return p


class Parametrisation:
    """Orders, delays and integrators of a sandwich; the map phi -> theta.

    Parameters
    ----------
    orders : tuple of int
        (na, nb, nc, nd, q1, q2): orders of eq. (2.1), integrators
        included in na and nc, and the delays.
    i1, i2 : int
        Poles fixed at z = 1 in L1 and L2.
    zero_radius : float
        Zeros are kept inside this radius (see `ZERO_RADIUS`).
    n_offsets, n_inits : int
        Experiments with an output offset, and with initial conditions,
        estimated (their entries follow the model's in phi).
    minimum_phase : {None, 'L1'}
        'L1': L1's zeros are kept inside `MINIMUM_PHASE_RADIUS` (`stable`;
        `minimum_phase_start` moves a start there).
    """

    def __init__(self, orders, i1=0, i2=0, *, zero_radius=ZERO_RADIUS,
                 n_offsets=0, n_inits=0, minimum_phase=None):
        na, nb, nc, nd, q1, q2 = orders
        if not (0 <= i1 <= na and 0 <= i2 <= nc):
            raise ValueError(f"integrators ({i1}, {i2}) exceed the orders "
                             f"na = {na}, nc = {nc}")
        self.o = (na, nb, nc, nd, q1, q2)
        self.i1, self.i2 = i1, i2
        self.p = nc + na + 4 + nb + nd
        self.q = self.p - i1 - i2
        self.nc_free, self.na_free = nc - i2, na - i1
        self.im = self.nc_free + self.na_free      # m1 in phi
        self.im_theta = nc + na                    # m1 in theta
        self.zero_radius = zero_radius
        self.minimum_phase = minimum_phase
        self.n_off = n_offsets                     # output offsets, next
        self.init_sizes = init_sizes(self.o)
        self.n_init = sum(self.init_sizes)         # per experiment
        self.n_inits = n_inits                     # experiments, last
        self.size = self.q + n_offsets + n_inits * self.n_init
        self.t0 = self._affine(np.zeros(self.q))
        self.T = np.column_stack([self._affine(e) - self.t0
                                  for e in np.eye(self.q)]) if self.q else \
            np.zeros((self.p, 0))

    def _affine(self, phi):
        c_free, a_free = phi[:self.nc_free], phi[self.nc_free:self.im]
        c = np.convolve(np.r_[1.0, c_free], integrator_poly(self.i2))[1:]
        a = np.convolve(np.r_[1.0, a_free], integrator_poly(self.i1))[1:]
        return np.concatenate([c, a, phi[self.im:]])

    def theta(self, phi):
        """Full parameter vector of eq. (2.5)."""
        return self.t0 + self.T @ phi[:self.q]

    def extend(self, phi):
        """A model's reduced vector with zero output offsets and initial
        conditions appended."""
        return np.concatenate([phi[:self.q],
                               np.zeros(self.size - self.q)])

    def init(self, phi, e):
        """(x_past, v_past, y_past) of experiment e, or None."""
        if not self.n_inits:
            return None
        start = self.q + self.n_off + e * self.n_init
        kx, kv, ky = self.init_sizes
        vals = phi[start:start + self.n_init]
        return vals[:kx], vals[kx:kx + kv], vals[kx + kv:]

    def phi(self, theta):
        """Reduced vector of a theta whose denominators hold the
        integrators (their remainder after division is dropped)."""
        na, nb, nc, nd = self.o[:4]
        c, a = theta[:nc], theta[nc:nc + na]
        c_free = np.polydiv(np.r_[1.0, c], integrator_poly(self.i2))[0]
        a_free = np.polydiv(np.r_[1.0, a], integrator_poly(self.i1))[0]
        return self.extend(np.concatenate([c_free[1:], a_free[1:],
                                           theta[nc + na:]]))

    def stable(self, phi):
        """Finite, the free denominators strictly stable and the zeros
        inside `zero_radius` (L1's inside `MINIMUM_PHASE_RADIUS` with a
        minimum-phase L1)."""
        nb, nd = self.o[1], self.o[3]
        ib = self.im + 4
        margin = 1.0 - self.zero_radius
        l1_margin = 1.0 - MINIMUM_PHASE_RADIUS if self.minimum_phase \
            else margin
        return (self.poles_stable(phi)
                and is_stable(phi, ib, nb, l1_margin)
                and is_stable(phi, ib + nb, nd, margin))

    def minimum_phase_start(self, phi):
        """phi with L1's zeros outside `MINIMUM_PHASE_RADIUS` reflected to
        1 / conj(z) (an all-pass factor apart, the same magnitude
        response: the slopes times |z| and the widths over it keep the
        backlash output), and those still outside pulled in to it; phi
        itself without a minimum-phase L1 or with L1's zeros inside."""
        nb, ib = self.o[1], self.im + 4
        if not (self.minimum_phase and nb) or \
                is_stable(phi, ib, nb, 1.0 - MINIMUM_PHASE_RADIUS):
            return phi
        with np.errstate(all='ignore'):
            z = np.roots(np.r_[1.0, phi[ib:ib + nb]])
        if not np.all(np.isfinite(z)):
            return phi
        inside = 0.99 * MINIMUM_PHASE_RADIUS
        far = np.abs(z) > inside
        k = float(np.prod(np.abs(z[far])))   # L1's gain over the new one's
        z[far] = 1 / np.conj(z[far])
        far = np.abs(z) > inside
        z[far] *= inside / np.abs(z[far])
        phi = phi.copy()
        phi[ib:ib + nb] = np.real(np.poly(z))[1:]
        phi[self.im:self.im + 2] *= k
        phi[self.im + 2:self.im + 4] /= k
        return phi

    def poles_stable(self, phi):
        """Finite, and the free denominators strictly stable."""
        return (bool(np.all(np.isfinite(phi)))
                and is_stable(phi, 0, self.nc_free, STABILITY_MARGIN)
                and is_stable(phi, self.nc_free, self.na_free,
                              STABILITY_MARGIN))

    def widen_zero_radius(self, phi):
        """Let the zeros of a start be admissible: radius >= 1.5 max|z|."""
        nb, nd = self.o[1], self.o[3]
        ib = self.im + 4
        for start, n in ((ib, nb), (ib + nb, nd)):
            if n:
                z = np.roots(np.r_[1.0, phi[start:start + n]])
                self.zero_radius = max(self.zero_radius,
                                       1.5 * float(np.max(np.abs(z))))

    def minimum_phase_bound(self, phi, share=0.99):
        """`MINIMUM_PHASE_RADIUS` if L1 is kept minimum-phase and a zero
        of L1 is at |z| >= share times it, else None."""
        nb, ib = self.o[1], self.im + 4
        if not (self.minimum_phase and nb):
            return None
        with np.errstate(all='ignore'):
            z = np.roots(np.r_[1.0, phi[ib:ib + nb]])
        return MINIMUM_PHASE_RADIUS if np.any(
            np.abs(z) >= share * MINIMUM_PHASE_RADIUS) else None

    def zeros_at_bound(self, phi, share=0.99):
        """Blocks ('L1', 'L2') with a zero at |z| >= share * zero_radius:
        the search pressed it against its bound, the sign of a degenerate
        optimum (see `ZERO_RADIUS`)."""
        nb, nd = self.o[1], self.o[3]
        ib = self.im + 4
        out = []
        for name, start, n in (('L1', ib, nb), ('L2', ib + nb, nd)):
            if n and np.isfinite(self.zero_radius):
                with np.errstate(all='ignore'):
                    z = np.roots(np.r_[1.0, phi[start:start + n]])
                if np.any(np.abs(z) >= share * self.zero_radius):
                    out.append(name)
        return out

    def bounds(self, phi, m_min):
        """Box for a step d: m + d >= m_min, D + d >= 0."""
        lo = np.full(self.size, -np.inf)
        hi = np.full(self.size, np.inf)
        im = self.im
        lo[im:im + 2] = m_min - phi[im:im + 2]
        lo[im + 2:im + 4] = -phi[im + 2:im + 4]
        return lo, hi

    def clip(self, phi, m_min):
        phi = phi.copy()
        im = self.im
        phi[im:im + 2] = np.maximum(phi[im:im + 2], m_min)
        phi[im + 2:im + 4] = np.maximum(phi[im + 2:im + 4], 0.0)
        return phi

    def _init_jacobian(self, phi, e, u, yhat, *, theta, sp, ymeas):
        """Columns for every experiment's initial conditions: those of
        experiment e by forward differences, the others zero."""
        out = np.zeros((u.size, self.n_inits * self.n_init))
        start = self.q + self.n_off + e * self.n_init
        for j in range(self.n_init):
            step = 1e-6 * max(1.0, abs(phi[start + j]))
            trial = phi.copy()
            trial[start + j] += step
            init = self.init(trial, e)
            with np.errstate(all='ignore'):
                if sp:
                    moved = simulate_with_sensitivities(theta, self.o, u,
                                                        ymeas, init)[0]
                else:
                    moved = oe_output(theta, self.o, u, init)
            out[:, e * self.n_init + j] = (moved - yhat) / step
        return out

    def _offsets(self, phi, n_exp):
        if self.n_off not in (0, n_exp):
            raise ValueError(f"{self.n_off} offsets for {n_exp} experiments")
        return phi[self.q:] if self.n_off else np.zeros(n_exp)

    def residuals(self, phi, u, y, sp=False, eps=0.0):
        """Output errors over the experiments (lists u and y), stacked;
        with ``sp`` the series-parallel prediction errors, with eps > 0
        those of the smoothed backlash (`smooth_output`)."""
        theta = self.theta(phi)
        off = self._offsets(phi, len(u))
        with np.errstate(all='ignore'):
            if sp:
                return np.concatenate([
                    yy - c - sp_output(theta, self.o, uu, yy - c,
                                       self.init(phi, e))
                    for e, (uu, yy, c) in enumerate(zip(u, y, off))])
            if eps > 0:
                return np.concatenate([
                    yy - smooth_output(theta, self.o, uu, eps,
                                       self.init(phi, e)) - c
                    for e, (uu, yy, c) in enumerate(zip(u, y, off))])
            return np.concatenate([
                yy - oe_output(theta, self.o, uu, self.init(phi, e)) - c
                for e, (uu, yy, c) in enumerate(zip(u, y, off))])

    def cost(self, phi, u, y, sp=False):
        """Output-error cost 0.5 * sum(r^2) over the experiments (lists u
        and y; inf if not finite); with ``sp`` the series-parallel
        prediction error instead."""
        r = self.residuals(phi, u, y, sp)
        with np.errstate(all='ignore'):
            c = 0.5 * float(r @ r)
        return c if np.isfinite(c) else np.inf

    def jacobian(self, phi, u, y, sp=False):
        """(residuals, Jacobian of y_hat w.r.t. phi, zones), the
        experiments (lists u and y) stacked; each experiment starts from
        rest and has its own output offset when the structure has them."""
        theta = self.theta(phi)
        off = self._offsets(phi, len(u))
        rs, Js, zs = [], [], []
        for e, (uu, yy) in enumerate(zip(u, y)):
            init = self.init(phi, e)
            with np.errstate(all='ignore'):
                yhat, J, zones = simulate_with_sensitivities(
                    theta, self.o, uu, yy - off[e] if sp else None, init)
                if self.i1 or self.i2:
                    J = J @ self.T          # else T is the identity
            cols = [J]
            if self.n_off:
                ind = np.zeros((uu.size, self.n_off))
                ind[:, e] = 1.0
                cols.append(ind)
            if self.n_inits:
                cols.append(self._init_jacobian(phi, e, uu, yhat,
                                                theta=theta, sp=sp,
                                                ymeas=yy - off[e]))
            J = np.hstack(cols) if len(cols) > 1 else J
            rs.append(yy - yhat - off[e])
            Js.append(J)
            zs.append(zones)
        if len(rs) == 1:
            return rs[0], Js[0], zs[0]
        return np.concatenate(rs), np.vstack(Js), np.concatenate(zs)


def unit_poles(den, tol=1e-9):
    """How many roots of the monic denominator 1, a1, ... sit at z = 1."""
    poly = np.r_[1.0, den]
    count = 0
    while poly.size > 1 and abs(np.polyval(poly, 1.0)) <= tol * np.sum(
            np.abs(poly)):
        poly = np.polydiv(poly, [1.0, -1.0])[0]
        count += 1
    return count


class Problem:
    """A scaled output-error problem: data, structure, sign (private).

    Holds ``u / su`` and ``sign * y / sy`` and maps reduced parameters
    phi (see `Parametrisation`) to models and results in the user's units.
    """

    def __init__(self, u, y, orders, *, i1=0, i2=0, sign=1, dt=True,
                 name=None, offsets=False, inits=False, minimum_phase=None):
        us = list(u) if isinstance(u, list) else [u]
        ys = list(y) if isinstance(y, list) else [y]
        self.orders = {k: orders[k] for k in ('na', 'nb', 'nc', 'nd', 'q1',
                                               'q2')}
        self.st = Parametrisation(tuple(self.orders.values()), i1, i2,
                                  n_offsets=len(us) if offsets else 0,
                                  n_inits=len(us) if inits else 0,
                                  minimum_phase=minimum_phase)
        self.sign = 1 if sign >= 0 else -1
        self.su = _scale(np.concatenate(us))
        self.sy = _scale(np.concatenate(ys))
        self.u_user, self.y_user = us, ys
        self.u = [scaled(part, self.su) for part in us]
        self.y = [self.sign * scaled(part, self.sy) for part in ys]
        self.n_samples = sum(part.size for part in us)
        self.dt, self.name = dt, name
        # theta_user = theta_scaled * unit: slopes sy/su, thresholds su
        im = self.st.im_theta
        self.unit = np.ones(self.st.p)
        self.unit[im:im + 2] = self.sy / self.su
        self.unit[im + 2:im + 4] = self.su

    def phi_of_model(self, model):
        """Reduced scaled parameters of a model of this structure."""
        theta = model.normalized().theta / self.unit
        return self.st.phi(theta)

    def evaluate(self, model):
        """A model of this structure on these data: (its output-error cost
        on the scaled data, in the units of `lm`'s cost and of the linear
        baseline's ``cost_scaled``; its cost and its fit in the user's
        units). Not finite for a model that diverges on them."""
        with np.errstate(all='ignore'):
            phi = self.phi_of_model(model)
            _, cost, fit = self._fit(phi)
            return self.st.cost(phi, self.u, self.y), cost, float(fit)

    def model(self, phi):
        """The model of phi in the user's units (signed normalisation)."""
        return SandwichSystem.from_theta(
            self.st.theta(phi) * self.unit, **self.orders, dt=self.dt,
            name=self.name, sign=self.sign)

    def result(self, out, method, linear=None, extra=None, min_fit=MIN_FIT):
        """The `IdentificationResult` of an `_lm.lm` output `out`, judged
        by `result.verdict`. An `out` with ``fallback`` (the linear fit as
        a sandwich, see `_search`) is not judged on convergence."""
        phi = out['phi']
        theta = self.st.theta(phi) * self.unit
        n, q = self.n_samples, self.st.size
        r, cost, fit = self._fit(phi)
        std = self._std(out, theta)
        stable = self.st.poles_stable(phi)
        finite = bool(np.all(np.isfinite(theta)) and np.isfinite(cost))
        labels = SandwichSystem.from_theta(
            theta, **self.orders).theta_labels
        with np.errstate(over='ignore', invalid='ignore'):  # diverged: inf
            white = whiteness(r)
        failed = verdict(
            finite=finite, stable=stable,
            converged=None if out.get('fallback') else out['converged'],
            zeros_at_bound=self.st.zeros_at_bound(phi) if stable else [],
            zero_radius=self.st.zero_radius, fit=fit, min_fit=min_fit,
            linear=linear, cost_scaled=out['cost'], std=std, theta=theta,
            labels=labels, minimum_phase_bound=self.st.minimum_phase_bound(
                phi))
        res = IdentificationResult(
            model=self.model(phi), theta=theta, history=np.zeros((0,
                                                                  theta.size)),
            errors=r, counts={'iterations': out['nit']},
            success=True, message=out['message'], method=method,
            options={}, orders=dict(self.orders), theta_labels=labels,
            nit=out['nit'], std=std, fit=float(fit), cost=cost,
            integrators={'L1': self.st.i1, 'L2': self.st.i2},
            linear=linear, significance=None if linear is None else
            backlash_significance(linear['cost'], cost, linear['n_params'],
                                  q, n),
            whiteness=white, converged=bool(out['converged']
                                                   or out.get('fallback')),
            n_experiments=len(self.u))
        judge(res, failed)
        if self.st.n_off:
            res.offsets = {'method': 'estimate', 'u': [0.0] * len(self.u),
                           'y': list(self.sign * self.sy * phi[
                               self.st.q:self.st.q + self.st.n_off])}
        if self.st.n_inits:
            res.initial_conditions = [
                {'x_past': self.su * x, 'v_past': self.sy * v,
                 'y_past': self.sign * self.sy * yy}
                for x, v, yy in (self.st.init(phi, e)
                                 for e in range(self.st.n_inits))]
        res.crossing = self._crossing(phi, res.model.backlash)
        if extra:
            res.update(extra)
        return res

    def _fit(self, phi):
        """(residuals, cost, fit) in the user's units, on the data as
        given (the search ran on their rounded scaled copy, see
        `_data.scaled`)."""
        y_all = np.concatenate(self.y_user)
        r = self.sign * self.sy * self.st.residuals(
            phi, [part / self.su for part in self.u_user],
            [self.sign * part / self.sy for part in self.y_user])
        with np.errstate(over='ignore', invalid='ignore'):   # diverged
            cost = 0.5 * float(r @ r)
            denom = np.linalg.norm(y_all - y_all.mean())
            fit = 100 * (1 - np.linalg.norm(r) / denom) if denom > 0 \
                else -np.inf
        return r, cost, fit

    def poorly_determined(self, out):
        """Whether the data leave a parameter of the `lm` output `out`
        poorly determined (`result.poorly_determined`), as the verdict
        of its result would say."""
        theta = self.st.theta(out['phi']) * self.unit
        return bool(np.any(poorly_determined(self._std(out, theta), theta)))

    def _std(self, out, theta):
        """Standard errors of theta, sigma^2 (J'J)^-1 mapped through the
        parametrisation (inf where J is not finite)."""
        J = out['J']
        sigma2 = 2 * out['cost'] / max(self.n_samples - self.st.size, 1)
        std = np.full(theta.size, np.inf)
        if np.all(np.isfinite(J)):
            with np.errstate(all='ignore'):
                try:
                    cov_phi = sigma2 * np.linalg.pinv(J.T @ J)
                except np.linalg.LinAlgError:   # the SVD did not converge
                    return std                  # (J'J of enormous range)
                T = self.st.T * self.unit[:, None]
                cov_model = cov_phi[:self.st.q, :self.st.q]
                std = np.sqrt(np.clip(np.diag(T @ cov_model @ T.T), 0,
                                      None))
        return std

    def _crossing(self, phi, backlash):
        """Where the model's slope lines cross (`Backlash.crossing`, in
        u's units; None if m1 == m2) and the share of the samples its x
        spends beyond: {'x': ..., 'share': ...}."""
        cross = backlash.crossing
        if cross is None:
            return {'x': None, 'share': 0.0}
        theta = self.st.theta(phi)
        with np.errstate(all='ignore'):
            x = self.su * np.concatenate([
                oe_signals(theta, self.st.o, uu, self.st.init(phi, e))[1]
                for e, uu in enumerate(self.u)])
            beyond = x < cross if backlash.m1 < backlash.m2 else x > cross
        return {'x': float(cross), 'share': float(np.mean(beyond))}
