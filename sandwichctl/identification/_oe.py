r"""Output-error fitting of a sandwich structure (private).

The batch identifiers (`refine`, `identify`) minimise the output-error
cost (2.6) in a *reduced* parameter vector phi of a `Structure`:

- the data are scaled by the caller (u / su, s y / sy), so the numbers the
  optimiser sees do not depend on the data's units, and the sign s of the
  overall gain is taken out of the parameters (the backlash slopes stay
  positive);
- poles fixed at z = 1 (integrators) are factored out of L1's or L2's
  denominator, ``A(q) = (1 - q^-1)^i A'(q)``, so that only A' is free and
  only A' must stay stable.

The full parameter vector of eq. (2.5), theta, is the affine image
``theta = t0 + T phi``: the Jacobian of the simulated output with respect
to phi is ``J_theta T``. Levenberg-Marquardt steps are solved as box QPs
(m1, m2 >= m_min, D1, D2 >= 0); a step is accepted only if the cost
decreases and the free denominators stay stable, which copes with the
kinks of the cost (see `refine`).
"""

import numpy as np

from ._predictor import (simulate_with_sensitivities, oe_output, sp_output,
                         smooth_output, is_stable, init_sizes)
from ._qp import box_qp, QPError

__all__ = []

#: Free poles are kept inside |z| < 1 - STABILITY_MARGIN.
STABILITY_MARGIN = 1e-4
#: A run stopped at max_iter counts as converged when its last decrease
#: and the Gauss-Newton prediction of what is left are both below this
#: share of the output's energy (the fit would change in its sixth digit).
CONVERGED = 1e-6
#: Zeros of L1 and L2 are kept inside |z| < ZERO_RADIUS (or the start's
#: largest zero times 1.5, if larger): with b0 = d0 = 1 a zero escaping to
#: infinity trades for a vanishing slope m and a growing width D, a
#: degenerate valley that looks like one more sample of delay.
ZERO_RADIUS = 20.0


def integrator_poly(i):
    """Coefficients of (1 - q^-1)^i, ascending powers of q^-1."""
    p = np.ones(1)
    for _ in range(i):
        p = np.convolve(p, [1.0, -1.0])
    return p


