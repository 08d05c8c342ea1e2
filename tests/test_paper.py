"""Where the paper is ambiguous, every reading is available and measured
(issue 14): the three readings of "SNR 46.5", both readings of the
gradient baseline, eq. (3.9), and the numbers the tutorials and the
reproduction page quote."""

import re
import warnings
from pathlib import Path

import nbformat
import numpy as np
import pytest

import sandwichctl as sw
from sandwichctl.identification import _predictor as pr
from sandwichctl.identification import _recursive as rc
from sandwichctl.paper import examples, section5, section6

ROOT = Path(__file__).resolve().parents[1]


def _markdown(notebook):
    nb = nbformat.read(ROOT / 'notebooks' / notebook, as_version=4)
    return '\n'.join(c.source for c in nb.cells if c.cell_type == 'markdown')


def _quoted(text, fraction):
    """The percentage as the prose writes it, e.g. '2.6 %' or '2.6%'."""
    value = f"{100 * fraction:.1f}"
    return re.search(rf"(?<![\d.]){re.escape(value)} ?%", text) is not None


# ------------------------------------------------------ "SNR equal to 46.5"
@pytest.mark.parametrize('kind, std_ratio', [
    ('variance', 1 / np.sqrt(46.5)),
    ('amplitude', 1 / 46.5),
    ('db', 10 ** (-46.5 / 20)),
])
def test_add_noise_readings_in_closed_form(kind, std_ratio):
    y = np.sin(0.05 * np.arange(200000))
    noise = examples.add_noise(y, 46.5, seed=0, kind=kind) - y
    assert np.std(noise) / np.std(y) == pytest.approx(std_ratio, rel=0.01)
    # the same standard normal draws, scaled: only the scale differs
    unit = np.random.default_rng(0).standard_normal(y.size)
    np.testing.assert_allclose(noise, unit * std_ratio * np.std(y),
                               rtol=1e-9, atol=1e-14)


def test_add_noise_default_is_the_variance_ratio():
    y = np.cos(0.3 * np.arange(500))
    np.testing.assert_array_equal(
        examples.add_noise(y, 46.5, seed=4),
        examples.add_noise(y, 46.5, seed=4, kind='variance'))


def test_add_noise_of_a_huge_ratio_adds_next_to_nothing():
    # snr ** 2 and 10 ** (snr / 10) overflowed Python floats (OverflowError)
    y = np.cos(0.3 * np.arange(500))
    for kind in ('variance', 'amplitude', 'db'):
        noisy = examples.add_noise(y, 1e300, seed=4, kind=kind)
        assert np.max(np.abs(noisy - y)) < 1e-100


def test_add_noise_rejects_an_unknown_reading():
    with pytest.raises(ValueError, match=r"kind must be one of \['amplitude'"
                                         r", 'db', 'variance'\]; got 'power'"):
        examples.add_noise(np.ones(3), 46.5, kind='power')


def test_headings_of_the_noisy_blocks():
    assert [section5.snr_label(46.5, k) for k in examples.SNR_KINDS] == [
        'SNR 46.5 (variance ratio)', 'SNR 46.5 (amplitude ratio)',
        'SNR 46.5 dB']
    with pytest.raises(ValueError, match=r"kind must be one of"):
        section5.snr_label(46.5, 'power')


