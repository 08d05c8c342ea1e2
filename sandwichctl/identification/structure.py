r"""Structure and delay selection over a bounded grid of candidates.

`select_structure` identifies a sandwich system (`identify`) for every
combination of orders (na, nb, nc, nd) and delays (q1, q2) of a small
grid, and with ``include_linear=True`` also the linear output-error model
of the same total orders (`identify_linear` with nb + nd + 1 numerator
coefficients, na + nc poles and delay q1 + q2, the model each sandwich
nests). It ranks them in a `StructureTable`:

- with `validation` data, by the fit of the free-run simulation from rest
  on them (`fit_percent`): the honest test, since a richer structure
  always fits the estimation data better;
- without, by an information criterion of the estimation residuals
  e = y - yhat (free run from rest) over N samples with p free
  parameters:

  .. math::

      \mathrm{AIC} = N \log\frac{\sum e^2}{N} + 2p, \qquad
      \mathrm{BIC} = N \log\frac{\sum e^2}{N} + p \log N.

Each row costs one identification (a fraction of a second to a few
seconds), so the grid is kept small: a few orders and delays around what
the physics suggests.
"""

import itertools
import numbers
import time
import warnings
from html import escape

import numpy as np

from ._options import check_minimum_phase, OEOptions
from .linear import identify_linear
from .pipeline import identify, _method_options
from ..tools.experiments import _check_dt, as_experiments
from ..tools.residuals import _simulate
from ..tools.validation import fit_percent
from .._checks import (MAX_ORDER, IdentificationWarning, check_bool,
                       check_option, progress_bar)

__all__ = ['select_structure', 'StructureTable']

#: Default orders (na, nb, nc, nd) of `select_structure`.
DEFAULT_ORDERS = ((1, 0, 1, 0), (1, 0, 1, 1), (2, 1, 1, 0), (1, 0, 2, 1),
                  (2, 1, 2, 1))

#: Default delays (q1, q2) of `select_structure` (those of `identify`).
DEFAULT_DELAYS = ((1, 1),)

#: Largest number of sandwich structures `select_structure` accepts.
MAX_ROWS = 100

_ORDER_KEYS = ('na', 'nb', 'nc', 'nd')
_DELAY_KEYS = ('q1', 'q2')
_CRITERIA = ('aic', 'bic')


