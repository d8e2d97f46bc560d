"""A small numpydoc section parser for the docstring tests (numpydoc itself is not a dependency).

Shared by ``tests/unit/test_docstrings.py`` (which fails on an incomplete docstring in the covered
modules) and ``python tests/docstring_sections.py`` (which counts complete docstrings over the package).

A section is a title line followed by a line of dashes (numpydoc); the entries of ``Parameters``
are its unindented lines, ``name : type`` or ``name1, name2 : type``.  A public function is a
function (or a compiled numba function) that a module defines under a name without an underscore.

The rule, as pvlib and xclim have it: References and Examples where a user calls the function.
- **The user API** (``user_api``): the names of ``screening.__all__`` and of the API reference pages
  (``docs/api/*.md``: each ``::: module`` with its ``__all__`` or its listed ``members``, each
  ``::: module.name``).  A user function's docstring has Parameters (if it takes any), Returns,
  References (the works of the bibliography, ``docs/bibliography.md``, by label) and Examples with a
  doctest.
- **A helper** (any other public function): a summary (and Notes) alone where it says all, or
  Parameters and Returns both (References and Examples are not asked for).  A compiled twin says
  ``Compiled twin of :func:`x`.`` and a wrapper that only resolves a name says ``Like :func:`x` ...``:
  they document nothing again.
Every documented parameter is one of the signature and every parameter is documented.
"""

import importlib
import inspect
import pathlib
import pkgutil
import re

#: The sections of a user function's docstring.
REQUIRED = ("Parameters", "Returns", "References", "Examples")
#: The sections of a helper's docstring.
HELPER_REQUIRED = ("Parameters", "Returns")
#: A docstring that points to its twin or to the function it wraps instead of repeating it.
POINTER = re.compile(r"^(Compiled twin of|Like) :(func|meth|class):")
API_PAGES = pathlib.Path(__file__).resolve().parents[1] / "docs" / "api"
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


def problems(func, user=True):
    """What a function's docstring lacks: missing sections (those of a user function, or of a helper with
    ``user=False``), undocumented parameters, documented names that are not parameters.  Empty for a
    complete docstring."""
    found = sections(func.__doc__)
    if not user and (POINTER.match(inspect.cleandoc(func.__doc__ or ""))
                     or not {"Parameters", "Returns", "Yields"} & set(found)):
        return []
    params = signature_parameters(func)
    out = [f"no {name} section" for name in (REQUIRED if user else HELPER_REQUIRED)
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
    """``{name: function}`` of the functions a module defines itself under a name without an underscore."""
    out = {}
    for name, obj in vars(module).items():
        func = python_function(obj)
        if not name.startswith("_") and func is not None and func.__module__ == module.__name__:
            out[name] = func
    return out


def _api_objects(target, members):
    """The objects an API page's ``::: target`` entry documents."""
    try:
        module = importlib.import_module(target)
    except ImportError:
        parent, name = target.rsplit(".", 1)
        return [getattr(importlib.import_module(parent), name)]
    return [getattr(module, name) for name in (members or getattr(module, "__all__", []))]


def api_entries():
    """``[(target, members)]`` of the ``::: target`` entries of the API pages (members: the listed ones, or
    None)."""
    entries = []
    for page in sorted(API_PAGES.glob("*.md")):
        for line in page.read_text().splitlines():
            stripped = line.strip()
            if stripped.startswith(":::"):
                entries.append((stripped[3:].strip(), None))
            elif stripped.startswith("- ") and entries and line.startswith("        "):
                target, members = entries[-1]
                entries[-1] = (target, (members or []) + [stripped[2:].strip()])
    return entries


def user_api():
    """The Python functions of the user API: ``screening.__all__`` and the API reference pages."""
    import screening

    objects = [getattr(screening, name) for name in screening.__all__]
    for target, members in api_entries():
        objects += _api_objects(target, members)
    return {f for f in map(python_function, objects) if f is not None}


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
    """``(complete, total)`` public functions over the whole package, each by its rule."""
    user = user_api()
    funcs = {f"{m.__name__}.{n}": f for m in package_modules() for n, f in public_functions(m).items()}
    return sum(not problems(f, f in user) for f in funcs.values()), len(funcs)


if __name__ == "__main__":
    complete, total = coverage()
    print(f"public functions with a complete numpydoc docstring by its rule: {complete} of {total}")