def test_demo_runs_the_servo_loop_then_the_three_noisy_blocks(tmp_path,
                                                               capsys):
    from sandwichctl.__main__ import main
    assert main(['demo', '--out', str(tmp_path), '--samples', '1500']) == 0
    out = capsys.readouterr().out
    # the main job first: both designs on the drive, and the play-free limit
    servo, paper = out.split('Reproducing Section 5')
    assert servo.startswith('== servo loop on a simulated ball-screw axis')
    rms = {}
    for name in ('linear', 'sandwich', 'linear, no play'):
        row = re.search(rf"^{re.escape(name)} +([0-9.]+) +[0-9]+ +[0-9.]+ "
                        rf"+(\d+) +([0-9.]+)%$", servo, re.M)
        rms[name] = float(row.group(1))
        assert row.group(2) == '0' and float(row.group(3)) <= 1.0
    assert rms['sandwich'] < rms['linear']
    ratio = float(re.search(r"sandwich RMS / linear RMS: ([0-9.]+)",
                            servo).group(1))
    assert ratio == pytest.approx(rms['sandwich'] / rms['linear'], abs=0.01)
    blocks = paper.split('\n== ')[1:]
    assert [b.split(' ==')[0] for b in blocks] == [
        'noise-free', 'noisy, SNR 46.5 (variance ratio)',
        'noisy, SNR 46.5 (amplitude ratio)', 'noisy, SNR 46.5 dB']
    for block in blocks:
        assert re.search(r"\n error ", block)
        for label in section5.METHODS:
            assert label in block.splitlines()[1]
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        'axis.c', 'axis.h', 'fig2_noise_free.png', 'fig3_noisy_amplitude.png',
        'fig3_noisy_db.png', 'fig3_noisy_variance.png', 'servo_loop.png']


def test_demo_without_the_servo_loop(tmp_path, capsys):
    from sandwichctl.__main__ import main
    assert main(['demo', '--out', str(tmp_path), '--samples', '300',
                 '--no-servo']) == 0
    assert 'servo loop' not in capsys.readouterr().out
    assert not (tmp_path / 'servo_loop.png').exists()


@pytest.mark.parametrize('args, says', [
    (['--snr', 'nan'], 'argument --snr: expected a finite number > 0'),
    (['--snr', '-3'], 'argument --snr: expected a finite number > 0'),
    (['--samples', '3'], 'argument --samples: expected a finite number >= '
                         '100'),
    (['--samples', 'abc'], "argument --samples: expected an integer"),
    (['--seed', '-1'], 'argument --seed: expected a finite number >= 0'),
    (['--out', __file__], 'is a file, not a folder')])
def test_demo_options_are_checked_before_it_runs(args, says, capsys):
    # --snr nan ran the noise-free part, wrote a figure, then raised
    from sandwichctl.__main__ import main
    with pytest.raises(SystemExit) as exit_:
        main(['demo', '--no-servo', *args])
    assert exit_.value.code == 2
    assert says in capsys.readouterr().err


@pytest.fixture(scope='module')
def noisy_bundle_errors():
    """Final bundle error of the demo's record (seed 0, 20,000 samples)
    under each reading."""
    out = {}
    for kind in examples.SNR_KINDS:
        run = section5.section5_run(
            20000, seed=0, snr=46.5, snr_kind=kind,
            methods={'bundle': section5.METHODS['bundle']})
        out[kind] = run['results']['bundle'].parameter_error(
            run['theta_true'])[-1]
    return out


def test_fig3_is_reproduced_under_amplitude_and_db_readings(
        noisy_bundle_errors):
    assert noisy_bundle_errors['amplitude'] <= 0.05       # Fig. 3
    assert noisy_bundle_errors['db'] <= 0.01
    assert noisy_bundle_errors['variance'] > 0.15         # biased


def test_reproduction_page_quotes_the_measured_errors(noisy_bundle_errors):
    page = (ROOT / 'docs' / 'reproduction.md').read_text()
    for kind, err in noisy_bundle_errors.items():
        assert f"{err:.2%}" in page, (kind, f"{err:.2%}")


def test_section5_notebook_prose_matches_its_numbers():
    text = _markdown('section5_reproduction.ipynb')
    for kind in examples.SNR_KINDS:
        run = section5.section5_run(
            6000, seed=0, snr=46.5, snr_kind=kind,
            methods={'bundle': section5.METHODS['bundle']})
        err = run['results']['bundle'].parameter_error(run['theta_true'])[-1]
        assert _quoted(text, err), (kind, err)


# -------------------------------------------------- the gradient baseline
@pytest.fixture(scope='module')
def paper_record():
    plant = examples.paper_plant()
    u = examples.paper_input(20000, seed=0)
    return plant, u, plant.simulate(u).outputs


