"""The package's architecture (docs/architecture.md) holds: rooms, one-way
imports with no cycles (imports inside functions included), modules of at
most 800 lines, ``__all__`` in every public module, a page that names
every module, test files named after modules, and in `identification`
functions of at most 60 lines of code (compiled kernels aside) and private
helpers of at most 6 positional parameters."""

import ast
import importlib
from pathlib import Path

import pytest

import sandwichctl as sw

PACKAGE = Path(sw.__file__).resolve().parent
ROOMS = ['model', 'identification', 'design', 'tools', 'data', 'paper']
#: A room may import only from the rooms listed here (and _checks).
ALLOWED = {
    'model': set(),
    'tools': {'model'},
    'identification': {'model', 'tools'},
    'design': {'model', 'tools'},
    'data': {'model'},
    'paper': {'model', 'tools', 'identification', 'design', 'data'},
}


def _modules():
    for path in sorted(PACKAGE.rglob('*.py')):
        rel = path.relative_to(PACKAGE.parent).with_suffix('')
        parts = list(rel.parts)
        if parts[-1] == '__init__':
            parts = parts[:-1]
        yield '.'.join(parts), path


def _imports(name, path):
    """Modules of the package imported anywhere in the file."""
    tree = ast.parse(path.read_text(encoding='utf-8'))
    is_pkg = path.name == '__init__.py'
    base = name.split('.') if is_pkg else name.split('.')[:-1]
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                parent = base[:len(base) - node.level + 1]
                mod = '.'.join(parent + ([node.module] if node.module else []))
            else:
                mod = node.module or ''
            targets = [mod] + [f"{mod}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        else:
            continue
        known = {n for n, _ in _modules()}
        for t in targets:
            if t in known and t != name:
                found.add(t)
    return found


GRAPH = {name: _imports(name, path) for name, path in _modules()}


def _room(mod):
    parts = mod.split('.')
    return parts[1] if len(parts) > 1 else None


def test_no_import_cycles():
    """Depth-first search over all imports, function-level ones included.

    A package ``__init__`` importing its own submodules is the package's
    normal structure, not a cycle, so edges into a package from its own
    members are not followed."""
    def edges(mod):
        return {t for t in GRAPH[mod]
                if not (mod.startswith(t + '.'))}
    state = {}

    def visit(mod, stack):
        state[mod] = 'open'
        for t in edges(mod):
            if state.get(t) == 'open':
                cycle = stack[stack.index(t):] + [t]
                pytest.fail(f"import cycle: {' -> '.join(cycle)}")
            if t not in state:
                visit(t, stack + [t])
        state[mod] = 'done'

    for mod in GRAPH:
        if mod not in state:
            visit(mod, [mod])


def test_rooms_import_one_way():
    bad = []
    for mod, targets in GRAPH.items():
        room = _room(mod)
        if room not in ALLOWED:
            continue
        for t in targets:
            other = _room(t)
            if other in ALLOWED and other != room \
                    and other not in ALLOWED[room]:
                bad.append(f"{mod} imports {t}")
    assert not bad, '\n'.join(bad)


def test_modules_at_most_800_lines():
    long = {name: n for name, path in _modules()
            if (n := len(path.read_text(encoding='utf-8').splitlines())) > 800}
    assert not long, long


def test_package_root_holds_only_rooms():
    root = {p.stem for p in PACKAGE.glob('*.py')}
    assert root == {'__init__', '__main__', '_checks'}
    for room in ROOMS:
        assert (PACKAGE / room / '__init__.py').is_file(), room


def test_every_public_module_declares_all():
    missing = []
    for name, path in _modules():
        if any(part.startswith('_') for part in name.split('.')[1:]):
            continue
        module = importlib.import_module(name)
        if not isinstance(getattr(module, '__all__', None), list):
            missing.append(name)
            continue
        for attr in module.__all__:
            assert hasattr(module, attr), f"{name}.__all__ lists {attr}"
    assert not missing, missing


def test_package_all_is_built_from_the_rooms():
    for room in ROOMS:
        module = importlib.import_module(f"sandwichctl.{room}")
        if room in ('paper', 'data'):
            assert module.__all__ and room in sw.__all__
            continue
        for name in module.__all__:
            assert name in sw.__all__, name
            assert getattr(sw, name) is getattr(module, name)
    # the studies stay in their room
    for name in ('section5_run', 'section6_run', 'study', 'xystudy'):
        assert name not in sw.__all__ and not hasattr(sw, name), name
    assert sw.examples is sw.paper.examples


DOCS = PACKAGE.parent / 'docs'
TESTS = PACKAGE.parent / 'tests'
#: Test files that check the whole package rather than one module.
CROSS_CUTTING = {'architecture', 'bad_input', 'docs', 'notebooks', 'pickle',
                 'readme', 'warnings'}


def _module_files():
    """Every module file of the package, relative to it (room __init__
    files aside: the rooms have their own rows)."""
    return sorted(str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob('*.py')
                  if p.name != '__init__.py' or p.parent == PACKAGE)


def test_architecture_page_lists_every_module():
    page = (DOCS / 'architecture.md').read_text(encoding='utf-8')
    missing = [rel for rel in _module_files() if f"`{rel}`" not in page]
    assert not missing, (
        "docs/architecture.md does not name these modules (add a row "
        "`room/module.py` | what it holds):\n" + '\n'.join(missing))
    rooms = [room for room in ROOMS if f"**{room}**" not in page]
    assert not rooms, f"docs/architecture.md has no section for {rooms}"


def test_test_files_are_named_after_modules():
    names = {Path(rel).stem.lstrip('_') for rel in _module_files()}
    names |= set(ROOMS)
    stray = []
    for path in sorted(TESTS.glob('test_*.py')):
        name = path.stem[len('test_'):]
        if name in CROSS_CUTTING:
            continue
        if not any(name == m or name.startswith(m + '_') for m in names):
            stray.append(path.name)
    assert not stray, (
        f"test files not named after a module or room "
        f"(test_<module>[_<aspect>].py): {stray}")


#: Longest function of `identification` in lines of code (no docstring,
#: comments or blank lines; compiled kernels aside), and most positional
#: parameters of a private helper (self aside).
MAX_FUNCTION_LINES = 60
MAX_POSITIONAL = 6


def _code_lines(lines, node):
    skip = set()
    body = node.body
    if ast.get_docstring(node, clean=False) is not None:
        skip = set(range(body[0].lineno, body[0].end_lineno + 1))
    return sum(1 for i in range(node.lineno, node.end_lineno + 1)
               if i not in skip and lines[i - 1].strip()
               and not lines[i - 1].strip().startswith('#'))


def test_identification_functions_are_short():
    long, wide = [], []
    for path in sorted((PACKAGE / 'identification').glob('*.py')):
        text = path.read_text(encoding='utf-8')
        lines = text.splitlines()
        for node in ast.walk(ast.parse(text)):
            if not isinstance(node, ast.FunctionDef) or any(
                    'numba' in ast.unparse(d) or 'jit' in ast.unparse(d)
                    for d in node.decorator_list):
                continue
            where = f"{path.name}:{node.lineno} {node.name}"
            if _code_lines(lines, node) > MAX_FUNCTION_LINES:
                long.append(where)
            args = node.args.posonlyargs + node.args.args
            n = len(args) - (bool(args) and args[0].arg in ('self', 'cls'))
            private = node.name.startswith('_') and not (
                node.name.startswith('__') and not path.stem.startswith('_'))
            if (private or path.stem.startswith('_')) and \
                    n > MAX_POSITIONAL:
                wide.append(where)
    assert not long, f"over {MAX_FUNCTION_LINES} lines of code: {long}"
    assert not wide, f"over {MAX_POSITIONAL} positional parameters: {wide}"
