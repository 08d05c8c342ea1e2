"""Every notebook in notebooks/ is valid and committed without outputs.

The notebooks are *executed* by tests/test_docs.py: the documentation
build runs each of them once through myst-nb and jupyter-cache (a cell
that raises fails the build), checks that each ran in under two minutes
and that its page shows printed output and figures. Running them here as
well would double the suite's longest step.
"""

import re
from pathlib import Path

import nbformat          # the 'test' extra: missing is a failure, not a skip
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / 'notebooks').glob('*.ipynb'))


def test_there_are_notebooks():
    names = {p.name for p in NOTEBOOKS}
    assert {'quickstart.ipynb', 'section5_reproduction.ipynb',
            'xy_stage.ipynb', 'compensation.ipynb'} <= names


@pytest.mark.parametrize('path', NOTEBOOKS, ids=lambda p: p.name)
def test_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    for i, cell in enumerate(nb.cells):
        if cell.cell_type == 'code':
            assert cell.outputs == [], f"{path.name}: cell {i} has outputs"
            assert cell.execution_count is None, (
                f"{path.name}: cell {i} has an execution count")


@pytest.mark.parametrize('path', NOTEBOOKS, ids=lambda p: p.name)
def test_runs_on_the_python3_kernel(path):
    """The docs build starts the kernel named in the notebook."""
    nb = nbformat.read(path, as_version=4)
    assert nb.metadata.get('kernelspec', {}).get('name') == 'python3'


def test_every_notebook_is_in_the_docs_toctree():
    index = (ROOT / 'docs' / 'tutorials.md').read_text(encoding='utf-8')
    listed = set(re.findall(r'^notebooks/(\w+)\s*$', index, flags=re.M))
    assert listed == {p.stem for p in NOTEBOOKS}