class StructureTable:
    """Candidate structures ranked by `select_structure`.

    It prints as an aligned table (and as HTML in a notebook); the best
    row is first.

    Attributes
    ----------
    rows : list of dict
        One dict per candidate, best first, with the keys

        - ``rank`` (1 is the best), ``kind`` ('sandwich' or 'linear'),
          ``structure`` (e.g. 'sandwich 2/1/2/1, q 1/0' or
          'linear OE nb=4 nf=4 nk=1'), ``orders`` (the keyword arguments
          of `identify` or `identify_linear`);
        - ``n_params``: free parameters (integrators fixed at z = 1 not
          counted);
        - ``fit_validation``: percentage fit of the free-run simulation
          on the validation data (None without them);
        - ``aic``, ``bic``: information criteria of the estimation
          residuals (module documentation);
        - ``fit``: percentage fit of the free-run simulation on the
          estimation data;
        - ``p_value``: the F-test of the backlash against the linear
          model it nests (``res.significance``; small means the backlash
          matters), None for linear rows;
        - ``success``, ``message``: the identifier's verdict (a
          candidate that could not be identified has ``success`` False,
          no model and the reason in ``message``);
        - ``time``: seconds spent on the candidate;
        - ``model``: the identified `SandwichSystem` or
          ``control.TransferFunction``;
        - ``result``: the full identification result;
        - ``warnings``: the warnings its identification gave.
    criterion : {'aic', 'bic'}
        The criterion shown (and ranked by without validation data).
    validated : bool
        Whether the rows are ranked by the validation fit.
    elapsed : float
        Seconds for the whole search.
    minimum_phase : {None, 'L1'}
        The block the sandwiches keep minimum-phase (identify's
        ``minimum_phase``).
    """

    def __init__(self, rows, criterion, validated, elapsed,
                 minimum_phase=None):
        self.rows = rows
        self.criterion = criterion
        self.validated = validated
        self.elapsed = elapsed
        self.minimum_phase = minimum_phase

    @property
    def best(self):
        """The best row (a dict, see `rows`)."""
        return self.rows[0]

    @property
    def best_model(self):
        """The model of the best row, ready to use (a `SandwichSystem` or
        a ``control.TransferFunction``; None if no candidate could be
        identified)."""
        return self.rows[0]['model']

    def __len__(self):
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def __getitem__(self, index):
        return self.rows[index]

    def _columns(self):
        """(header, formatter, right-aligned) of the displayed columns."""
        def num(key, fmt):
            def cell(row):
                value = row[key]
                if value is None or not np.isfinite(value):
                    return '-'
                return format(value, fmt)
            return cell

        def p_value(row):
            p = row['p_value']
            if p is None or not np.isfinite(p):
                return '-'
            return '<1e-16' if p < 1e-16 else f"{p:.2g}"

        cols = [('rank', lambda r: str(r['rank']), True),
                ('structure', lambda r: r['structure'], False),
                ('params', lambda r: str(r['n_params'])
                 if r['n_params'] is not None else '-', True)]
        if self.validated:
            cols.append(('val fit %', num('fit_validation', '.2f'), True))
        cols += [(self.criterion.upper(), num(self.criterion, '.1f'), True),
                 ('est fit %', num('fit', '.2f'), True),
                 ('backlash p', p_value, True),
                 ('success', lambda r: 'yes' if r['success'] else 'no',
                  False),
                 ('time s', num('time', '.2f'), True)]
        return cols

    def _title(self):
        how = ('validation fit (free run from rest)' if self.validated
               else f"{self.criterion.upper()} of the estimation residuals")
        phase = self.minimum_phase
        return (f"StructureTable: {len(self.rows)} candidates ranked by "
                f"{how}, in {self.elapsed:.1f} s" + (
                    f" ({phase} minimum-phase)" if phase else ""))

    def _notes(self):
        notes = []
        if self.rows and not self.rows[0]['success']:
            notes.append("no candidate was identified successfully; see "
                         "rows[i]['message']")
        failed = [r['rank'] for r in self.rows if r['model'] is None]
        if failed:
            notes.append(f"could not be identified: rank(s) {failed} (see "
                         f"rows[i]['message'])")
        warned = [r['rank'] for r in self.rows if r['warnings']]
        if warned:
            notes.append(f"warnings during identification: rank(s) "
                         f"{warned} (see rows[i]['warnings'])")
        return notes

    def __repr__(self):
        cols = self._columns()
        cells = [[f(r) for _, f, _ in cols] for r in self.rows]
        widths = [max([len(h)] + [len(c[i]) for c in cells])
                  for i, (h, _, _) in enumerate(cols)]

        def line(values):
            return '  '.join(
                v.rjust(w) if right else v.ljust(w)
                for v, w, (_, _, right) in zip(values, widths,
                                               cols)).rstrip()
        lines = [self._title(), line([h for h, _, _ in cols])]
        lines += [line(c) for c in cells]
        lines += [f"note: {n}" for n in self._notes()]
        return '\n'.join(lines)

    def _repr_html_(self):
        cols = self._columns()
        head = ''.join(f"<th style='text-align:{'right' if right else 'left'}"
                       f"'>{escape(h)}</th>" for h, _, right in cols)
        body = []
        for r in self.rows:
            cells = ''.join(
                f"<td style='text-align:{'right' if right else 'left'}'>"
                f"{escape(f(r))}</td>" for _, f, right in cols)
            style = " style='font-weight:bold'" if r['rank'] == 1 else ''
            body.append(f"<tr{style}>{cells}</tr>")
        notes = ''.join(f"<p>note: {escape(n)}</p>" for n in self._notes())
        return (f"<div><p>{escape(self._title())}</p><table><thead><tr>"
                f"{head}</tr></thead><tbody>{''.join(body)}</tbody></table>"
                f"{notes}</div>")

    def to_pandas(self):
        """The table as a ``pandas.DataFrame`` (needs pandas).

        One row per candidate, best first, with the columns of `rows`
        except ``result`` and ``warnings``.

        Returns
        -------
        pandas.DataFrame

        Raises
        ------
        ImportError
            If pandas is not installed (it is not a dependency of
            sandwichctl).
        """
        try:
            import pandas as pd
        except ImportError:
            raise ImportError("StructureTable.to_pandas needs pandas, which "
                              "is not installed (pip install pandas); the "
                              "rows are also available as .rows, a list of "
                              "dicts") from None
        keep = [k for k in self.rows[0] if k not in ('result', 'warnings')]
        return pd.DataFrame([{k: r[k] for k in keep} for r in self.rows]
                            ).set_index('rank')


