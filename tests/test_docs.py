"""Build the documentation with warnings as errors, as CI does.

A failure lists the Sphinx warnings. They usually point at a docstring
(for instance, |x| in plain docstring text is a reST substitution
reference: write abs(x), or put it in double backquotes) or at a page
missing from the toctree in docs/index.md. The documentation tools are in
the ``test`` extra, so a missing tool is a failure, not a skip.
"""

import os
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parents[1] / 'docs'


def test_docs_build_without_warnings(tmp_path):
    """sphinx-build -W -b html docs <tmp> succeeds (< 60 s)."""
    cmd = [sys.executable, '-m', 'sphinx', '-W', '--keep-going', '-q',
           '-b', 'html', '-d', str(tmp_path / 'doctrees'), str(DOCS),
           str(tmp_path / 'html')]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=120,
                          env={**os.environ, 'MPLBACKEND': 'Agg'})
    assert proc.returncode == 0, (
        f"sphinx-build failed (exit {proc.returncode}):\n{proc.stderr}")
    html = tmp_path / 'html'
    for page in ('index', 'getting-started', 'model', 'api/index'):
        assert (html / f"{page}.html").is_file(), page
    # the API reference picks up public names from the modules' __all__
    generated = {p.name for p in (html / 'api' / 'generated').glob('*.html')}
    for name in ('sandwichctl.SandwichSystem', 'sandwichctl.compare',
                 'sandwichctl.save_model', 'sandwichctl.plot_hysteresis'):
        assert f"{name}.html" in generated, name
