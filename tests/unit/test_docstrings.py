"""The public functions of the covered modules have numpydoc docstrings by their rule, and their Examples run.

The rule (``tests/docstring_sections.py``, a small parser: numpydoc is not a dependency), as pvlib and
xclim have it: a function of the user API (the names of ``screening.__all__`` and of the API reference
pages, ``docs/api/*.md``) has the sections Parameters (if it takes any), Returns, References and Examples
with at least one doctest; any other public function, a helper, has a summary (and Notes) alone, or
Parameters and Returns both, or points to the function it repeats (``Compiled twin of :func:`x`.``, ``Like :func:`x` ...``).  Every docstring
documents every parameter of the signature and no other name.  The Examples of every covered module run
here as doctests, so ``make test`` runs them.  ``python tests/docstring_sections.py`` counts the complete
docstrings over the whole package.

COVERED grows as modules are documented; a module in it stays complete.
"""

import doctest
import importlib

import docstring_sections as ds
import pytest

#: Modules whose every public function has a full numpydoc docstring with a running example.
COVERED = [
    "screening.applications.atlas",
    "screening.analysis.correction",
    "screening.analysis.error_model",
    "screening.analysis.escalation",
    "screening.applications.fit_excitation",
    "screening.analysis.fragility",
    "screening.analysis.fragility_surface",
    "screening.applications.im_fragility",
    "screening.analysis.indicators",
    "screening.analysis.intensity",
    "screening.analysis.intensity_records",
    "screening.analysis.intensity_rvt",
    "screening.applications.metrics",
    "screening.analysis.multifidelity",
    "screening.analysis.probabilities",
    "screening.applications.risk",
    "screening.analysis.target_intensity",
    "screening.report.tradeoff",
    "screening.applications.tradeoff_study",
    "screening.analysis.trust",
    "screening.core.atomicfile",
    "screening.analysis.beds",
    "screening.cli.commands",
    "screening.cli.base",
    "screening.cli.records",
    "screening.core.condensation.api",
    "screening.core.condensation.cubic",
    "screening.core.condensation.paper",
    "screening.core.condensation.quadrature",
    "screening.core.condensation.registry",
    "screening.core.condensation.uplift_integrals",
    "screening.core.condensation.virtual_work",
    "screening.core.excitations.base",
    "screening.core.excitations.clough_penzien",
    "screening.core.excitations.kanai_tajimi",
    "screening.core.excitations.registry",
    "screening.report.risk_figures",
    "screening.report.collection_report",
    "screening.kernels.cache",
    "screening.kernels.dopri",
    "screening.core.interpolation",
    "screening.core.signatures",
    "screening.core.laws.hunt_crossley",
    "screening.core.laws.registry",
    "screening.core.laws.winkler",
    "screening.core.limits",
    "screening.core.model.cases",
    "screening.core.model.foundation",
    "screening.core.model.points",
    "screening.core.physics.contact",
    "screening.core.records",
    "screening.report.figure_base",
    "screening.report.figures",
    "screening.report.fragility_figures",
    "screening.report.record_figures",
    "screening.report.spot_figures",
    "screening.report.text",
    "screening.report.tradeoff_figures",
    "screening.report.tradeoff_files",
    "screening.report.tradeoff_text",
    "screening.solvers.schema",
    "screening.solvers.datasets",
    "screening.solvers.estimates",
    "screening.analysis.linearization",
    "screening.solvers.mc_models",
    "screening.solvers.mc_registry",
    "screening.kernels.mcs_equations",
    "screening.kernels.mcs_kernels",
    "screening.solvers.model_choice",
    "screening.kernels.moment_kernels",
    "screening.solvers.moments",
    "screening.solvers.montecarlo",
    "screening.solvers.outputs",
    "screening.solvers.simulate",
    "screening.solvers.stiff_bed",
    "screening.kernels.stiff_bed_contact",
    "screening.kernels.stiff_bed_kernels",
    "screening.solvers.synthesis",
    "screening.solvers.tail",
    "screening.solvers.timegrid",
    "screening.core.status",
    "screening.core.validation",
    "screening.sweep.accuracy",
    "screening.io.cdofile",
    "screening.applications.cloud",
    "screening.sweep.config",
    "screening.sweep.connect",
    "screening.io.errors",
    "screening.sweep.execution",
    "screening.sweep.grid",
    "screening.sweep.interrupt",
    "screening.sweep.probabilities",
    "screening.io.reader",
    "screening.applications.records_study",
    "screening.sweep.study",
    "screening.sweep.run",
    "screening.io.writer",
    "screening.io.zarrfile",
    "screening.sweep.inventory",
]


