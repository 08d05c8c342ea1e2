"""Build the documentation as CI does, executing the tutorials, and check
the HTML itself.

The build is ``sphinx -W -n`` (warnings are errors, every reference must
resolve) with a fresh jupyter-cache, so every notebook in ``notebooks/``
is executed once, here: a cell that raises fails the build (this is the
test that runs the tutorials; tests/test_notebooks.py checks how they are
committed). A failure lists the Sphinx warnings. They usually point at a
docstring (for instance, |x| in plain docstring text is a reST
substitution reference: write abs(x), or put it in double backquotes), a
dotted name in single backquotes that names nothing, or a page missing
from a toctree (docs/index.md, guide.md or tutorials.md). The
documentation tools are in the ``test`` extra, so a missing tool is a
failure, not a skip.

The kernel: the notebooks run on the 'python3' kernelspec, which normally
comes with ipykernel inside the virtual environment and starts
``sys.executable``. If the 'python3' spec found first would start another
interpreter (e.g. a user-level spec of a different Python), a spec for
``sys.executable`` is written to a temporary directory put first on
JUPYTER_PATH, so the notebooks run against the sandwichctl under test.
"""

import json
import os
import re
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / 'docs'
NOTEBOOKS = sorted((ROOT / 'notebooks').glob('*.ipynb'))
NOTEBOOK_TIME_LIMIT = 120              # seconds per notebook (STYLE)
BUILD_TIME_LIMIT = 600


def _spec_runs_this_python():
    from jupyter_client.kernelspec import KernelSpecManager, NoSuchKernel
    try:
        spec = KernelSpecManager().get_kernel_spec('python3')
    except NoSuchKernel:
        return False
    exe = spec.argv[0]
    # jupyter_client replaces a bare 'python'/'python3' by sys.executable
    generic = {'python', f'python{sys.version_info[0]}',
               'python{}.{}'.format(*sys.version_info[:2])}
    if exe in generic:
        return True
    try:
        return os.path.samefile(exe, sys.executable)
    except OSError:
        return False


def _kernel_env(root):
    """Environment whose 'python3' kernelspec runs this interpreter."""
    env = dict(os.environ)
    env.pop('MPLBACKEND', None)        # conf.py sets the inline backend
    if not _spec_runs_this_python():
        spec_dir = root / 'kernels' / 'python3'
        spec_dir.mkdir(parents=True)
        (spec_dir / 'kernel.json').write_text(json.dumps({
            'argv': [sys.executable, '-m', 'ipykernel_launcher', '-f',
                     '{connection_file}'],
            'display_name': 'Python 3 (tests)', 'language': 'python'}))
        env['JUPYTER_PATH'] = os.pathsep.join(
            [str(root)] + [p for p in env.get('JUPYTER_PATH', '').split(
                os.pathsep) if p])
    return env


@pytest.fixture(scope='module')
def built(tmp_path_factory):
    """Build once for the module: (html dir, jupyter-cache dir, seconds)."""
    tmp = tmp_path_factory.mktemp('docs')
    cache = tmp / 'jupyter_cache'
    cmd = [sys.executable, '-m', 'sphinx', '-W', '-n', '--keep-going', '-q',
           '-b', 'html', '-d', str(tmp / 'doctrees'),
           '-D', f'nb_execution_cache_path={cache}', str(DOCS),
           str(tmp / 'html')]
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True,
                          timeout=BUILD_TIME_LIMIT,
                          env=_kernel_env(tmp / 'jupyter'))
    elapsed = time.perf_counter() - start
    return tmp / 'html', cache, elapsed, proc.returncode, proc.stderr


def test_build_without_warnings(built):
    html, _, elapsed, returncode, warnings = built
    assert returncode == 0, (
        f"sphinx-build -W -n failed (exit {returncode}):\n{warnings}")
    assert elapsed < BUILD_TIME_LIMIT
    for page in ('index', 'getting-started', 'model', 'api/index'):
        assert (html / f"{page}.html").is_file(), page


