"""Step 13 of the output-error search (`_search`): does the open
backlash generalise to held-out tails of the record? (private)"""

import numpy as np

from ._lm import lm
from ._linear import fit_oe, fit_output

__all__ = []

#: Share of each experiment's samples, at its end, held out by step 13.
HELD_OUT = 0.25
#: Step 13 is skipped when the held-out tails have fewer samples.
MIN_HELD_OUT = 500
#: Most Levenberg-Marquardt iterations of step 13's refit on the heads.
HELD_OUT_ITER = 30


def step13_held_out(task, prob, best, linear, origin):
    """Step 13: does the open backlash generalise? The tail of each
    experiment (`HELD_OUT` of its samples) is held out; the sandwich (by
    `lm` from its phi, at most `HELD_OUT_ITER` iterations) and the linear
    fit of its integrators (`_linear.fit_oe`) are fitted again on the
    heads, and each simulates the whole record from rest with those
    parameters, scored on the tails alone. A sandwich that predicts the
    tails worse than the linear model is replaced by the floor of step 12
    (`Search.closed`, of the `origin` search); when the structure cannot
    hold the linear fit that floor is the `held` model, and it is the one
    refitted and compared (`Search.fit_held`). Skipped for a closed
    backlash already and when the tails hold fewer than `MIN_HELD_OUT`
    samples. Sets ``best['held_out']`` (None, or a dict of the tails'
    fits; ``note`` when skipped) and returns (problem, best, linear)."""
    best['held_out'] = None
    if best.get('fallback'):
        return prob, best, linear
    cut = [part.size - int(np.ceil(HELD_OUT * part.size))
           for part in prob.u]
    n_tail = sum(part.size - c for part, c in zip(prob.u, cut))
    if n_tail < MIN_HELD_OUT:
        best['held_out'] = {'samples': n_tail, 'note': (
            f"the open backlash was not cross-checked: the held-out tails "
            f"would have {n_tail} samples, fewer than {MIN_HELD_OUT}")}
        return prob, best, linear

    def heads(parts):
        return [part[:c] for part, c in zip(parts, cut)]
    starts = np.cumsum([0] + [part.size for part in prob.u[:-1]])
    tails = np.concatenate([np.arange(c, part.size) + at for part, c, at
                            in zip(prob.u, cut, starts)])
    y_tail = np.concatenate(prob.y)[tails]
    if not _scorable(heads(prob.u) + heads(prob.y), y_tail):
        best['held_out'] = {'samples': n_tail, 'note': (
            "the open backlash was not cross-checked: the leading "
            f"{1 - HELD_OUT:.0%} of an experiment has a constant input or "
            "output, or the held-out tails a constant output, so nothing "
            "fitted there could be scored")}
        return prob, best, linear
    st = prob.st
    head = lm(st, best['phi'], heads(prob.u), heads(prob.y), HELD_OUT_ITER,
              task.opt.tol)
    fit_sw = _fit(st.residuals(head['phi'], prob.u, prob.y)[tails], y_tail)
    # the linear fit of the same integrators (its gain's sign its own)
    lin = fit_oe(heads(prob.u), [prob.sign * y for y in heads(prob.y)],
                 task.shape, st.i1 + st.i2, max_iter=task.opt.max_iter,
                 tol=task.opt.tol, offsets=task.offsets)
    fit_lin = _fit((prob.sign * np.concatenate(prob.y)
                    - fit_output(lin, prob.u, task.shape[2]))[tails], y_tail)
    name = "the linear model"
    if fit_sw < fit_lin:
        if not origin.held_tried:
            origin.held_start()
        if origin.held is not None:  # the floor is the model it holds
            floor = origin.probs[origin.sign]
            held = origin.fit_held(heads(floor.u), heads(floor.y),
                                   origin.held['phi'])
            fit_lin = _fit(floor.st.residuals(held['phi'], floor.u,
                                              floor.y)[tails], y_tail)
            name = "the best linear model this structure holds"
    open_ = bool(np.isfinite(fit_sw) and not fit_sw < fit_lin)
    best['held_out'] = {'samples': n_tail, 'fit': fit_sw,
                        'linear_fit': fit_lin, 'open': open_}
    if open_:
        return prob, best, linear
    out = origin.closed(
        f"the open backlash did not generalise: fitted on the leading "
        f"{1 - HELD_OUT:.0%} of each experiment, it predicts the held-out "
        f"rest worse than {name} ({fit_sw:.4g} % against {fit_lin:.4g} %, "
        f"res.held_out)")
    out['held_out'] = best['held_out']
    out['n_starts'] = best['n_starts']
    return origin.probs[origin.sign], out, dict(
        linear, **{k: v for k, v in origin.baseline().items() if k == 'held'})


def _scorable(heads, y_tail):
    """Whether models can be fitted on the `heads` (every signal varies
    over two samples or more) and scored on the tails' output `y_tail`."""
    return (all(part.size >= 2 and np.ptp(part) > 0 for part in heads)
            and np.ptp(y_tail) > 0)


def _fit(r, y):
    """Fit (percent) of residuals r on y; -inf when not finite."""
    with np.errstate(all='ignore'):
        fit = 100 * (1 - np.linalg.norm(r) / np.linalg.norm(y - y.mean()))
    return float(fit) if np.isfinite(fit) else -np.inf