def _gradient(record, n=None, **options):
    plant, u, y = record
    return sw.identify(u[:n], y[:n], **plant.orders, method='gradient',
                       theta0=examples.PAPER_THETA0, **options)


def test_skip_reading_skips_most_updates(paper_record):
    res = _gradient(paper_record)
    assert set(res.counts) == {'long', 'skip'}
    assert res.counts['skip'] / 20000 > 0.9               # 93 % skipped
    assert res.options['nonsmooth'] == 'skip'
    assert res.options['skip_nonsmooth'] is True


def test_the_readings_part_at_the_first_nonsmooth_sample(paper_record):
    skip = _gradient(paper_record, 500, nonsmooth='skip')
    sub = _gradient(paper_record, 500, nonsmooth='subgradient')
    assert set(sub.counts) == {'long', 'subgradient'}
    first = np.flatnonzero(skip.kinds != sub.kinds)[0]
    assert skip.kinds[first] == rc.SKIP and sub.kinds[first] == rc.SUBGRADIENT
    np.testing.assert_array_equal(skip.history[:first], sub.history[:first])
    # skip leaves the estimate; the subgradient reading moves it
    np.testing.assert_array_equal(skip.history[first],
                                  skip.history[first - 1])
    assert not np.array_equal(sub.history[first], sub.history[first - 1])


@pytest.mark.parametrize('old, new', [(True, 'skip'),
                                      (False, 'subgradient')])
def test_skip_nonsmooth_is_the_older_spelling(paper_record, old, new):
    a = _gradient(paper_record, 2000, skip_nonsmooth=old)
    b = _gradient(paper_record, 2000, nonsmooth=new)
    np.testing.assert_array_equal(a.history, b.history)
    assert a.options['nonsmooth'] == new
    assert a.options['skip_nonsmooth'] is old


@pytest.mark.parametrize('options, exc, match', [
    (dict(nonsmooth='omit'), ValueError,
     r"nonsmooth must be one of \('skip', 'subgradient'\); got 'omit'"),
    (dict(nonsmooth='skip', skip_nonsmooth=False), ValueError,
     r"skip_nonsmooth=False means nonsmooth='subgradient', but "
     r"nonsmooth='skip' was given"),
    (dict(nonsmooth='skip', full_step_test=True), TypeError,
     r"unknown option\(s\) \['full_step_test'\] for method='gradient'"),
])
def test_gradient_option_errors(paper_record, options, exc, match):
    with pytest.raises(exc, match=match):
        _gradient(paper_record, 100, **options)


def test_subgradient_reading_at_the_paper_step_diverges_loudly(paper_record):
    with pytest.warns(RuntimeWarning, match='diverged at sample'):
        res = _gradient(paper_record, nonsmooth='subgradient')
    assert not res.success and res.history.shape[0] < 20000


def test_subgradient_reading_converges_with_a_smaller_step(paper_record):
    res = _gradient(paper_record, nonsmooth='subgradient', mu=0.005)
    assert res.success
    assert res.parameter_error(paper_record[0].theta)[-1] < 0.005


def test_section5_table_marks_divergence(paper_record):
    with warnings.catch_warnings():
        warnings.simplefilter('error')           # recorded, not raised
        run = section5.section5_run(4000, seed=0)
    assert any('diverged' in m
               for m in run['warnings']['gradient/subgradient'])
    lines = section5.section5_table(run).splitlines()
    row = next(line for line in lines if line.split()[0] == 'error')
    assert 'diverged @3119' in row
    # the skip reading does not diverge, but after 4,000 samples it is
    # still worse than the linear baseline: starred, with the reason
    assert row.split()[2].endswith('%*')
    assert any(line.startswith('* gradient/skip: the fit is worse than the '
                               'linear baseline') for line in lines)


