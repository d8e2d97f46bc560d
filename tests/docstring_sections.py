"""A small numpydoc section parser for the docstring tests (numpydoc itself is not a dependency).

Shared by ``tests/unit/test_docstrings.py`` (which fails on an incomplete docstring in the covered
modules) and ``python tests/docstring_sections.py`` (which counts complete docstrings over the package).

A section is a title line followed by a line of dashes (numpydoc); the entries of ``Parameters``
are its unindented lines, ``name : type`` or ``name1, name2 : type``.  A public function is a
function (or a compiled numba function) named in its module's ``__all__`` and defined there.
"""

import importlib
import inspect
import pkgutil
import re

#: The sections every public function's docstring has.
REQUIRED = ("Parameters", "Returns", "References", "Examples")
_ENTRY = re.compile(r"^(\*{0,2}[A-Za-z_][\w]*(?:\s*,\s*\*{0,2}[A-Za-z_][\w]*)*)\s*(?::.*)?$")


def sections(doc):
    """``{title: [lines]}`` of a docstring's numpydoc sections (the lines dedented); ``""`` holds the summary."""
    lines = inspect.cleandoc(doc or "").splitlines()
    out, title = {"": []}, ""
    i = 0
    while i < len(lines):
        line = lines[i]
        underline = lines[i + 1].strip() if i + 1 < len(lines) else ""
        if line.strip() and underline and set(underline) == {"-"} and len(underline) == len(line.strip()):
            title = line.strip()
            out[title] = []
            i += 2
            continue
        out[title].append(line)
        i += 1
    return out


def documented_parameters(lines):
    """The parameter names of a ``Parameters`` section (``*args`` and ``args`` alike)."""
    names = []
    for line in lines:
        if line and not line[0].isspace():
            match = _ENTRY.match(line.strip())
            if match:
                names += [n.strip().lstrip("*") for n in match.group(1).split(",")]
    return names


def signature_parameters(func):
    """The parameter names of a function's signature, without ``self``/``cls``."""
    try:
        params = inspect.signature(func).parameters
    except (TypeError, ValueError):
        return []
    return [name for name in params if name not in ("self", "cls")]


def _all_parameters(func):
    try:
        return list(inspect.signature(func).parameters)
    except (TypeError, ValueError):
        return []


def problems(func):
    """What a function's docstring lacks: missing sections, undocumented parameters, documented names
    that are not parameters.  Empty for a complete docstring."""
    found = sections(func.__doc__)
    params = signature_parameters(func)
    out = [f"no {name} section" for name in REQUIRED
           if name not in found and not (name == "Parameters" and not params)]
    if "Returns" not in found and "Yields" in found:
        out = [p for p in out if p != "no Returns section"]
    if "Parameters" in found:
        documented = documented_parameters(found["Parameters"])
        out += [f"parameter {p!r} undocumented" for p in params if p not in documented]
        declared = params + [p for p in ("self", "cls") if p in _all_parameters(func)]   # a plain function's ``cls``
        out += [f"{p!r} documented but not a parameter" for p in documented if p not in declared]
    if "Examples" in found and not any(line.lstrip().startswith(">>>") for line in found["Examples"]):
        out.append("Examples without a doctest")
    return out


def python_function(obj):
    """The Python function behind ``obj`` (a compiled numba function's ``py_func``), or None."""
    obj = getattr(obj, "py_func", obj)
    return obj if inspect.isfunction(obj) else None


def public_functions(module):
    """``{name: function}`` of the functions a module declares in ``__all__`` and defines itself."""
    out = {}
    for name in getattr(module, "__all__", []):
        func = python_function(getattr(module, name, None))
        if func is not None and func.__module__ == module.__name__:
            out[name] = func
    return out


def package_modules():
    """Every module of the package, imported."""
    import screening

    names = ["screening"] + [m.name for m in pkgutil.walk_packages(screening.__path__, "screening.")]
    modules = {}
    for name in names:                       # a former home is the moved module itself: counted once
        module = importlib.import_module(name)
        modules.setdefault(module.__name__, module)
    return list(modules.values())


def coverage():
    """``(complete, total)`` public functions over the whole package."""
    funcs = {f"{m.__name__}.{n}": f for m in package_modules() for n, f in public_functions(m).items()}
    return sum(not problems(f) for f in funcs.values()), len(funcs)


if __name__ == "__main__":
    complete, total = coverage()
    print(f"public functions with a complete numpydoc docstring: {complete} of {total}")
