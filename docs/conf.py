"""Sphinx configuration of the sandwichctl documentation.

Build (from the repository root, with the ``test`` extra installed)::

    python -m sphinx -W -b html docs docs/_build/html

The build is offline: no intersphinx, notebooks are rendered without
being executed, and MathJax is only fetched by the browser.
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
# `name` in docstrings links to the object when it can be found.
default_role = 'py:obj'

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
nb_execution_mode = 'off'   # notebooks are committed without outputs

# -- Figures (the plot directive runs its code at build time) --------------
plot_include_source = True
plot_html_show_source_link = False
plot_html_show_formats = False
plot_formats = [('png', 100)]
plot_rcparams = {'figure.autolayout': True}

# -- HTML -------------------------------------------------------------------
html_theme = 'alabaster'
html_title = f"sandwichctl {release}"
html_theme_options = {
    'description': 'Sandwich systems with backlash-like hysteresis, '
                   'for python-control',
    'fixed_sidebar': True,
}
html_sidebars = {'**': ['about.html', 'navigation.html', 'searchbox.html']}
