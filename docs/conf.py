"""Sphinx configuration of the sandwichctl documentation.

Build (from the repository root, with the ``test`` extra installed)::

    python -m sphinx -W -n -b html docs docs/_build/html

The build is offline and strict:

- the tutorials (``notebooks/*.ipynb``, committed without outputs) are
  executed at build time by myst-nb through jupyter-cache; a cell that
  raises fails the build. The cache lives in ``docs/_build/.jupyter_cache``
  (``-D nb_execution_cache_path=...`` moves it; the tests use a fresh one);
  jupyter-cache re-runs a notebook when its code changes, not when the
  package does, so ``make docs`` clears it first;
- MathJax is served from the site itself (sphinx-mathjax-offline), so no
  page loads a script from the network;
- ``-n`` (nitpicky): every cross-reference must resolve. References to
  python-control, numpy, scipy and matplotlib cannot be resolved offline
  (no intersphinx); they are listed in ``nitpick_ignore_regex`` below and
  render as code. A name in single backquotes that is no documented
  object (numpydoc's convention for parameter names) renders as code too;
  see ``_ext/sandwichctl_docs.py``.
"""

import os
import sys

import sphinx.ext.autosummary

import sandwichctl

sys.path.insert(0, os.path.abspath('_ext'))

# -- Project ----------------------------------------------------------------
project = 'sandwichctl'
author = 'the sandwichctl developers'
copyright = '2026, the sandwichctl developers'
release = sandwichctl.__version__
version = release

# -- General ----------------------------------------------------------------
extensions = [
    'sphinx.ext.autodoc',
    'sphinx.ext.autosummary',
    'sphinx.ext.mathjax',
    'sphinx-mathjax-offline',   # MathJax 3 copied into _static/mathjax
    'matplotlib.sphinxext.plot_directive',
    'numpydoc',
    'myst_nb',              # Markdown pages and notebooks (includes MyST)
    'sandwichctl_docs',     # _ext/: API pages, docstring excerpts, notebooks
]
templates_path = ['_templates']
exclude_patterns = ['_build', 'jupyter_execute', '**.ipynb_checkpoints',
                    'README.md']
source_suffix = {'.rst': 'restructuredtext', '.md': 'myst-nb',
                 '.ipynb': 'myst-nb'}
# `name` in docstrings links to the object when it is documented, and
# renders as code otherwise (parameter names); see _ext/.
default_role = 'sandwichctl-obj'

# -- Nitpicky references ----------------------------------------------------
nitpicky = True
nitpick_ignore_regex = [
    # Offline build: no intersphinx inventories for the libraries below,
    # so their names render as code instead of links.
    (r'py:.*', r'(control|ct|numpy|np|scipy|matplotlib|plt|dask|'
               r'distributed|tqdm|numba|piqp)(\..*)?'),
    # Builtins and the standard library, as autodoc writes them in "Bases"
    # and signatures.
    (r'py:.*', r'(object|list|dict|tuple|str|int|float|bool|complex|'
               r'Exception|UserWarning|RuntimeWarning|Warning|'
               r'(os|io|json|pathlib|collections|concurrent|typing|'
               r'dataclasses|numbers|warnings)\..*)'),
]

# -- sandwichctl_docs (_ext/sandwichctl_docs.py) ----------------------------
sandwichctl_package = 'sandwichctl'
# Notebooks live in the top-level notebooks/ folder; they are copied to
# docs/notebooks/ so that a toctree line "notebooks/<name>" includes one.
sandwichctl_notebooks = '../notebooks'

# -- autodoc, autosummary, numpydoc -----------------------------------------
autosummary_generate = True
# Summaries are the first sentence; "(eq. (2.2))" does not end one.
sphinx.ext.autosummary.WELL_KNOWN_ABBREVIATIONS += (
    'eq.', 'eqs.', 'Eq.', 'Eqs.')
autosummary_imported_members = False
autodoc_member_order = 'bysource'
autodoc_typehints = 'none'
numpydoc_show_class_members = False     # members are in the class template
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False
# No numpydoc validation checks: with any check on, numpydoc 1.11 crashes
# (StopIteration in validate.source_file_def_line) on properties written
# as ``property(lambda self: ...)``, as in backlash.py. Docstring style is
# reviewed, not enforced by the build.
numpydoc_validation_checks = set()

# -- MyST and notebooks -----------------------------------------------------
myst_enable_extensions = ['dollarmath', 'amsmath']
myst_heading_anchors = 3
# Execute the tutorials at build time, through jupyter-cache. A notebook
# that raises fails the build; each has two minutes (STYLE: notebooks run
# in minutes).
nb_execution_mode = 'cache'
# The kernels inherit this process's environment: a MPLBACKEND=Agg set for
# the build (or by a test runner) would make every figure vanish from the
# pages, so the kernels get the notebook's own inline backend. (The plot
# directive of the .md/.rst pages uses Agg whatever this says.)
os.environ['MPLBACKEND'] = 'module://matplotlib_inline.backend_inline'
# The kernels get an IPython profile of their own, in the build directory:
# it quiets ipykernel's notice that a local kernel talks over TCP without
# encryption (one per notebook on stderr), and keeps the tutorials
# independent of the developer's own profile.
_profile = os.path.join(os.path.dirname(os.path.abspath(__file__)), '_build',
                        '.ipython', 'profile_default')
os.makedirs(_profile, exist_ok=True)
with open(os.path.join(_profile, 'ipython_kernel_config.py'), 'w') as _f:
    _f.write("c.IPKernelApp.log_level = 'ERROR'\n")
os.environ['IPYTHONDIR'] = os.path.dirname(_profile)
nb_execution_cache_path = os.path.join(os.path.dirname(__file__), '_build',
                                       '.jupyter_cache')
nb_execution_raise_on_error = True
nb_execution_show_tb = True
nb_execution_timeout = 120
nb_execution_excludepatterns = []

# -- Figures (the plot directive runs its code at build time) --------------
plot_include_source = True
plot_html_show_source_link = False
plot_html_show_formats = False
plot_formats = [('png', 100)]
plot_rcparams = {'figure.autolayout': True}

# -- HTML -------------------------------------------------------------------
html_theme = 'pydata_sphinx_theme'
html_title = f"sandwichctl {release}"
html_theme_options = {
    # no links to external services, no version switcher (offline site)
    'navigation_with_keys': False,
    'show_toc_level': 2,
    'navbar_align': 'left',
    'footer_start': ['copyright'],
    'footer_end': ['sphinx-version'],
    'secondary_sidebar_items': ['page-toc'],
    'header_links_before_dropdown': 5,
}
html_show_sourcelink = False
# docs/_static/sandwichctl.css: printed output wraps, displayed tables have
# spacing
html_static_path = ['_static']
html_css_files = ['sandwichctl.css']
# The header shows the four entries of index.md's toctree (getting started,
# tutorials, user guide, API reference), so each is one click away at any
# width, with no "More" menu. The hand-written pages and the tutorials get
# the full width (no "Section Navigation" sidebar; their neighbours are in
# the header's page and the previous/next links). (Exact names: Sphinx
# refuses two wildcard patterns matching one page.) The API pages keep the
# sidebar that lists the modules.
_here = os.path.dirname(os.path.abspath(__file__))
html_sidebars = {
    name: [] for name in
    [os.path.splitext(f)[0] for f in os.listdir(_here)
     if f.endswith(('.md', '.rst')) and f != 'README.md']
    + ['notebooks/' + os.path.splitext(f)[0]
       for f in os.listdir(os.path.join(_here, sandwichctl_notebooks))
       if f.endswith('.ipynb')]}
