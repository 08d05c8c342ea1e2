"""Sphinx helpers for the sandwichctl documentation (local extension).

1. **API pages.** At start-up, `write_api_pages` writes ``api/index.rst``
   and one ``api/<room>.<module>.rst`` per public module of sandwichctl
   (every ``sandwichctl/<room>/<name>.py`` whose names do not start with
   ``_``), grouped on the index by room (subpackage). Each module page
   shows the module docstring and an autosummary table of the names in
   the module's ``__all__``, so a new public module or name appears in
   the docs without editing them. The files are generated
   (``docs/api/`` is git-ignored) and are only rewritten when their text
   changes.

2. **Docstring excerpts.** The directive ::

       .. sandwichctl-docstring:: sandwichctl.backlash
          :section: Crossing slope lines

   renders a module's docstring (or one of its ``----``-underlined
   sections, without the title) as reStructuredText, section titles
   allowed, so pages can quote the code's documentation instead of
   copying it.

3. **Notebooks.** `copy_notebooks` copies the notebooks of the folder
   named by ``sandwichctl_notebooks`` (``../notebooks``) to
   ``docs/notebooks/`` (git-ignored), where the toctree can list them as
   ``notebooks/<name>``. myst-nb executes them at build time (conf.py).

4. **Soft references.** The default role ``sandwichctl-obj`` (text in
   single backquotes) is ``:py:obj:`` with two additions, resolved when
   Python's own lookup fails (``missing-reference``): a name documented
   under another path is found by its tail (``identify`` on the page of
   ``sandwichctl.identification.pipeline`` links to ``sandwichctl.identify``,
   ``examples.add_noise`` to ``sandwichctl.paper.examples.add_noise``);
   and a plain word that names no documented object (numpydoc writes
   parameter names in single backquotes) renders as code without a
   warning. A dotted name that resolves nowhere still fails the nitpicky
   build, so a typo such as ``SandwichSystem.simulte`` is caught.
"""

import importlib
import json
import inspect
import pkgutil
import textwrap
from pathlib import Path

from docutils.parsers.rst import directives
from sphinx.domains.python import PyXRefRole
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective
from sphinx.util.nodes import make_refnode

logger = logging.getLogger(__name__)

#: Order of the rooms (subpackages) in the API reference; rooms not
#: listed follow alphabetically, so a new room needs no change here.
ROOM_ORDER = ['model', 'identification', 'design', 'tools', 'data', 'paper']

API_INTRO = """\
API reference
=============

sandwichctl is used next to python-control::

    import control as ct
    import sandwichctl as sw

The package is organised in rooms (subpackages), one concept each; see
:doc:`../architecture`. Every public name of the toolbox is importable
from the top level (``sw.SandwichSystem``, ``sw.compare``, ...); the
paper's studies and example plants stay in their namespace
(``sw.paper.section5``, ``sw.examples.paper_plant()``). The pages below
follow the modules, one topic each; this page is generated from the
modules' ``__all__``.
"""


def public_rooms(package):
    """(room, [dotted module names]) of `package`, in `ROOM_ORDER`."""
    rooms = [info.name for info in pkgutil.iter_modules(package.__path__)
             if info.ispkg and not info.name.startswith('_')]
    rooms = ([r for r in ROOM_ORDER if r in rooms]
             + sorted(set(rooms) - set(ROOM_ORDER)))
    out = []
    for room in rooms:
        sub = importlib.import_module(f"{package.__name__}.{room}")
        names = sorted(info.name for info in pkgutil.iter_modules(sub.__path__)
                       if not info.name.startswith('_') and not info.ispkg)
        out.append((room, [f"{room}.{n}" for n in names]))
    return out


def public_modules(package):
    """The dotted names of the public modules of `package`, room by room."""
    return [name for _, names in public_rooms(package) for name in names]


def _relative_name(package, module, name):
    """Name, relative to `package`, under which an object is documented.

    Classes and functions re-exported by the package are documented as
    ``package.name``; data (whose ``#:`` comments autodoc reads from the
    defining module) and objects not re-exported keep the module path.
    """
    obj = getattr(module, name)
    flat = getattr(package, name, None) is obj
    if flat and callable(obj):
        return name
    return f"{module.__name__[len(package.__name__) + 1:]}.{name}"


