"""The README's example must run as written."""

import pathlib
import re

import numpy as np

import sandwichctl as sw

README = pathlib.Path(__file__).resolve().parents[1] / 'README.md'


def test_readme_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)[0]
    namespace = {}
    exec(compile(code, str(README), 'exec'), namespace)
    res, plant = namespace['res'], namespace['plant']
    assert res.success
    assert sw.parameter_error(res.theta, plant.theta) < 0.02
    paper = namespace['paper']        # as its comment says: below linear
    assert (round(paper.fit, 1), round(paper.linear['fit'], 1)) == (61.4,
                                                                     63.6)
    assert not paper.success
    loaded = sw.load_model(tmp_path / 'stage_axis.json')
    np.testing.assert_array_equal(loaded.theta, res.model.theta)


def test_readme_numbers_are_the_benchmark_pages():
    """The robustness numbers the README quotes are those docs/algorithm.md
    reports for benchmarks/bench_robustness.py (six families)."""
    docs = (README.parent / 'docs' / 'algorithm.md').read_text()
    found = re.search(r"Over the (\d+) cases: (\d+) \([\d.]+%\) successes, "
                      r"(\d+) of (\d+) noise-free.*?(\d+) failures reported "
                      r"as\s+success", docs, re.S)
    assert found, "docs/algorithm.md no longer states the six families' sums"
    cases, successes, clean, clean_cases, silent = map(int, found.groups())
    text = ' '.join(README.read_text().split())
    quoted = (f"On {cases} random plants (six seeded families) it reaches "
              f"the accuracy the data allow in {successes} cases "
              f"({round(100 * successes / cases)}%; {clean} of the "
              f"{clean_cases} noise-free ones); {silent} of the other "
              f"{cases - successes} are local optima")
    assert quoted in text, f"README should say: {quoted}"


def test_readme_says_how_to_open_the_tutorials():
    text = README.read_text()
    assert 'pip install -e ".[notebooks]"' in text
    assert 'jupyter lab notebooks/' in text
    pyproject = (README.parent / 'pyproject.toml').read_text()
    extra = re.search(r'^notebooks = \[(.*)\]$', pyproject, re.M)
    assert extra and '"jupyterlab' in extra.group(1)
