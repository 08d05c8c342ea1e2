"""The kernels compiled for given orders (`_predictor._kernel`, used on
long records) give the numbers of the kernels for any orders, bit for
bit, so a long record's model does not depend on which ran: they are
compiled on a thread of their own, and the kernels for any orders run
until they are ready."""

import numpy as np
import pytest

from sandwichctl.identification import _predictor as pr


def _theta(rng, o):
    na, nb, nc, nd, q1, q2 = o
    return np.r_[rng.uniform(-0.3, 0.3, nc), rng.uniform(-0.3, 0.3, na),
                 rng.uniform(0.5, 1.5, 2), rng.uniform(0.05, 0.3, 2),
                 rng.uniform(-0.5, 0.5, nb), rng.uniform(-0.5, 0.5, nd)]


def _all_signals(theta, o, u, ym, init):
    """Every output of the simulations the identifier runs."""
    y, J, z = pr.simulate_with_sensitivities(theta, o, u, init=init)
    ysp, Jsp, zsp = pr.simulate_with_sensitivities(theta, o, u, ymeas=ym,
                                                   init=init)
    return [y, J, z, ysp, Jsp, zsp, *pr.oe_signals(theta, o, u, init),
            *pr.oe_signals(theta, o, u, init, ymeas=ym),
            pr.smooth_output(theta, o, u, 0.05, init)]


@pytest.mark.parametrize('o', [(2, 2, 3, 1, 0, 1), (1, 0, 0, 2, 3, 2)])
def test_compiled_for_the_orders_equals_any_orders(monkeypatch, rng, o):
    theta = _theta(rng, o)
    u, ym = rng.normal(0, 1, 400), rng.normal(0, 1, 400)
    sizes = pr.init_sizes(o)
    init = tuple(rng.normal(0, 0.5, k) for k in sizes)
    for start in (None, init):
        monkeypatch.setattr(pr, 'SPECIALIZE_FROM', 10 ** 9)
        generic = _all_signals(theta, o, u, ym, start)
        monkeypatch.setattr(pr, 'SPECIALIZE_FROM', 100)
        ring = np.zeros((pr.ring_rows(o), theta.size))
        for kind in ('oe', 'sp', 'output'):    # compiled on their thread
            pr._kernel(o, kind, u.size, ring, ring)
        pr.wait_for_kernels()
        assert pr._kernel(o, 'oe', u.size, ring, ring) is not pr.oe_simulate
        compiled = _all_signals(theta, o, u, ym, start)
        assert set(np.unique(generic[2])) == {-1, 0, 1}  # every zone met
        for a, b in zip(generic, compiled):
            np.testing.assert_array_equal(a, b)
        # compiled once, on their thread, for the types the callers pass
        for kind in ('oe', 'sp', 'output'):
            kernel = pr._kernel(o, kind, u.size, ring, ring)
            assert len(kernel.signatures) == 1, kind


def test_kernel_choice(monkeypatch):
    o = (2, 2, 3, 1, 0, 1)
    rows = pr.ring_rows(o)
    assert rows >= pr.padding(o) and rows & (rows - 1) == 0
    ring = np.zeros((rows, 12))
    other = np.zeros((rows + 1, 12))
    n = pr.SPECIALIZE_FROM
    assert pr._kernel(o, 'oe', n - 1, ring, ring) is pr.oe_simulate
    assert pr._kernel(o, 'sp', n - 1, ring, ring) is pr.sp_simulate
    assert pr._kernel(o, 'output', n - 1) is pr._output_padded
    # whole-record arrays (the recursive estimators' layout) or rings of
    # another size are not indexed by a mask: the kernel for any orders
    assert pr._kernel(o, 'oe', n, other, other) is pr.oe_simulate
    pr._kernel(np.array(o), 'oe', n, ring, ring)
    pr.wait_for_kernels()
    compiled = pr._kernel(np.array(o), 'oe', n, ring, ring)
    assert compiled is not pr.oe_simulate
    assert pr._kernel(list(o), 'oe', n, ring, ring) is compiled   # kept


def _child(o, queue):
    """In a forked child: compile the kernels of other orders and run
    them (numba's compiler lock must not be held by a thread the fork did
    not copy)."""
    theta = np.r_[0.1, 0.2, 0.1, 1.0, 1.2, 0.1, 0.2, 0.3, -0.2]
    u = np.random.default_rng(1).normal(0, 1, 300)
    ring = np.zeros((pr.ring_rows(o), theta.size))
    pr._kernel(o, 'oe', u.size, ring, ring)
    pr.wait_for_kernels()
    kernel = pr._kernel(o, 'oe', u.size, ring, ring)
    queue.put((kernel is not pr.oe_simulate,
               float(pr.simulate_with_sensitivities(theta, o, u)[0][-1])))


def test_fork_while_compiling(monkeypatch):
    """A fork waits for a compilation under way (`os.register_at_fork`),
    and the child compiles on a thread of its own."""
    import multiprocessing
    monkeypatch.setattr(pr, 'SPECIALIZE_FROM', 100)
    o_parent, o_child = (2, 1, 1, 1, 1, 0), (1, 1, 2, 1, 0, 0)
    ring = np.zeros((pr.ring_rows(o_parent), 10))
    pr._kernel(o_parent, 'sp', 300, ring, ring)     # compiling on its thread
    ctx = multiprocessing.get_context('fork')
    queue = ctx.Queue()
    child = ctx.Process(target=_child, args=(o_child, queue))
    child.start()
    compiled, last = queue.get(timeout=300)
    child.join(timeout=60)
    assert child.exitcode == 0 and compiled and np.isfinite(last)