def test_every_function_of_the_top_level_api_has_a_full_numpydoc_docstring():
    """``screening.linearize``, ``monte_carlo``, ``simulate`` and the condensed model's functions."""
    import screening

    functions = {name: ds.python_function(getattr(screening, name)) for name in screening.__all__}
    functions = {name: f for name, f in functions.items() if f is not None}
    assert {"linearize", "monte_carlo", "simulate"} <= set(functions)
    incomplete = {name: ds.problems(func) for name, func in functions.items() if ds.problems(func)}
    assert not incomplete, incomplete


USER = ds.user_api()


def _problems(functions):
    """``{name: problems}`` of the incomplete docstrings among ``functions``, each by its rule."""
    found = {name: ds.problems(func, func in USER) for name, func in functions.items()}
    return {name: p for name, p in found.items() if p}


def test_the_user_api_holds_the_top_level_names_and_the_api_pages():
    import screening
    from screening.io.reader import open_result

    assert ds.python_function(screening.linearize) in USER and open_result in USER
    assert ds.python_function(ds.sections) not in USER




def _run_examples(module, functions):
    """Run the Examples of ``functions`` ({name: function}) of ``module`` as doctests; ``(attempted, failed)``."""
    finder = doctest.DocTestFinder(recurse=False)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for name, func in functions.items():
        for test in finder.find(func, f"{module.__name__}.{name}", module=module, globs=dict(vars(module))):
            runner.run(test)
    result = runner.summarize(verbose=False)
    return result.attempted, result.failed


def _functions(module_name):
    module = importlib.import_module(module_name)
    return module, ds.public_functions(module)


@pytest.mark.parametrize("module_name", COVERED)
def test_every_public_function_has_a_full_numpydoc_docstring(module_name):
    _, functions = _functions(module_name)
    assert functions, f"{module_name} defines no public function"
    incomplete = _problems(functions)
    assert not incomplete, incomplete


@pytest.mark.parametrize("module_name", COVERED)
def test_the_examples_run(module_name):
    module, functions = _functions(module_name)
    attempted, failed = _run_examples(module, functions)
    assert failed == 0, "a doctest failed (its output is printed above)"
    assert attempted > 0 or not USER & set(functions.values()), "a user function without a doctest"


def test_the_parser_sees_sections_entries_and_missing_parameters():
    """The parser against hand-made docstrings: a full one, one with an undocumented and a stray name."""
    def full(a, b, *args):
        """Summary.

        Parameters
        ----------
        a, b : float
            Two numbers [m].
        *args : float
            More [m].

        Returns
        -------
        float
            Their sum [m].

        References
        ----------
        .. [1] A book.

        Examples
        --------
        >>> full(1, 2)
        3
        """
        return a + b + sum(args)

    def partial(x, y):
        """Summary.

        Parameters
        ----------
        x : float
            A number.
        z : float
            Not a parameter.
            y : indented, so a description line, not an entry.
        """

    def twin(x):
        """Compiled twin of :func:`full`."""

    def short(x):
        """Twice ``x``."""

    assert ds.problems(full) == []
    assert ds.documented_parameters(ds.sections(full.__doc__)["Parameters"]) == ["a", "b", "args"]
    assert ds.problems(partial) == ["no Returns section", "no References section", "no Examples section",
                                    "parameter 'y' undocumented", "'z' documented but not a parameter"]
    assert ds.problems(partial, user=False) == ["no Returns section", "parameter 'y' undocumented",
                                                "'z' documented but not a parameter"]
    assert ds.problems(twin, user=False) == ds.problems(short, user=False) == [] and ds.problems(twin) != []
