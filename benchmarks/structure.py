"""Structure numbers of the package: imports back up the layers, circles, deferred imports, sizes.

Run: ``python benchmarks/structure.py`` (``--list`` prints every upward import, circle and dodging
import).  The layers are read from the module table of ``docs/architecture.md``; the parsing is
shared with ``tests/unit/test_layers.py`` (``tests/import_graph.py``).
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import import_graph as ig  # noqa: E402


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
    print(f"modules: {len(graph.modules)} ({len(unmapped)} without a layer{': ' + ', '.join(unmapped) if unmapped else ''})")
    print(f"imports of the package by the package: {len(graph.imports)}")
    print(f"imports back up the layers: {len(up)} (top-level {sum(not i.deferred for i, _, _ in up)})")
    print(f"import circles: {len(circles)} ({', '.join(' <-> '.join(c) for c in circles)})")
    print(f"imports inside functions: {len(deferred)}; of them dodging a circle: {len(dodging)}")
    print(f"modules without __all__: {len(missing_all)} of {len(public)}")
    print("largest modules (lines): " + ", ".join(f"{m} {n}" for n, m in sizes[:5]))
    if verbose:
        for imp, a, b in up:
            print(f"  up   {imp.source}:{imp.line} ({a}) -> {imp.target} ({b}){' [in a function]' if imp.deferred else ''}")
        for imp in dodging:
            print(f"  dodge {imp.source}:{imp.line} -> {imp.target}")
        for m in missing_all:
            print(f"  no __all__: {m}")


if __name__ == "__main__":
    main("--list" in sys.argv)