# ---------------------------------------------------------------- (3.9)
def _one_sample(u_k, target):
    """y_hat(k) = v(k) = m1 (u(k) - D1): the backlash alone, one sample."""
    o = (0, 0, 0, 0, 0, 0)
    pad = pr.padding(o)
    u, y = np.zeros(pad + 1), np.zeros(pad + 1)
    u[pad], y[pad] = u_k, target
    xs, vs, ys = (np.zeros(pad + 1) for _ in range(3))
    zs = np.zeros(pad + 1, dtype=np.int64)
    return o, pad, u, y, xs, vs, zs, ys


def _classify(theta, u_k, target, full_step_test):
    o, k, u, y, xs, vs, zs, ys = _one_sample(u_k, target)
    grad = np.zeros(4)
    f0, e0 = rc._cost(theta, o, u, y, y, xs, vs, zs, k, grad)
    H = (-e0 * grad)[None, :]
    new, trial, t = (np.zeros(4) for _ in range(3))
    kind, eta, _ = rc.bundle_finish(
        theta, np.ones(1), H, np.zeros(1), 1, f0, e0, o, u, y, y, xs, vs, zs,
        ys, k, 0.01, 0.01, 0.5, 10, 0.1, 0.5, 0.5, 1e-4, False, 1e-6, new,
        trial, t, grad, full_step_test)
    t_full = -H[0]
    full = theta + t_full
    full[2:] = np.maximum(full[2:], 0)
    f_full, _ = rc._cost(full, o, u, y, y, xs, vs, zs, k, grad)
    return kind, eta, f_full < f0


def test_eq_3_9_literal_reading_blocks_a_long_step_that_overshoots():
    theta = np.array([1.0, 1.0, 0.5, 0.5])
    # u = 2, target 3: ||w||^2 = 3.25 > 2, the full step t overshoots
    kind, eta, decreases = _classify(theta, 2.0, 3.0, False)
    assert not decreases and kind == rc.LONG and eta == 0.01
    kind, eta, _ = _classify(theta, 2.0, 3.0, True)
    assert kind == rc.SHORT and 0 < eta < 0.01


def test_eq_3_9_literal_reading_keeps_a_long_step_that_descends():
    theta = np.array([1.0, 1.0, 0.1, 0.1])
    # u = 0.5, target 0.6: ||w||^2 = 1.16 < 2, the full step descends
    for test in (False, True):
        kind, eta, decreases = _classify(theta, 0.5, 0.6, test)
        assert decreases and kind == rc.LONG and eta == 0.01


def test_eq_3_9_literal_reading_turns_long_steps_short(paper_record):
    plant, u, y = paper_record
    opts = dict(section5.PAPER_SETTINGS['bundle'],
                theta0=examples.PAPER_THETA0)
    plain = sw.identify(u[:3000], y[:3000], **plant.orders, method='bundle',
                        **opts)
    literal = sw.identify(u[:3000], y[:3000], **plant.orders,
                          method='bundle', full_step_test=True, **opts)
    assert literal.options['full_step_test'] is True
    assert literal.counts['short'] > 10 * plain.counts['short']
    assert literal.counts['long'] < plain.counts['long'] / 2


# ------------------------------------------------------------ Section 6
def test_xy_stage_notebook_prose_matches_its_numbers():
    run = section6.section6_run(
        n_samples=6700, n_validation=4000, seed=0,
        methods={'bundle': ('bundle', section6.PAPER_SETTINGS)})
    val = run['validation']['bundle']
    text = _markdown('xy_stage.ipynb')
    # the nonsmooth recursion's numbers move with the machine's rounding
    # (19.1 % and 2.6 % when written, 29.2 % and 3.0 % on another machine):
    # the prose's claims are the sides of 11 % they fall on
    assert val['one_step_max_relative_error'] < 0.11 < val[
        'max_relative_error']
    assert 'meets its 11 %' in text and 'does **not** reach 11 %' in text
    assert '34 %' not in text and '34%' not in text
    page = (ROOT / 'docs' / 'reproduction.md').read_text()
    assert 'on the same sides of 11%' in ' '.join(page.split())
