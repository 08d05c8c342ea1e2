"""The bundle direction QP (3.4): piqp solvers reused between samples,
the compiled weights, and the bundle recursion they serve (issue 16)."""

import threading
import warnings

import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.identification import _qp
from sandwichctl.identification import _recursive as rc


def _problems(rng):
    """Simplex QPs as the bundle poses them: P = H H', c = beta >= 0 with
    beta[0] = 0, over several sizes and scales, including collinear and
    repeated subgradients and a zero bundle."""
    out = []
    for n in (2, 3, 5, 6, 9):
        for scale in (1e-6, 1.0, 1e3):
            H = rng.normal(0, scale, (n, 9))
            beta = np.concatenate([[0.0], rng.uniform(0, scale, n - 1)])
            out.append((H, beta))
        H = np.outer(rng.uniform(0.5, 2, n), rng.normal(0, 1, 9))
        out.append((H, np.zeros(n)))                          # collinear
        H = np.repeat(rng.normal(0, 1, (1, 9)), n, axis=0)
        out.append((H, np.concatenate([[0.0], np.full(n - 1, 1e-3)])))
        H[1:] += 1e-9 * rng.normal(0, 1, (n - 1, 9))          # nearly equal
        out.append((H, np.zeros(n)))
        out.append((np.zeros((n, 9)), np.zeros(n)))           # zero bundle
    return out


def _lam(H, beta):
    """The bundle weights of `direction_weights` (compiled)."""
    lam = np.full(beta.size, np.nan)
    rc.direction_weights(H, beta.copy(), beta.size, lam, 0)
    return lam


def _reference(H, beta):
    """The same weights by numpy steps: scale, solve, clip, renormalise."""
    P = H @ H.T
    scale = max(float(np.max(np.diag(P))), float(np.max(np.abs(beta))),
                1e-300)
    lam = np.clip(_qp.simplex_solve(P / scale, beta / scale), 0.0, None)
    return lam / lam.sum()


def test_reused_solver_gives_the_fresh_solution(rng, monkeypatch):
    problems = _problems(rng)
    reused = [_lam(H, beta) for H, beta in problems]
    monkeypatch.setattr(_qp, '_REUSE', False)
    fresh = [_lam(H, beta) for H, beta in problems]
    for a, b in zip(reused, fresh):
        np.testing.assert_array_equal(a, b)
        assert np.all(a >= 0) and a.sum() == pytest.approx(1, abs=1e-12)


def test_one_solver_per_size_is_kept_and_updated(rng):
    H = rng.normal(0, 1, (5, 9))
    _lam(H, np.zeros(5))
    solver = _qp._local.simplex[5]
    _lam(rng.normal(0, 1, (5, 9)), np.zeros(5))
    _lam(rng.normal(0, 1, (4, 9)), np.zeros(4))
    assert _qp._local.simplex[5] is solver
    assert _qp._local.simplex[4] is not solver


def test_each_thread_has_its_own_solvers(rng):
    H = rng.normal(0, 1, (5, 9))
    _lam(H, np.zeros(5))
    seen = []

    def work():
        seen.append(_lam(H, np.zeros(5)))
        seen.append(_qp._local.simplex[5])

    thread = threading.Thread(target=work)
    thread.start()
    thread.join()
    assert seen[1] is not _qp._local.simplex[5]
    np.testing.assert_array_equal(seen[0], _lam(H, np.zeros(5)))


class _Broken:
    """A cached solver whose update raises or whose solve fails."""

    def __init__(self, fail_update):
        self.fail_update = fail_update

    def update(self, **kwargs):
        if self.fail_update:
            raise ValueError("update refused")

    def solve(self):
        return 'not solved'


@pytest.mark.parametrize('fail_update', [True, False])
def test_failed_update_falls_back_to_a_fresh_setup(rng, monkeypatch,
                                                   fail_update):
    H, beta = rng.normal(0, 1, (5, 9)), np.r_[0.0, rng.uniform(0, 1, 4)]
    expected = _lam(H, beta)
    _qp._local.simplex[5] = _Broken(fail_update)
    np.testing.assert_array_equal(_lam(H, beta), expected)
    assert isinstance(_qp._local.simplex[5], type(_qp._new_solver()))


