"""Structure numbers of the package: imports back up the folders (the layers), circles, deferred imports, sizes.

Run: ``python benchmarks/structure.py`` (``--list`` prints every upward import, circle and dodging
import).  The order of the folders is read from the folder table of ``docs/architecture.md``; the parsing is
shared with ``tests/unit/test_layers.py`` (``tests/import_graph.py``).
"""

import ast
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import import_graph as ig  # noqa: E402

ROOT = Path(__file__).resolve().parents[1] / "screening"
#: The modules on the write path of a sweep result, from the solvers to the result formats and ``info``.
OUTPUT_PATH = ("solvers/schema.py", "solvers/outputs.py", "kernels/moment_kernels.py", "solvers/moments.py",
               "solvers/datasets.py", "sweep/execution.py", "io/writer.py", "io/zarrfile.py",
               "io/store.py", "report/text.py")
#: Calls that declare an output variable (its name the first argument).
DECLARATIONS = ("Output", "_history")
#: Output variables whose mentions are counted: a history, a flag, a probability and a solver summary.
OUTPUT_SAMPLES = ("var_theta", "sl_trust", "p_overturn", "min_k_eq")


def output_mentions(name, lists_only=False):
    """``{module: n}``: the string constants equal to ``name`` in each module of :data:`OUTPUT_PATH`
    (``lists_only``: only those in a tuple, list, set, as a dict key or declaring it (:data:`DECLARATIONS`):
    the lists of names; not the reads ``values["name"]`` nor other call arguments)."""
    out = {}
    for module in OUTPUT_PATH:
        path = ROOT / module
        if not path.exists():
            continue
        n = 0
        for parent in ast.walk(ast.parse(path.read_text())):
            if lists_only and isinstance(parent, (ast.Tuple, ast.List, ast.Set)):
                children = parent.elts
            elif lists_only and isinstance(parent, ast.Dict):
                children = [k for k in parent.keys if k is not None]
            elif lists_only and isinstance(parent, ast.Call) and getattr(parent.func, "id", "") in DECLARATIONS:
                children = parent.args[:1]
            elif not lists_only and isinstance(parent, ast.Constant):
                children = [parent]
            else:
                continue
            n += sum(isinstance(c, ast.Constant) and c.value == name for c in children)
        if n:
            out[module] = n
    return out


def statements_inside_functions():
    """The import statements of the package that sit inside a function body (of any module)."""
    inside = set()
    for path in ROOT.rglob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
                inside.update((path, c.lineno) for c in ast.walk(node) if isinstance(c, (ast.Import, ast.ImportFrom)))
    return len(inside)


def public_names(graph):
    """The distinct names of the package's literal ``__all__`` lists."""
    return {name for path in graph.modules.values() for name in (ig.declared_all(path) or [])}


def main(verbose=False):
    """Print the structure numbers."""
    graph = ig.read_graph()
    layers = ig.read_layers()
    unmapped = [m for m in graph.modules if m and ig.layer_of(m, layers) is None
                and graph.modules[m].name != "__init__.py"]
    up = ig.upward(graph, layers)
    circles = ig.cycles(ig.package_edges(graph))
    deferred = [i for i in graph.imports if i.deferred]
    dodging = ig.dodging(graph)
    public = ig.public_modules(graph)
    missing_all = ig.without_all(graph)
    sizes = ig.sizes(graph)
    print(f"modules: {len(graph.modules)} ({len(unmapped)} outside the folders of docs/architecture.md{': ' + ', '.join(unmapped) if unmapped else ''})")
    print(f"imports of the package by the package: {len(graph.imports)}")
    print(f"imports back up the folders: {len(up)} (top-level {sum(not i.deferred for i, _, _ in up)})")
    print(f"import circles: {len(circles)} ({', '.join(' <-> '.join(c) for c in circles)})")
    print(f"imports inside functions: {len(deferred)}; of them dodging a circle: {len(dodging)}")
    print(f"import statements inside functions (any module, package or not): {statements_inside_functions()}")
    print(f"modules without __all__: {len(missing_all)} of {len(public)}")
    print(f"public names (distinct names in the __all__ lists): {len(public_names(graph))}")
    private, undeclared = ig.private_name_uses(graph), ig.undeclared_name_uses(graph)
    print(f"underscored names taken from another module: {len(private)}; names shared inside the package "
          f"outside __all__ (allowed: __all__ is the user API): {len(undeclared)}")
    tested = [m for m in graph.modules if m and graph.modules[m].name != "__init__.py"]
    print(f"source modules with a test module of their own name: "
          f"{sum(ig.has_test_module(m) for m in tested)} of {len(tested)}")
    print("largest modules (lines): " + ", ".join(f"{m} {n}" for n, m in sizes[:5]))
    print("largest modules (lines of code: no docstring, comment or blank line): "
          + ", ".join(f"{m} {n}" for n, m in ig.code_sizes(graph)[:5]))
    mentions = {name: output_mentions(name) for name in OUTPUT_SAMPLES}
    lists = {name: output_mentions(name, lists_only=True) for name in OUTPUT_SAMPLES}
    print("places naming each output variable on the write path (string constants, in files): " + ", ".join(
        f"{name} {sum(m.values())} in {len(m)}" for name, m in mentions.items()))
    print("  of them in lists of names (tuples, lists, sets, dict keys, declarations): " + ", ".join(
        f"{name} {sum(m.values())} in {len(m)}" for name, m in lists.items()))
    if verbose:
        for imp, a, b in up:
            print(f"  up   {imp.source}:{imp.line} ({a}) -> {imp.target} ({b}){' [in a function]' if imp.deferred else ''}")
        for imp in dodging:
            print(f"  dodge {imp.source}:{imp.line} -> {imp.target}")
        for m in missing_all:
            print(f"  no __all__: {m}")
        for use in private + undeclared:
            print(f"  {'private' if use in private else 'undeclared'} {use.source}:{use.line} <- {use.target}.{use.name}")
        for name, m in mentions.items():
            print(f"  {name}: " + ", ".join(f"{module} {n}" for module, n in m.items())
                  + "; in lists: " + ", ".join(f"{module} {n}" for module, n in lists[name].items()))


if __name__ == "__main__":
    main("--list" in sys.argv)