def _grid(value, keys, default, argname):
    """The list of tuples of a grid argument (tuples, one tuple, or a
    dict of ranges)."""
    example = ("a list of (" + ', '.join(keys) + ") tuples or a dict of "
               "ranges such as {" + ', '.join(f"'{k}': range(0, 2)"
                                             for k in keys) + "}")
    if value is None:
        return [tuple(v) for v in default]
    if isinstance(value, dict):
        unknown = set(value) - set(keys)
        missing = [k for k in keys if k not in value]
        if unknown or missing:
            raise ValueError(
                f"{argname} as a dict needs exactly the keys {list(keys)}; "
                f"got {sorted(value, key=str)}")
        axes = []
        for k in keys:
            v = value[k]
            try:
                v = [v] if isinstance(v, numbers.Integral) else list(v)
            except TypeError:
                raise TypeError(f"{argname}[{k!r}] must be an integer or a "
                                f"list of integers; got {v!r}") from None
            if not v:
                raise ValueError(f"{argname}[{k!r}] is empty; give at least "
                                 f"one value")
            axes.append(v)
        items = list(itertools.product(*axes))
    elif isinstance(value, (list, tuple, range)):
        items = list(value)
        if items and all(isinstance(v, numbers.Integral) for v in items):
            items = [tuple(items)]           # one structure on its own
    else:
        raise TypeError(f"{argname} must be {example}; got "
                        f"{type(value).__name__}")
    if not items:
        raise ValueError(f"{argname} is empty; give {example}")
    out = []
    for item in items:
        if not (isinstance(item, (tuple, list)) and len(item) == len(keys)):
            raise ValueError(f"{argname} must be {example}; got the entry "
                             f"{item!r}")
        for k, v in zip(keys, item):
            if isinstance(v, bool) or not isinstance(v, numbers.Integral) \
                    or not 0 <= v <= MAX_ORDER:
                raise ValueError(f"{argname}: {k} must be an integer from 0 "
                                 f"to {MAX_ORDER}; got {v!r} in "
                                 f"{tuple(item)!r}")
        out.append(tuple(int(v) for v in item))
    return list(dict.fromkeys(out))          # drop repeats, keep the order


def _centred(exps):
    """The experiments with their means of u and y removed."""
    out = type(exps)([(u - u.mean(), y - y.mean()) for u, y in exps],
                     exps.dt)
    return out


def _free_run_fit(model, exps, offsets=False):
    """(fit %, sum of squared errors) of the free run from rest; with
    `offsets` plus the least-squares constant of each experiment."""
    runs = [_simulate(model, u, exps.dt) for u in exps.u]
    if offsets:
        runs = [run + np.mean(y - run) for run, y in zip(runs, exps.y)]
    y, yhat = np.concatenate(exps.y), np.concatenate(runs)
    return fit_percent(y, yhat), float(np.sum((y - yhat) ** 2))


def _run(fit, bar):
    """Call fit(); return (result or None, message, warnings, seconds)."""
    start = time.perf_counter()
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')
        try:
            res, error = fit(), None
        except (ValueError, np.linalg.LinAlgError) as err:
            res, error = None, f"{type(err).__name__}: {err}"
    bar.update()
    return res, error, [str(w.message) for w in caught], \
        time.perf_counter() - start


