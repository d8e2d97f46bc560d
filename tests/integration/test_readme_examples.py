"""The examples of the README and of the docs pages run as written, in order, one test per example.

What counts as an example, in README order and then the docs pages (:data:`PAGES` first, the others
alphabetically):

* every line of a ```bash block, run with the package's command line (``.venv/bin/screening``
  replaced by :func:`screening.cli.main` in this process, or ``python -m screening.cli`` in the slow
  test), each expected to exit 0;
* every ```python block, run with ``exec`` (:data:`FRAGMENTS` lists the blocks that are fragments of a
  longer program, with why);
* every ```toml block: it must parse; one whose first line names a file (``# examples/statue.toml``)
  is that file: compared with the repository's copy when there is one (the quickstart's study is
  ``examples/collection.toml``), else written into the working folder for the lines after it; either
  way it must load as a study.

All run in one temporary folder holding copies of ``studies/`` and ``examples/``.  Lines not run, and
why, are in :data:`SKIPPED`; lines of other tools (:data:`TOOLS`: CDO, NCO) run where the tool is
installed, each expected to exit 0 without a warning (``test_netcdf_cf.py`` checks what they compute).

Each example is its own test, so a run shows its progress line by line and no test is silent for long.
The fast tests shrink the Monte Carlo of the copied study files (:data:`TINY`: fewer samples and spot
checks, shorter records; what is asserted here is that the examples run, not their numbers); the slow
ones run every line as its own process on the studies as shipped.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib
from pathlib import Path

import pytest

from screening.sweep.study import load_study

ROOT = Path(__file__).resolve().parents[2]

#: docs pages whose examples build on each other, in this order (after the README); then the others
PAGES = ("README.md", "docs/cli.md", "docs/outputs.md", "docs/distributed.md")

#: substring of a line -> why it is not run
SKIPPED = {
    "make ": "the set-up itself; this test runs inside it",
    "--scheduler": "needs a running dask scheduler",
    ".venv/bin/dask ": "starts a dask scheduler or workers (test_sweep_zarr.py runs this recipe with its own processes)",
    "echo $! > /tmp/": "keeps the process id of the scheduler or workers the recipe started",
    'kill "$(cat /tmp/': "stops the scheduler and workers of the recipe by their process ids",
    "export outputs/quick.zarr": "exports the result of the skipped --scheduler run",
    "tradeoff studies/speed_accuracy.toml": "about 10 minutes of Monte Carlo; the trade study has its own tests",
}

#: (page, substring of a python block) -> why the block is a fragment, not a program
FRAGMENTS = {
    ("docs/records.md", "RSN6_IMPVALL"): "needs a PEER record file and a block and bed defined before it",
    ("docs/distributed.md", "SLURMCluster"): "submits jobs to a SLURM queue (test_cluster.py runs the same path "
                                             "on dask-jobqueue's local cluster)",
}

#: other tools in the recipes: run when installed
TOOLS = ("cdo", "ncks")

#: edits of the copied study files that keep the fast tests fast (Monte Carlo samples)
TINY = {
    "studies/fragility.toml": [("samples = 500", "samples = 4"), ("t_end = 20.0", "t_end = 5.0"),
                               ("{index = {eps = 0, S0 = 18}}, {index = {eps = 0, S0 = 20}},\n", ""),
                               ("{index = {eps = 1, S0 = 18}}, {index = {eps = 1, S0 = 20}},\n", "")],
    "studies/quick.toml": [("samples = 100", "samples = 20")],
    "examples/statue.toml": [("budget_s = 60", "budget_s = 3")],
    "examples/collection.toml": [("budget_s = 600", "budget_s = 3"), ("num = 10", "num = 2")],
}


def _pages():
    others = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "docs").glob("*.md"))
    return list(PAGES) + [p for p in others if p not in PAGES]


def doc_examples():
    """``[(page, kind, text, reason or None)]`` in document order; ``kind`` is bash, python or toml."""
    examples = []
    for page in _pages():
        text = (ROOT / page).read_text()
        for kind, block in re.findall(r"```(bash|python|toml)\n(.*?)```", text, flags=re.S):
            if kind == "bash":
                for line in block.splitlines():
                    if line.strip():
                        reason = next((why for key, why in SKIPPED.items() if key in line), None)
                        examples.append((page, kind, line.strip(), reason))
            else:
                reason = next((why for (where, key), why in FRAGMENTS.items() if where == page and key in block),
                              None)
                examples.append((page, kind, block, reason))
    return examples


EXAMPLES = doc_examples()


def _id(example):
    page, kind, text, _ = example
    first = text.strip().splitlines()[0] if text.strip() else ""
    return f"{page}:{kind}:{re.sub(r'[^A-Za-z0-9_.=-]+', '_', first)[:60]}"


def _workspace(path, tiny):
    for folder in ("studies", "examples"):
        shutil.copytree(ROOT / folder, path / folder)
    (path / "outputs").mkdir()
    if tiny:
        for name, edits in TINY.items():
            file = path / name
            text = file.read_text()
            for old, new in edits:
                assert old in text, (name, old)
                text = text.replace(old, new)
            file.write_text(text)
    return path


@pytest.fixture(scope="module")
def tiny_workspace(tmp_path_factory):
    return _workspace(tmp_path_factory.mktemp("docs_examples"), tiny=True)


@pytest.fixture(scope="module")
def shipped_workspace(tmp_path_factory):
    return _workspace(tmp_path_factory.mktemp("docs_examples_shipped"), tiny=False)


def _run(example, workspace, in_process):
    page, kind, text, reason = example
    if reason is not None:
        pytest.skip(reason)
    if kind == "toml":
        parsed = tomllib.loads(text)
        named = re.match(r"#\s*(\S+\.toml)", text)
        if named is None:
            assert isinstance(parsed, dict)
            return
        target = ROOT / named.group(1)
        if target.is_file():
            assert text == target.read_text(), f"{page} shows {named.group(1)} other than the file"
        else:
            (workspace / named.group(1)).write_text(text)
        load_study(workspace / named.group(1))          # a study file shown whole loads and validates
        return
    cwd = os.getcwd()
    os.chdir(workspace)
    try:
        if kind == "python":
            exec(compile(text, f"<{page}>", "exec"), {"__name__": "__doc_example__"})
            return
        argv = shlex.split(text, comments=True)
        if argv[0] in TOOLS:
            if shutil.which(argv[0]) is None:
                pytest.skip(f"{argv[0]} is not installed")
            proc = subprocess.run(argv, capture_output=True, text=True, timeout=300)
            assert proc.returncode == 0 and "Warning" not in proc.stderr, f"{text}\n{proc.stderr[-2000:]}"
            return
        assert argv[0] == ".venv/bin/screening", text
        if in_process:
            from screening.cli import main

            assert main(argv[1:]) == 0, text
        else:
            env = {**os.environ, "PYTHONPATH": str(ROOT)}
            proc = subprocess.run([sys.executable, "-m", "screening.cli", *argv[1:]], env=env,
                                  capture_output=True, text=True, timeout=900)
            assert proc.returncode == 0, f"{text}\n{proc.stderr[-2000:]}"
    finally:
        os.chdir(cwd)


def test_examples_are_found_and_most_run():
    """Every skipped line has a reason here, the quickstart is among the examples, and most lines run."""
    bash = [e for e in EXAMPLES if e[1] == "bash"]
    assert any(line.startswith("make run") and reason for _, _, line, reason in bash)
    assert sum(reason is None for *_, reason in bash) >= 12, bash
    readme = [text for page, _, text, _ in EXAMPLES if page == "README.md"]
    assert any(text.startswith(".venv/bin/screening run examples/collection.toml") for text in readme)
    assert any("fragility outputs/collection.nc" in text and "--limit-state overturn" in text for text in readme)


def test_the_quickstart_shows_rows_of_the_collection_file():
    """The quickstart's excerpt of ``examples/collection.csv`` (a block without a language, not run) is the file's
    header and rows as they are."""
    text = (ROOT / "README.md").read_text()
    excerpt = re.search(r"```\n# examples/collection.csv[^\n]*\n(.*?)```", text, flags=re.S).group(1)
    rows = (ROOT / "examples" / "collection.csv").read_text().splitlines()
    lines = excerpt.strip().splitlines()
    assert len(lines) >= 2 and all(line in rows for line in lines), lines


def test_quickstart_is_at_most_40_lines():
    text = (ROOT / "README.md").read_text()
    quickstart = re.search(r"^## Quickstart.*?(?=^## )", text, flags=re.S | re.M).group(0)
    assert len(quickstart.rstrip().splitlines()) <= 40


@pytest.mark.parametrize("example", EXAMPLES, ids=[_id(e) for e in EXAMPLES])
def test_example_runs(example, tiny_workspace):
    _run(example, tiny_workspace, in_process=True)


def test_examples_wrote_what_they_say(tiny_workspace):
    """After the examples above (same module, same folder): the files the pages name are there."""
    out = tiny_workspace / "outputs"
    for name in ("collection.nc", "collection_overturn_pga.nc", "collection_overturn_pga.png", "my_study.nc", "quick.nc",
                 "fragility.nc", "fragility_fragility.nc"):
        assert (out / name).is_file(), name
    assert list((tiny_workspace / "figs").glob("quick_*.png"))


@pytest.mark.slow
@pytest.mark.parametrize("example", EXAMPLES, ids=[_id(e) for e in EXAMPLES])
def test_example_runs_as_shipped(example, shipped_workspace):
    """As a user types them: each line its own process, the studies as shipped."""
    _run(example, shipped_workspace, in_process=False)