def test_api_reference_is_generated_and_grouped_by_room(built):
    html = built[0]
    generated = {p.name for p in (html / 'api' / 'generated').glob('*.html')}
    for name in ('sandwichctl.SandwichSystem', 'sandwichctl.compare',
                 'sandwichctl.save_model', 'sandwichctl.plot_hysteresis',
                 'sandwichctl.step_response', 'sandwichctl.SandwichWarning'):
        assert f"{name}.html" in generated, name
    index = (html / 'api' / 'index.html').read_text(encoding='utf-8')
    rooms = [index.find(f"<code class=\"docutils literal notranslate\">"
                        f"<span class=\"pre\">{room}</span></code>")
             for room in ('model', 'identification', 'design', 'tools')]
    assert all(pos > 0 for pos in rooms) and rooms == sorted(rooms), rooms


def _toctree_notebooks():
    index = (DOCS / 'tutorials.md').read_text(encoding='utf-8')
    return re.findall(r'^notebooks/(\w+)\s*$', index, flags=re.M)


def test_every_notebook_is_a_page(built):
    assert sorted(_toctree_notebooks()) == sorted(p.stem for p in NOTEBOOKS)


@pytest.mark.parametrize('name', [p.stem for p in NOTEBOOKS])
def test_tutorial_page_shows_outputs_and_figures(built, name):
    page = (built[0] / 'notebooks' / f"{name}.html").read_text(
        encoding='utf-8')
    images = re.findall(r'<img[^>]+src="([^"]+)"', page)
    assert images, f"{name}: no figure on the page"
    for src in images:
        if not src.startswith('data:'):
            assert (built[0] / 'notebooks' / src).resolve().is_file(), src
    assert re.search(r'class="output (text_plain|stream)', page), (
        f"{name}: no printed output on the page")
    assert 'class="output traceback' not in page, f"{name}: an error cell"


def test_build_prints_no_kernel_notice(built):
    """conf.py gives the kernels a profile that quiets ipykernel's notice
    about TCP without encryption (once per notebook otherwise)."""
    assert 'Kernel is running over TCP' not in built[4]


@pytest.mark.parametrize('name', [p.stem for p in NOTEBOOKS])
def test_tutorial_page_shows_no_machine_text(built, name):
    """No progress-bar text, no TqdmWarning, no path of the build machine
    (a warning shown by a cell names the kernel's temporary file)."""
    page = (built[0] / 'notebooks' / f"{name}.html").read_text(
        encoding='utf-8')
    for text in ('TqdmWarning', 'it/s]', 'ipykernel_', 'site-packages',
                 str(ROOT), str(built[0].parent)):
        assert text not in page, f"{name}: {text!r} on the page"


@pytest.mark.parametrize('name', [p.stem for p in NOTEBOOKS])
def test_notebook_was_executed_in_time(built, name):
    """Each notebook ran once in the build, in under two minutes."""
    from jupyter_cache import get_cache
    records = {Path(r.uri).stem: r.data
               for r in get_cache(str(built[1])).list_cache_records()}
    assert name in records, f"{name} was not executed by the build"
    seconds = records[name].get('execution_seconds')
    assert seconds is not None and seconds < NOTEBOOK_TIME_LIMIT, seconds


class _Resources(HTMLParser):
    """Collect the URLs of scripts, stylesheets and images of a page."""

    def __init__(self):
        super().__init__()
        self.urls = []

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == 'script' and attrs.get('src'):
            self.urls.append(('script', attrs['src']))
        elif tag == 'link' and 'stylesheet' in (attrs.get('rel') or '') \
                and attrs.get('href'):
            self.urls.append(('stylesheet', attrs['href']))
        elif tag == 'img' and attrs.get('src'):
            self.urls.append(('img', attrs['src']))


def test_no_page_loads_anything_from_the_network(built):
    html = built[0]
    remote = []
    pages = sorted(html.rglob('*.html'))
    assert len(pages) > 20
    for page in pages:
        parser = _Resources()
        parser.feed(page.read_text(encoding='utf-8'))
        for kind, url in parser.urls:
            if re.match(r'^([a-z][a-z0-9+.-]*:)?//', url, flags=re.I):
                remote.append(f"{page.relative_to(html)}: {kind} {url}")
    assert not remote, '\n'.join(remote)


def test_mathjax_is_served_locally(built):
    html = built[0]
    assert (html / '_static' / 'mathjax' / 'tex-chtml.js').is_file()
    page = (html / 'model.html').read_text(encoding='utf-8')
    assert '_static/mathjax/tex-chtml.js' in page
    assert r'\(' in page or r'\[' in page         # math for MathJax