def select_structure(data, orders=None, delays=None, validation=None,
                     criterion='aic', include_linear=True, progress=False,
                     **identify_options):
    r"""Rank sandwich structures and delays (and linear models) on data.

    Every combination of `orders` and `delays` is identified with
    `identify` (and, with `include_linear`, the linear output-error model
    of the same total orders with `identify_linear`), then ranked by the
    validation fit when `validation` is given, else by `criterion`
    (module documentation). Candidates that fail (``success`` False) are
    ranked after those that succeed.

    By default (``offsets='mean'``) the means of u and y are removed from
    every experiment, estimation and validation alike, and every model is
    scored by its free-run simulation from rest. That changes the drift
    of an integrating plant; with ``offsets='estimate'`` the data are used
    as given, every model is fitted with a constant output offset per
    experiment, and scored by its free run from rest plus the best such
    offset on each experiment (estimation and validation alike).

    Parameters
    ----------
    data : tuple, control.TimeResponseData or list
        Estimation data: a ``(u, y)`` pair of arrays, a record, or a list
        of experiments (see `as_experiments`).
    orders : list of tuple or dict, optional
        Orders (na, nb, nc, nd) to try: a list of tuples (one tuple alone
        is also accepted) or a dict of ranges, e.g. ``{'na': [1, 2],
        'nb': [0], 'nc': [1, 2], 'nd': [0, 1]}`` (every combination).
        Default `DEFAULT_ORDERS` (five structures).
    delays : list of tuple or dict, optional
        Delays (q1, q2), in the same forms (dict keys 'q1', 'q2').
        Default ``[(1, 1)]``, those of `identify`.
    validation : tuple, control.TimeResponseData or list, optional
        Validation data (a separate experiment), in the same forms. When
        given, the rows are ranked by the fit on them.
    criterion : {'aic', 'bic'}, optional
        Information criterion shown, and ranked by without validation
        data (default 'aic').
    include_linear : bool, optional
        Also identify the linear output-error model of each structure's
        total orders (default True).
    progress : bool, optional
        Show a progress bar (tqdm) over the candidates.
    **identify_options
        Further keyword arguments of `identify` (e.g. ``integrators``,
        ``method``, ``max_iter``); ``dt`` sets the sampling time of
        array data. ``integrators`` also applies to the linear rows.
        ``offsets`` is 'mean' (the default) or 'estimate' (above).
        ``minimum_phase='L1'`` ranks sandwiches with a minimum-phase L1
        (the linear rows stay unconstrained; the title says so).

    Returns
    -------
    StructureTable
        The ranked candidates: ``rows`` (dicts), ``best`` (the first row)
        and ``best_model``; it prints as a table.

    Warns
    -----
    IdentificationWarning
        If no candidate was identified successfully; or, with
        ``offsets='mean'``, if a model that succeeded has an integrator
        (the removed means changed its drift: ``offsets='estimate'``
        suits such data). The warnings of the
        identifications themselves are not repeated: each row keeps its
        own (``rows[i]['warnings']``) and the table notes which rows have
        some.

    Raises
    ------
    ValueError
        If a grid is empty, has an entry of the wrong length or a
        negative or non-integer order or delay, or has more than
        `MAX_ROWS` structures; if `criterion` is unknown, ``offsets`` is
        neither 'mean' nor 'estimate', or ``minimum_phase`` is not None,
        False or 'L1'; if the data are invalid (see `as_experiments`), or
        validation data are sampled at another dt.
    TypeError
        If a grid is not a list or a dict, if `identify_options` sets the
        orders, delays or ``progress``, or the data are not in an
        accepted form.

    See Also
    --------
    identify, identify_linear : the identifiers behind each row.
    compare, residuals : validate the chosen model.

    Examples
    --------
    >>> import sandwichctl as sw
    >>> case = sw.data.random_case(18, n=2000, snr=50)
    >>> case.orders
    {'na': 2, 'nb': 1, 'nc': 1, 'nd': 1, 'q1': 2, 'q2': 1}
    >>> table = sw.select_structure((case.u, case.y),
    ...                             orders=[(1, 0, 1, 0), (2, 1, 1, 1)],
    ...                             delays=[(2, 1)])
    >>> table.best['structure']
    'sandwich 2/1/1/1, q 2/1'
    >>> [row['kind'] for row in table]
    ['sandwich', 'sandwich', 'linear', 'linear']
    >>> model = table.best_model            # a SandwichSystem, ready to use
    """
    _check_arguments(criterion, include_linear, progress, identify_options)
    structures = [o + q for o in _grid(orders, _ORDER_KEYS, DEFAULT_ORDERS,
                                       'orders')
                  for q in _grid(delays, _DELAY_KEYS, DEFAULT_DELAYS,
                                 'delays')]
    if len(structures) > MAX_ROWS:
        raise ValueError(
            f"orders x delays make {len(structures)} structures, more than "
            f"{MAX_ROWS}; each costs one identification: narrow the grid "
            f"around what the physics suggests")
    options = {k: v for k, v in identify_options.items()
               if k not in ('dt', 'offsets')}
    offsets = identify_options.get('offsets', 'mean')
    est, val = _read(data, validation, identify_options.get('dt'),
                     centre=offsets == 'mean')
    fitted = 'none' if offsets == 'mean' else offsets
    linears = []
    if include_linear:
        linears = list(dict.fromkeys(
            (nb + nd + 1, na + nc, q1 + q2)
            for na, nb, nc, nd, q1, q2 in structures))
    start = time.perf_counter()
    with progress_bar(progress, total=len(structures) + len(linears),
                      desc='select_structure') as bar:
        rows = [_identify_row(s, est, dict(options, offsets=fitted), bar)
                for s in structures]
        rows += [_linear_row(o, est, options.get('integrators', 'auto'),
                             fitted, bar) for o in linears]
    for row in rows:
        _score(row, est, val, est.n_samples, fitted == 'estimate')
    if offsets == 'mean':
        _warn_integrating(rows)
    _rank(rows, 'fit_validation' if val is not None else criterion,
          -1.0 if val is not None else 1.0)
    return StructureTable(rows, criterion, val is not None,
                          time.perf_counter() - start, check_minimum_phase(
                              identify_options.get('minimum_phase')))