def test_compiled_weights_equal_the_numpy_steps(rng):
    for H, beta in _problems(rng):
        n = beta.size
        lam = np.full(n + 2, np.nan)
        rc.direction_weights(np.vstack([H, np.ones((2, 9))]),
                             np.r_[beta, 1.0, 1.0], n, lam, 0)
        np.testing.assert_array_equal(lam[:n], _reference(H, beta))


def test_compiled_weights_warn_and_fall_back_when_piqp_fails(rng,
                                                             monkeypatch):
    def fail(P, c):
        raise _qp.QPError("piqp returned status -1")

    monkeypatch.setattr(rc, 'simplex_solve', fail)
    lam = np.full(4, np.nan)
    with pytest.warns(sw.IdentificationWarning, match="at sample 17"):
        rc.direction_weights(rng.normal(0, 1, (4, 9)), np.zeros(4), 4, lam,
                             17)
    np.testing.assert_array_equal(lam, [1.0, 0.0, 0.0, 0.0])
    monkeypatch.setattr(rc, 'simplex_solve', lambda P, c: -np.ones(c.size))
    with pytest.warns(sw.IdentificationWarning, match="no point"):
        rc.direction_weights(rng.normal(0, 1, (4, 9)), np.zeros(4), 3, lam,
                             3)
    np.testing.assert_array_equal(lam, [1.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize('n', [1, 2, 7, 8, 9, 15, 16, 17, 100, 128])
def test_pairwise_sum_adds_up_as_numpy(rng, n):
    for _ in range(20):
        a = rng.uniform(0, 1, n) * 10.0 ** rng.uniform(-9, 0, n)
        assert rc._pairwise_sum(a, n) == a.sum()


PLANT = sw.examples.paper_plant()

#: theta after 1,500 samples of the paper's example (input seed 3; noise
#: seed 4 at SNR 46.5), from the bundle recursion before the solver reuse
#: and the compiled loop (a Python loop and a new piqp setup per sample).
REFERENCE = {
    None: [1.027791031310097, 0.1402987034368316, 0.08428306671920967,
           0.1764414697703776, 2.4465102006207484, 2.83307979586835,
           0.20623862962966014, 0.28072083145292137, -0.09716244789875929],
    46.5: [0.5153840744198661, -0.3518786995741314, 0.16657490196701363,
           0.11211801577254545, 2.2817941980764216, 2.7077973463095755,
           0.07493700236783168, 0.26992039178883476, -0.40880942459953135],
}
COUNTS = {None: {'long': 1473, 'short': 6, 'null': 0, 'stop': 21},
          46.5: {'long': 1486, 'short': 7, 'null': 0, 'stop': 7}}


def _bundle(snr, **options):
    u = sw.examples.paper_input(1500, seed=3)
    y = PLANT.simulate(u).outputs
    if snr is not None:
        y = sw.examples.add_noise(y, snr, seed=4)
    with warnings.catch_warnings():
        warnings.simplefilter('ignore')
        return sw.identify(u, y, **PLANT.orders, method='bundle', eta0=0.015,
                           k1=6, **options)


@pytest.mark.parametrize('snr', [None, 46.5])
def test_bundle_identify_equals_the_reference(snr):
    res = _bundle(snr)
    # bit for bit where the reference was recorded; the tolerance leaves
    # room for another BLAS's rounding, which piqp's stopping amplifies
    np.testing.assert_allclose(res.theta, REFERENCE[snr], rtol=0, atol=1e-6)
    assert res.counts == COUNTS[snr]


def test_bundle_identify_without_reuse_is_the_same(monkeypatch):
    res = _bundle(46.5, predictor='parallel')
    monkeypatch.setattr(_qp, '_REUSE', False)
    ref = _bundle(46.5, predictor='parallel')
    np.testing.assert_array_equal(res.history, ref.history)
    np.testing.assert_array_equal(res.errors, ref.errors)
    np.testing.assert_array_equal(res.kinds, ref.kinds)
