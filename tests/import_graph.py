"""The package's import graph read with ``ast``: folders (the layers), upward imports, circles, deferred imports.

Shared by ``tests/unit/test_layers.py`` (which fails on what the architecture page does not allow)
and ``benchmarks/structure.py`` (which prints the structure numbers).  A module's layer is its folder (the first
part of its dotted name; a module at the top, ``_version``, is its own); the order of the folders, from the
bottom, is read from the folder table of ``docs/architecture.md``: the one map of the package.
"""

import ast
import re
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "screening"
ARCHITECTURE = ROOT / "docs" / "architecture.md"

@dataclass(frozen=True)
class Import:
    """One import of a package module by another: where, and whether it sits inside a function."""

    source: str
    target: str
    line: int
    deferred: bool


@dataclass
class Graph:
    """Every module of the package (dotted, without ``screening.``) and its imports of the package."""

    modules: dict = field(default_factory=dict)      # module -> Path
    imports: list = field(default_factory=list)      # [Import]

    def edges(self, deferred=None):
        """``{(source, target)}``, of all imports, the top-level ones (False) or the deferred (True)."""
        return {(i.source, i.target) for i in self.imports
                if i.source != i.target and (deferred is None or i.deferred == deferred)}


def module_name(path):
    """``screening/a/b.py`` -> ``a.b``; a package's ``__init__.py`` -> the package (``a``, or ``""``)."""
    parts = list(path.relative_to(PACKAGE).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _resolve(name, modules):
    """The package module that ``screening.<name>`` names: the module itself or its package."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name


def _inside_function(tree):
    """Ids of the import nodes that sit inside a function body (executed on call, not on import)."""
    inside = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            inside.update(id(n) for n in ast.walk(node) if isinstance(n, (ast.Import, ast.ImportFrom)))
    return inside


def _type_checking_only(tree):
    """Ids of the import nodes under ``if TYPE_CHECKING:`` (never executed)."""
    skipped = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            skipped.update(id(n) for n in ast.walk(node) if isinstance(n, (ast.Import, ast.ImportFrom)))
    return skipped


def _targets(node, source, is_package, modules):
    """The package modules an import node names."""
    if isinstance(node, ast.Import):
        return [n.name for n in node.names]
    if node.level:
        base = source.split(".") if source else []
        base = base if is_package else base[:-1]
        base = base[:len(base) - (node.level - 1)] if node.level > 1 else base
        prefix = "screening." + ".".join(base + ([node.module] if node.module else []))
    else:
        prefix = node.module or ""
    prefix = prefix.rstrip(".")
    names = [f"{prefix}.{alias.name}" for alias in node.names]
    # ``from screening.a import b``: b may be a submodule or a name defined in ``a``.
    return [n if _resolve(n[len("screening."):], modules) == n[len("screening."):] else prefix for n in names]


def read_graph(package=PACKAGE):
    """Parse every module of the package; every import of the package by a package module."""
    graph = Graph()
    for path in sorted(package.rglob("*.py")):
        graph.modules[module_name(path)] = path
    for name, path in graph.modules.items():
        tree = ast.parse(path.read_text(), str(path))
        inside, skipped = _inside_function(tree), _type_checking_only(tree)
        for node in ast.walk(tree):
            if not isinstance(node, (ast.Import, ast.ImportFrom)) or id(node) in skipped:
                continue
            for target in _targets(node, name, path.name == "__init__.py", graph.modules):
                if target != "screening" and not target.startswith("screening."):
                    continue
                resolved = _resolve(target[len("screening."):], graph.modules)
                graph.imports.append(Import(name, resolved, node.lineno, id(node) in inside))
    graph.imports = list(dict.fromkeys(graph.imports))        # one per module named, not per name
    return graph


def read_layers(text=None):
    """The folders of the package from the bottom (imported by all) to the top (imports all): the backticked
    names of the first column of the architecture page's folder table (``| folder | ... |``), in its order."""
    text = ARCHITECTURE.read_text() if text is None else text
    folders, inside = [], False
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("|"):
            inside = False
            continue
        if cells[0] == "folder":
            inside = True
            continue
        if inside and not cells[0].startswith("---"):
            folders += [name.rstrip("/").removesuffix(".py") for name in re.findall(r"`([\w./]+)`", cells[0])]
    return folders


def layer_of(module, layers):
    """The folder (layer) of a module: the first part of its dotted name, if the page lists it; None for the
    package's ``__init__`` (the public face, above every folder) and for a folder the page does not list."""
    folder = module.split(".")[0]
    return folder if module and folder in layers else None


def upward(graph, layers):
    """Imports from a folder up to a folder above it: ``[(Import, source folder, target folder)]``.  Every import
    counts, at the top of a module or inside a function; ``screening/__init__.py`` is above every folder."""
    rank = {name: n for n, name in enumerate(layers)}
    found = []
    for imp in graph.imports:
        a, b = layer_of(imp.source, layers), layer_of(imp.target, layers)
        if a and b and rank[b] > rank[a]:
            found.append((imp, a, b))
    return found


def cycles(edges):
    """The strongly connected components of more than one module (the import circles), sorted."""
    graph = {}
    for a, b in edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index, low, stack, on_stack, found, counter = {}, {}, [], set(), [], [0]

    def visit(v):
        # Tarjan's algorithm, iterative so that a deep graph cannot overflow the stack.
        work = [(v, iter(sorted(graph[v])))]
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        while work:
            node, children = work[-1]
            for child in children:
                if child not in index:
                    index[child] = low[child] = counter[0]
                    counter[0] += 1
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                    break
                if child in on_stack:
                    low[node] = min(low[node], index[child])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == node:
                            break
                    if len(component) > 1:
                        found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def package_edges(graph):
    """Imports between modules, leaving out those of a package ``__init__`` into its own package
    and those into ``screening/__init__`` (the public face): what a circle is counted on."""
    edges = set()
    for a, b in graph.edges():
        if b == "" or a == "":
            continue
        if graph.modules[a].name == "__init__.py" and b.startswith(a + "."):
            continue
        edges.add((a, b))
    return edges


def _reaches(edges, start, goal):
    """Whether ``goal`` is reachable from ``start`` along ``edges``."""
    seen, todo = {start}, [start]
    while todo:
        node = todo.pop()
        if node == goal:
            return True
        for a, b in edges:
            if a == node and b not in seen:
                seen.add(b)
                todo.append(b)
    return False


def dodging(graph):
    """Deferred imports that dodge a circle: moved to the top, they would close one."""
    top = package_edges(graph) & graph.edges(deferred=False)
    return [imp for imp in graph.imports
            if imp.deferred and (imp.source, imp.target) in package_edges(graph)
            and _reaches(top, imp.target, imp.source)]


def public_modules(graph):
    """Modules with no leading underscore in their path and some content (not an empty ``__init__``)."""
    return [name for name, path in graph.modules.items()
            if not any(part.startswith("_") for part in name.split(".")) and path.read_text().strip()]


def without_all(graph):
    """Public modules that do not define ``__all__``."""
    missing = []
    for name in public_modules(graph):
        path = graph.modules[name]
        tree = ast.parse(path.read_text())
        names = {t.id for node in tree.body if isinstance(node, (ast.Assign, ast.AnnAssign))
                 for t in (node.targets if isinstance(node, ast.Assign) else [node.target])
                 if isinstance(t, ast.Name)}
        if "__all__" not in names:
            missing.append(name)
    return missing


def sizes(graph):
    """``[(lines, module)]``, largest first."""
    return sorted(((len(p.read_text().splitlines()), m) for m, p in graph.modules.items()), reverse=True)


def code_lines(text):
    """Lines of code of a module's source: not blank, not a comment, not in a docstring."""
    tree = ast.parse(text)
    docstrings = set()
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and body \
                and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
                and isinstance(body[0].value.value, str):
            docstrings.update(range(body[0].lineno, body[0].end_lineno + 1))
    return sum(1 for n, line in enumerate(text.splitlines(), 1)
               if n not in docstrings and line.strip() and not line.strip().startswith("#"))


def code_sizes(graph):
    """``[(lines of code, module)]`` (:func:`code_lines`), largest first."""
    return sorted(((code_lines(p.read_text()), m) for m, p in graph.modules.items()), reverse=True)


def declared_all(path):
    """The names of a module's literal ``__all__`` (a list), or None (none, or not a literal)."""
    for node in ast.parse(path.read_text()).body:
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            try:
                return list(ast.literal_eval(node.value))
            except ValueError:
                return None
    return None


@dataclass(frozen=True)
class Use:
    """A name of one package module used by another: ``from target import name`` or ``alias.name``
    on an imported module."""

    source: str
    line: int
    target: str
    name: str


def _is_private(name):
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def name_uses(graph):
    """Every name a package module takes from another package module (not the modules themselves):
    the names of ``from ... import`` and the attributes read on an imported module (``kern.x``)."""
    uses = []
    for source, path in graph.modules.items():
        tree = ast.parse(path.read_text(), str(path))
        skipped = _type_checking_only(tree)
        aliases = {}                                  # local name -> package module it is bound to
        for node in ast.walk(tree):
            if id(node) in skipped:
                continue
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.startswith("screening.") and a.asname:
                        aliases[a.asname] = _resolve(a.name[len("screening."):], graph.modules)
            elif isinstance(node, ast.ImportFrom):
                for target, a in zip(_targets(node, source, path.name == "__init__.py", graph.modules), node.names):
                    if not target.startswith("screening.") or a.name == "*":
                        continue
                    dotted = target[len("screening."):]
                    if dotted in graph.modules and dotted.rsplit(".", 1)[-1] == a.name:      # a module
                        aliases[a.asname or a.name] = dotted
                    else:
                        uses.append(Use(source, node.lineno, _resolve(dotted, graph.modules), a.name))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases:
                uses.append(Use(source, node.lineno, aliases[node.value.id], node.attr))
    return [u for u in dict.fromkeys(uses)
            if u.target != u.source and not (u.name.startswith("__") and u.name.endswith("__"))]


def private_name_uses(graph):
    """Underscored names (not dunders) one module takes from another: internals leaking across modules."""
    return [u for u in name_uses(graph) if _is_private(u.name)]


def undeclared_name_uses(graph):
    """Names one module takes from a public module that are not in that module's ``__all__``: its
    internals, or names it merely imported (to be taken from their home).  A package ``__init__``
    gathering its own package's names is not counted."""
    public = set(public_modules(graph))
    declared = {m: declared_all(graph.modules[m]) for m in public}
    return [u for u in name_uses(graph) if u.target in public and not _is_private(u.name)
            and declared[u.target] is not None and u.name not in declared[u.target]
            and not (graph.modules[u.source].name == "__init__.py" and u.target.startswith(u.source + "."))]


def test_modules(root=ROOT / "tests"):
    """The stems of every test module of the suite."""
    return {p.stem for p in root.rglob("test_*.py")}


def has_test_module(module, tests=None):
    """Whether ``a.b.c`` has a test module of its own name: ``test_c.py`` or, where names repeat across
    packages (test basenames are unique in this suite), ``test_b_c.py`` or ``test_a_b_c.py``; a private module
    ``a._b`` is tested under its public name (``test_b.py``)."""
    tests = test_modules() if tests is None else tests
    parts = [p.lstrip("_") for p in module.split(".")]
    return any(f"test_{'_'.join(parts[-n:])}" in tests for n in range(1, len(parts) + 1))