def _check_arguments(criterion, include_linear, progress, identify_options):
    """select_structure's own arguments, and the identify options that
    its grids or its own arguments decide."""
    check_option('criterion', criterion, tuple(_CRITERIA))
    check_bool('include_linear', include_linear)
    check_bool('progress', progress)
    fixed = set(identify_options) & set(_ORDER_KEYS + _DELAY_KEYS
                                        + ('progress',))
    if fixed:
        raise TypeError(f"{sorted(fixed)} cannot be passed as identify "
                        f"options: the orders and delays come from the "
                        f"`orders` and `delays` grids, and `progress` is "
                        f"select_structure's own")
    check_minimum_phase(identify_options.get('minimum_phase'))
    offsets = identify_options.get('offsets', 'mean')
    if not (isinstance(offsets, str) and offsets in ('mean', 'estimate')):
        raise ValueError(
            f"select_structure removes the means of u and y of every "
            f"experiment (offsets='mean') or fits a constant output offset "
            f"per experiment ('estimate'), and scores every model alike; "
            f"got offsets={offsets!r}")
    # every row would fail alike on a wrong identify option: refuse it
    # here, once, instead of ranking a table of failures
    options = {k: v for k, v in identify_options.items()
               if k not in ('dt', 'offsets', 'name', 'method')}
    given = {k: options.pop(k) for k in list(options)
             if k in ('theta0', 'refine') + OEOptions.ARGUMENTS}
    _method_options(identify_options.get('method', 'oe'), options, offsets,
                    given)


def _read(data, validation, dt, centre=True):
    """(estimation, validation or None) experiments (`as_experiments`),
    with the sampling time `dt` if given, and with `centre` centred: the
    identifiers get the centred data (so offsets='none' for them), and
    the scores are computed on the same centred copies."""
    est = as_experiments(data)
    _varied('data', est)
    if dt is not None and dt is not True:      # True: not given

        if est.dt is True:
            est = type(est)(est, _check_dt(dt))
        elif abs(est.dt - _check_dt(dt)) > 1e-9 * est.dt:
            raise ValueError(f"dt = {dt:g} does not match the records' time "
                             f"step {est.dt:g}")
    val = None
    if validation is not None:
        try:
            val = as_experiments(validation)
        except (TypeError, ValueError) as err:
            raise type(err)(f"validation: {err}") from None
        _varied('validation', val)
        val = type(val)(val, _same_dt(val.dt, est.dt))
    if not centre:
        return est, val
    return _centred(est), None if val is None else _centred(val)


def _varied(argname, exps):
    """ValueError unless the input and the output of every experiment
    vary over at least two samples: nothing is identified from, or scored
    on, a constant signal."""
    for i, (u, y) in enumerate(exps):
        for what, x in (('input', u), ('output', y)):
            if not (x.size >= 2 and np.ptp(x) > 0):
                raise ValueError(
                    f"{argname}: the {what} of experiment {i} is constant "
                    f"({x.size} sample{'s' if x.size != 1 else ''}); every "
                    f"model would fail on it")