def _autosummary(package, module):
    return ['.. autosummary::', '   :toctree: generated', ''] + [
        f"   {_relative_name(package, module, n)}"
        for n in getattr(module, '__all__', [])]


def _module_page(package, module):
    title = module.__name__
    lines = [title, '=' * len(title), '', f".. py:module:: {title}"]
    # A module named like one of its functions (``sandwichctl.identify``)
    # leaves the name to the function.
    if getattr(package, title.rsplit('.', 1)[1], module) is not module:
        lines.append('   :no-index:')
    lines += ['', f".. sandwichctl-docstring:: {title}", '',
              f".. currentmodule:: {package.__name__}", '']
    if getattr(module, '__all__', None):
        lines += ['Contents', '--------', '']
        lines += _autosummary(package, module)
    return '\n'.join(lines) + '\n'


def _index_page(package, modules):
    lines = [API_INTRO]
    for room, names in public_rooms(package):
        sub = importlib.import_module(f"{package.__name__}.{room}")
        summary = (inspect.getdoc(sub) or room).split('\n\n')[0].replace('\n', ' ')
        title = f"``{room}``: {summary}"
        lines += [title, '-' * len(title), '', '.. toctree::',
                  '   :maxdepth: 1', '']
        lines += [f"   {name}" for name in names]
        lines.append('')
    warning_names = _warning_names(package)
    if warning_names:
        title = 'Warnings: categories to filter'
        lines += [title, '-' * len(title), '',
                  "Every warning sandwichctl issues belongs to one of these "
                  "categories and points at the user's line, so it can be "
                  "filtered, e.g. ``warnings.simplefilter('ignore', "
                  "sw.IdentificationWarning)``.", '',
                  f".. currentmodule:: {package.__name__}", '',
                  '.. autosummary::', '   :toctree: generated', '']
        lines += [f"   {name}" for name in warning_names]
        lines.append('')
    lines += ['', 'All public names', '----------------', '',
              f".. currentmodule:: {package.__name__}", '',
              '.. autosummary::', '']
    for _, module in modules:
        lines += [f"   {_relative_name(package, module, n)}"
                  for n in getattr(module, '__all__', [])]
    return '\n'.join(lines) + '\n'


def _warning_names(package):
    """Public warning categories exported at the top of the package."""
    return [name for name in getattr(package, '__all__', [])
            if isinstance(getattr(package, name, None), type)
            and issubclass(getattr(package, name), Warning)]


def _write_if_changed(path, text):
    if not path.exists() or path.read_text(encoding='utf-8') != text:
        path.write_text(text, encoding='utf-8')


def write_api_pages(srcdir, package_name='sandwichctl'):
    """Generate ``<srcdir>/api/*.rst`` from the package's modules."""
    package = importlib.import_module(package_name)
    outdir = Path(srcdir) / 'api'
    outdir.mkdir(exist_ok=True)
    modules = []
    for name in public_modules(package):
        module = importlib.import_module(f"{package_name}.{name}")
        if not hasattr(module, '__all__'):
            logger.warning(
                f"module {module.__name__} has no __all__, so the API "
                f"reference cannot tell its public names; add __all__ "
                f"(one topic per module, public names in __all__)")
        modules.append((name, module))
    # Remove pages of modules and names that are gone: an orphan page
    # would fail the build ("document isn't included in any toctree").
    wanted = {'index.rst'} | {f"{name}.rst" for name, _ in modules}
    for stale in outdir.glob('*.rst'):
        if stale.name not in wanted:
            stale.unlink()
    stubs = {f"{package_name}.{_relative_name(package, module, n)}.rst"
             for _, module in modules for n in getattr(module, '__all__', [])}
    stubs |= {f"{package_name}.{n}.rst" for n in _warning_names(package)}
    for stale in (outdir / 'generated').glob('*.rst'):
        if stale.name not in stubs:
            stale.unlink()
    _write_if_changed(outdir / 'index.rst', _index_page(package, modules))
    for name, module in modules:
        _write_if_changed(outdir / f"{name}.rst",
                          _module_page(package, module))