class Structure:
    """Orders, delays and integrators of a sandwich; the map phi -> theta.

    Parameters
    ----------
    na, nb, nc, nd, q1, q2 : int
        Orders of eq. (2.1), integrators included in na and nc.
    i1, i2 : int
        Poles fixed at z = 1 in L1 and L2.
    """

    def __init__(self, na, nb, nc, nd, q1, q2, i1=0, i2=0,
                 zero_radius=ZERO_RADIUS, n_offsets=0, n_inits=0):
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
        inside `zero_radius`."""
        nb, nd = self.o[1], self.o[3]
        ib = self.im + 4
        margin = 1.0 - self.zero_radius
        return (self.poles_stable(phi)
                and is_stable(phi, ib, nb, margin)
                and is_stable(phi, ib + nb, nd, margin))

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

    def _init_jacobian(self, phi, e, u, yhat, theta, sp, ymeas):
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
                cols.append(self._init_jacobian(phi, e, uu, yhat, theta,
                                                sp, yy - off[e]))
            J = np.hstack(cols) if len(cols) > 1 else J
            rs.append(yy - yhat - off[e])
            Js.append(J)
            zs.append(zones)
        if len(rs) == 1:
            return rs[0], Js[0], zs[0]
        return np.concatenate(rs), np.vstack(Js), np.concatenate(zs)


def _step(A, g, lo, hi):
    """Minimise 0.5 d'A d - g'd over lo <= d <= hi (None if it fails).

    The unconstrained minimiser is tried first (the bounds rarely bind);
    piqp solves the box QP otherwise.
    """
    try:
        d = np.linalg.solve(A, g)
        if np.all(np.isfinite(d)) and np.all(d >= lo) and np.all(d <= hi):
            return d
    except np.linalg.LinAlgError:
        pass
    try:
        return box_qp(A, -g, lo, hi)
    except QPError:
        return None


def lm(st, phi, u, y, max_iter=100, tol=1e-10, m_min=1e-9, sp=False,
       fixed=None):
    """Levenberg-Marquardt on the output-error cost, from an admissible phi.

    Every accepted step lowers the cost and keeps the structure stable, so
    the final cost is at most the starting cost. With ``sp`` the
    series-parallel prediction error is minimised instead (a smoother
    cost, biased under noise: a way to a start). ``fixed`` (a boolean
    mask) holds some parameters at their values. Returns a dict with phi,
    cost, J, r, nit, converged and message.
    """
    free = slice(None) if fixed is None else ~np.asarray(fixed)
    r, J, _ = st.jacobian(phi, u, y, sp)
    cost = 0.5 * float(r @ r)
    if not (np.isfinite(cost) and np.all(np.isfinite(J))):
        return dict(phi=phi, cost=np.inf if not np.isfinite(cost) else cost,
                    J=J, r=r, nit=0, converged=False,
                    message="the start does not give a finite output and "
                            "Jacobian")
    mu = 1e-3
    message, converged = f"stopped at max_iter = {max_iter}", False
    last_decrease = np.inf
    it = 0
    for it in range(1, max_iter + 1):
        Jf = J[:, free]
        A = Jf.T @ Jf
        g = Jf.T @ r
        diag = np.diag(A).copy()
        scale = np.maximum(diag, 1e-12 * max(float(np.max(diag, initial=0)),
                                             1e-300))
        lo, hi = st.bounds(phi, m_min)
        lo, hi = lo[free], hi[free]
        accepted = False
        while mu < 1e12:
            d = _step(A + mu * np.diag(scale), g, lo, hi)
            if d is None:
                mu *= 10
                continue
            full = np.zeros(phi.size)
            full[free] = d
            trial = st.clip(phi + full, m_min)
            if not st.stable(trial):
                mu *= 10
                continue
            cost_t = st.cost(trial, u, y, sp)
            if cost_t < cost:
                accepted = True
                break
            mu *= 10
        if not accepted:
            message = ("converged: no step decreases the cost (a minimum, "
                       "possibly at a kink)")
            converged = True
            break
        last_decrease = (cost - cost_t) / max(cost, 1e-300)
        step = np.linalg.norm(trial - phi)
        phi = trial
        r, J, _ = st.jacobian(phi, u, y, sp)
        cost = 0.5 * float(r @ r)
        mu = max(mu / 3, 1e-9)
        if not np.all(np.isfinite(J)):
            message = "stopped: the Jacobian is not finite"
            break
        if last_decrease < tol or step < tol * (1 + np.linalg.norm(phi)):
            message = (f"converged: relative decrease {last_decrease:.1e} "
                       f"or step {step:.1e} below tol")
            converged = True
            break
    if not converged and np.isfinite(cost) and np.all(np.isfinite(J)):
        # stopped at max_iter: converged if what is left is negligible, by
        # the last step and by the Gauss-Newton model of the cost
        Jf = J[:, free]
        g = Jf.T @ r
        A = Jf.T @ Jf
        with np.errstate(all='ignore'):
            d = np.linalg.lstsq(A, g, rcond=1e-12)[0]
        predicted = 0.5 * float(g @ d) / max(cost, 1e-300)
        # what is left, relative to the output's energy: a change of the
        # fit in the sixth digit is not worth more iterations
        yc = np.concatenate(y)
        energy = 0.5 * float(np.sum((yc - np.mean(yc)) ** 2))
        share = cost / max(energy, 1e-300)
        if max(last_decrease, predicted) * share < CONVERGED:
            converged = True
            message += (f" (last relative decrease {last_decrease:.1e}, "
                        f"predicted {predicted:.1e}: converged)")
        else:
            message += (f" (last relative decrease {last_decrease:.1e}, "
                        f"predicted {predicted:.1e})")
    return dict(phi=phi, cost=cost, J=J, r=r, nit=it, converged=converged,
                message=message)