def _identify_row(s, est, options, bar):
    """The row of the sandwich structure s = (na, nb, nc, nd, q1, q2)."""
    o = dict(zip(_ORDER_KEYS + _DELAY_KEYS, s))
    label = f"sandwich {s[0]}/{s[1]}/{s[2]}/{s[3]}, q {s[4]}/{s[5]}"
    bar.set_postfix_str(label)
    run = _run(lambda: identify(est, **o, dt=est.dt, **options), bar)
    return _row('sandwich', label, o, run)


def _linear_row(shape, est, integrators, offsets, bar):
    """The row of the linear output-error model shape = (nb, nf, nk)."""
    nb, nf, nk = shape
    o = dict(nb=nb, nf=nf, nk=nk)
    label = f"linear OE nb={nb} nf={nf} nk={nk}"
    bar.set_postfix_str(label)
    run = _run(lambda: identify_linear(est, **o, dt=est.dt,
                                       integrators=integrators,
                                       offsets=offsets), bar)
    return _row('linear', label, o, run)


def _rank(rows, key, sign):
    """Sort the rows (successes first, then by `key` times `sign`) and
    number them; warn if none succeeded."""
    def rank(row):
        value = row[key]
        bad = value is None or not np.isfinite(value)
        return (not row['success'], bad, 0.0 if bad else sign * value)

    rows.sort(key=rank)
    for i, row in enumerate(rows, 1):
        row['rank'] = i
    if not rows[0]['success']:
        warnings.warn(
            "select_structure: no candidate was identified successfully; "
            "the table ranks them anyway (see rows[i]['message'] before "
            "using best_model)", IdentificationWarning, stacklevel=3)


def _warn_integrating(rows):
    """Warn when a model that succeeded on centred data integrates."""
    def integrating(row):
        res = row['result']
        k = res.get('integrators') if res is not None else None
        return bool(sum(k.values()) if isinstance(k, dict) else k)

    found = [row['structure'] for row in rows
             if row['success'] and integrating(row)]
    if found:
        warnings.warn(
            f"select_structure: {', '.join(found)} integrate, and the "
            f"means removed from u and y (offsets='mean') changed their "
            f"drift, so their fits and ranks may mislead: "
            f"offsets='estimate' uses the data as given",
            IdentificationWarning, stacklevel=3)


def _same_dt(dt, wanted):
    """The validation data's dt, reconciled with the estimation data's."""
    if wanted is True:
        return dt
    if dt is True:
        return wanted
    if abs(dt - wanted) > 1e-9 * wanted:
        raise ValueError(f"validation is sampled at dt = {dt:g} but the "
                         f"estimation data at dt = {wanted:g}")
    return dt


def _row(kind, label, orders, run):
    """A table row from `_run`'s (result, error, warnings, seconds)."""
    res, error, caught, seconds = run
    row = {'rank': None, 'kind': kind, 'structure': label,
           'orders': orders, 'n_params': None, 'fit_validation': None,
           'aic': None, 'bic': None, 'fit': None, 'p_value': None,
           'success': False, 'message': error, 'time': seconds,
           'model': None, 'result': res, 'warnings': caught}
    if res is None:
        return row
    row['model'] = res.model
    row['success'] = bool(res.success)
    row['message'] = res.message
    if kind == 'sandwich':
        n_fixed = sum((res.get('integrators') or {}).values())
        row['n_params'] = int(np.size(res.theta)) - int(n_fixed)
        sig = res.get('significance')
        row['p_value'] = None if sig is None else float(sig['p_value'])
    else:
        row['n_params'] = int(np.size(res.theta))
    return row


def _score(row, est, val, n, offsets=False):
    """Fill the fits and the criteria of a row from free-run simulations
    (with `offsets`, each experiment's least-squares output offset)."""
    if row['model'] is None:
        return
    try:
        fit, sse = _free_run_fit(row['model'], est, offsets)
        if val is not None:
            row['fit_validation'] = _free_run_fit(row['model'], val,
                                                  offsets)[0]
    except ValueError as err:                 # an unstable model
        row['success'] = False
        row['message'] = f"{row['message']}; {err}"
        return
    row['fit'] = fit
    base = n * np.log(max(sse, 1e-300) / n)
    row['aic'] = float(base + 2 * row['n_params'])
    row['bic'] = float(base + row['n_params'] * np.log(n))