def copy_notebooks(srcdir, notebook_dir):
    """Mirror ``notebook_dir/*.ipynb`` into ``<srcdir>/notebooks``.

    A copy whose metadata lacks ``language_info`` (e.g. stripped before
    committing) gets the Python one, so that its code is highlighted.
    """
    source = Path(notebook_dir)
    target = Path(srcdir) / 'notebooks'
    target.mkdir(exist_ok=True)
    found = {p.name: p for p in source.glob('*.ipynb')} if source.is_dir() \
        else {}
    for old in target.glob('*.ipynb'):
        if old.name not in found:
            old.unlink()
    for name, path in found.items():
        text = path.read_text(encoding='utf-8')
        notebook = json.loads(text)
        metadata = notebook.setdefault('metadata', {})
        if 'language_info' not in metadata:
            metadata['language_info'] = {'name': 'python'}
            text = json.dumps(notebook, indent=1, ensure_ascii=False) + '\n'
        _write_if_changed(target / name, text)


def _docstring_section(doc, title):
    """Body of the ``----``-underlined section `title` of `doc`, or None."""
    lines = doc.splitlines()

    def is_title(i):
        return (i + 1 < len(lines) and lines[i].strip()
                and set(lines[i + 1].strip()) == {'-'}
                and len(lines[i + 1].strip()) >= len(lines[i].strip()))

    for i in range(len(lines)):
        if is_title(i) and lines[i].strip() == title:
            end = next((j for j in range(i + 2, len(lines)) if is_title(j)),
                       len(lines))
            return '\n'.join(lines[i + 2:end]).strip('\n')
    return None


class DocstringDirective(SphinxDirective):
    """Render a module's docstring, or one section of it, as reST."""

    required_arguments = 1
    option_spec = {'section': directives.unchanged_required}

    def run(self):
        name = self.arguments[0]
        try:
            module = importlib.import_module(name)
        except ImportError as exc:
            logger.warning(f"sandwichctl-docstring: cannot import {name}: "
                           f"{exc}", location=self.get_location())
            return []
        doc = textwrap.dedent(inspect.getdoc(module) or '')
        title = self.options.get('section')
        if title is not None:
            doc = _docstring_section(doc, title)
            if doc is None:
                logger.warning(
                    f"sandwichctl-docstring: the docstring of {name} has no "
                    f"section {title!r} (a title underlined with '-')",
                    location=self.get_location())
                return []
        source = inspect.getsourcefile(module)
        self.env.note_dependency(source)
        return self.parse_text_to_nodes(doc, allow_section_headings=True)


class SoftObjRole(PyXRefRole):
    """``:py:obj:`` that may fall back softly (see the module notes)."""

    def result_nodes(self, document, env, node, is_ref):
        node['refdomain'], node['reftype'] = 'py', 'obj'
        node['sandwichctl_soft'] = True
        return [node], []


def _on_missing_reference(app, env, node, contnode):
    """Resolve a soft reference by its tail, or render a plain word."""
    if not node.get('sandwichctl_soft'):
        return None
    target = node['reftarget']
    package = app.config.sandwichctl_package
    objects = env.get_domain('py').objects
    tail = target[len(package) + 1:] if target.startswith(
        package + '.') else target
    candidates = [f"{package}.{tail}"] + sorted(
        name for name in objects
        if '.' in tail and name.endswith('.' + tail)
        and name.startswith(package + '.'))
    for name in candidates:
        if name in objects:
            entry = objects[name]
            return make_refnode(app.builder, node['refdoc'], entry.docname,
                                entry.node_id, contnode, name)
    if '.' not in target:
        return contnode        # a parameter name or a plain word
    return None


def _on_config_inited(app, config):
    write_api_pages(app.srcdir, config.sandwichctl_package)
    if config.sandwichctl_notebooks:
        copy_notebooks(app.srcdir,
                       Path(app.confdir) / config.sandwichctl_notebooks)


def setup(app):
    """Register the directive, and generate the API and notebook pages."""
    app.add_config_value('sandwichctl_package', 'sandwichctl', 'env')
    app.add_config_value('sandwichctl_notebooks', None, 'env')
    app.add_directive('sandwichctl-docstring', DocstringDirective)
    app.add_role('sandwichctl-obj', SoftObjRole())
    app.connect('config-inited', _on_config_inited)
    app.connect('missing-reference', _on_missing_reference)
    return {'parallel_read_safe': True, 'parallel_write_safe': True}
