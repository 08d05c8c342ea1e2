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
    loaded = sw.load_model(tmp_path / 'stage_axis.json')
    np.testing.assert_array_equal(loaded.theta, res.model.theta)
