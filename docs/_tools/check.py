"""Build the documentation and look at it in a real browser (``make docs-check``).

Steps:

1. build the site as CI does (``sphinx -W -n``, notebooks executed with a
   fresh jupyter-cache) into ``docs/_build/html``;
2. open pages in headless Chromium, let MathJax typeset, and take a
   screenshot of each (``docs/_build/screenshots/<page>.png``);
3. read the page as the browser rendered it (``--dump-dom``) and check
   that the figures are there and that MathJax turned the TeX into
   rendered math (``mjx-container`` elements, no raw ``\\(`` left).

Look at the PNGs yourself: the quickstart page should show its first
figure (the simulated y and v, and the hysteresis loop) and the rendered
equation of the sandwich, u -> L1 -> x -> backlash -> v -> L2 -> y.

Chromium is not a Python package. On Debian or Ubuntu install it with::

    sudo apt-get install -y chromium        # (Ubuntu: chromium-browser)

or point the CHROMIUM environment variable at any Chromium or Chrome
binary. The browser runs with no network access needed: the site loads
nothing from the network (tests/test_docs.py checks that too).

Usage::

    python docs/_tools/check.py [--no-build] [--page notebooks/quickstart]...
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / 'docs'
HTML = DOCS / '_build' / 'html'
SHOTS = DOCS / '_build' / 'screenshots'
#: Pages to look at, and what each must show: figures, rendered math.
EXPECT = {'notebooks/quickstart': {'figure', 'math'},
          'model': {'math'},
          'getting-started': {'figure', 'math'}}
DEFAULT_PAGES = list(EXPECT)
CHROMIUM_FLAGS = ['--headless', '--no-sandbox', '--disable-gpu',
                  '--no-first-run', '--disable-background-networking',
                  '--disable-component-update', '--disable-sync',
                  '--hide-scrollbars', '--force-device-scale-factor=1',
                  '--virtual-time-budget=15000']


def find_chromium():
    """Path of a Chromium binary, or None."""
    if os.environ.get('CHROMIUM'):
        return os.environ['CHROMIUM']
    for name in ('chromium', 'chromium-browser', 'google-chrome',
                 'google-chrome-stable', 'chrome'):
        path = shutil.which(name)
        if path:
            return path
    return None


def build():
    """Build the site with a fresh notebook cache; exit on failure."""
    cache = DOCS / '_build' / '.jupyter_cache'
    shutil.rmtree(cache, ignore_errors=True)
    cmd = [sys.executable, '-m', 'sphinx', '-W', '-n', '--keep-going',
           '-b', 'html', '-d', str(DOCS / '_build' / 'doctrees'), str(DOCS),
           str(HTML)]
    print('$', ' '.join(cmd), flush=True)
    env = {k: v for k, v in os.environ.items() if k != 'MPLBACKEND'}
    if subprocess.run(cmd, env=env).returncode:
        sys.exit('the documentation build failed (warnings above)')


def browse(chromium, page, width=1280, height=3000):
    """Screenshot `page` and return (png path, rendered DOM)."""
    path = HTML / f"{page}.html"
    if not path.is_file():
        sys.exit(f"{path} does not exist: build the documentation first "
                 f"(run without --no-build)")
    url = path.resolve().as_uri()
    SHOTS.mkdir(parents=True, exist_ok=True)
    png = SHOTS / f"{page.replace('/', '_')}.png"
    with tempfile.TemporaryDirectory() as profile:
        flags = CHROMIUM_FLAGS + [f'--user-data-dir={profile}']
        subprocess.run([chromium, *flags, f'--window-size={width},{height}',
                        f'--screenshot={png}', url], check=True,
                       capture_output=True, timeout=120)
        dom = subprocess.run([chromium, *flags, '--dump-dom', url],
                             check=True, capture_output=True, text=True,
                             timeout=120).stdout
    return png, dom


def check(page, dom):
    """Problems seen in the rendered page (empty list if none)."""
    expect = EXPECT.get(page, set())
    problems = []
    if 'figure' in expect and not re.search(r'<img[^>]+src=', dom):
        problems.append('no figure')
    if 'math' in expect and 'mjx-container' not in dom:
        problems.append('no equation rendered by MathJax')
    if re.search(r'class="math[^"]*"[^>]*>\s*(\\\(|\\\[|\$)', dom):
        problems.append('raw TeX left on the page')
    return problems


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--no-build', action='store_true',
                        help='use the existing docs/_build/html')
    parser.add_argument('--page', action='append',
                        help=f'page to look at (default {DEFAULT_PAGES})')
    args = parser.parse_args(argv)
    chromium = find_chromium()
    if chromium is None:
        sys.exit('Chromium not found. Install it (Debian/Ubuntu: '
                 'sudo apt-get install -y chromium) or set CHROMIUM=<path '
                 'to a chromium or chrome binary>.')
    if not args.no_build:
        build()
    failed = False
    for page in args.page or DEFAULT_PAGES:
        png, dom = browse(chromium, page)
        problems = check(page, dom)
        failed |= bool(problems)
        print(f"{page}: {png.relative_to(ROOT)} "
              f"({'; '.join(problems) if problems else 'figures and math ok'})")
    print('Now look at the screenshots.')
    return 1 if failed else 0


if __name__ == '__main__':
    sys.exit(main())
