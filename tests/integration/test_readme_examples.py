"""The README's shell examples run as written, in order, in a fresh copy of the studies.

Every line of the README's ```bash blocks is run with the package's command line (``.venv/bin/screening``
replaced by this interpreter's ``-m screening.cli``) in a temporary folder holding a copy of
``studies/``, in README order, each expected to exit 0.  Lines not run, and why:

* ``make ...``: the set-up itself (this test runs inside it); ``make run`` is the next block's first line;
* ``--scheduler``: needs a running dask scheduler (tested with one in ``test_edges.py``); the rest of the
  distributed-run recipe (``dask scheduler``/``dask worker``, ``kill``, the export of its result) is run by
  ``test_sweep_zarr.py`` with processes of its own;
* ``tradeoff studies/speed_accuracy.toml``: ~10 minutes of Monte Carlo (the trade study has its own
  tests with a small study, ``tests/unit/analysis/test_tradeoff*.py``).

Lines of other tools (:data:`TOOLS`: CDO, NCO) run where the tool is installed, each expected to exit 0
without a warning (``test_netcdf_cf.py`` checks what they compute).

The fast test shrinks the Monte Carlo of the copied study files (:data:`TINY`: fewer samples) and
calls the command line in this process; the slow one runs every line as its own process on the
studies as shipped.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: substring of a line -> why it is not run
SKIPPED = {
    "make ": "the set-up itself; this test runs inside it",
    "--scheduler": "needs a running dask scheduler",
    ".venv/bin/dask ": "starts a dask scheduler or workers (test_sweep_zarr.py runs this recipe with its own processes)",
    "kill %": "stops the scheduler and workers of the recipe",
    "export outputs/quick.zarr": "exports the result of the skipped --scheduler run",
    "tradeoff studies/speed_accuracy.toml": "about 10 minutes of Monte Carlo; the trade study has its own tests",
}

#: other tools in the README's recipes: run when installed
TOOLS = ("cdo", "ncks")

#: edits of the copied study files that keep the fast test fast (Monte Carlo samples)
TINY = {
    "fragility.toml": [("samples = 500", "samples = 20")],
    "quick.toml": [("samples = 100", "samples = 20")],
}


def readme_commands():
    """``[(line, reason or None)]``: every line of the README's bash blocks, with why it is skipped."""
    text = (ROOT / "README.md").read_text()
    lines = []
    for block in re.findall(r"```bash\n(.*?)```", text, flags=re.S):
        for line in block.splitlines():
            if line.strip():
                reason = next((why for key, why in SKIPPED.items() if key in line), None)
                lines.append((line.strip(), reason))
    return lines


def _run_examples(tmp_path, tiny, monkeypatch=None):
    """Run the README's lines in ``tmp_path``: in this process with :func:`screening.cli.main` when
    ``monkeypatch`` is given (fast: no interpreter start per line), else as subprocesses."""
    shutil.copytree(ROOT / "studies", tmp_path / "studies")
    if tiny:
        for name, edits in TINY.items():
            path = tmp_path / "studies" / name
            text = path.read_text()
            for old, new in edits:
                assert old in text, (name, old)
                text = text.replace(old, new)
            path.write_text(text)
    if monkeypatch is not None:
        from screening.cli import main

        monkeypatch.chdir(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    ran = []
    for line, reason in readme_commands():
        if reason is not None:
            continue
        argv = shlex.split(line, comments=True)
        if argv[0] in TOOLS:
            if shutil.which(argv[0]) is not None:
                proc = subprocess.run(argv, cwd=tmp_path, capture_output=True, text=True, timeout=300)
                assert proc.returncode == 0 and "Warning" not in proc.stderr, f"{line}\n{proc.stderr[-2000:]}"
                ran.append(line)
            continue
        assert argv[0] == ".venv/bin/screening", line
        if monkeypatch is not None:
            assert main(argv[1:]) == 0, line
        else:
            proc = subprocess.run([sys.executable, "-m", "screening.cli", *argv[1:]], cwd=tmp_path, env=env,
                                  capture_output=True, text=True, timeout=900)
            assert proc.returncode == 0, f"{line}\n{proc.stderr[-2000:]}"
        ran.append(line)
    return ran


def test_readme_lists_what_it_skips():
    """Every skipped line has a reason here, and most lines run."""
    commands = readme_commands()
    skipped = [line for line, reason in commands if reason]
    assert any(line.startswith("make run") for line in skipped)
    assert sum(reason is None for _, reason in commands) >= 8, commands


def test_readme_examples_run_in_order(tmp_path, monkeypatch):
    ran = _run_examples(tmp_path, tiny=True, monkeypatch=monkeypatch)
    assert (tmp_path / "outputs" / "quick.nc").is_file() and (tmp_path / "outputs" / "fragility.nc").is_file()
    assert list((tmp_path / "figs").glob("quick_*.png"))
    assert (tmp_path / "outputs" / "fragility_fragility.nc").is_file()
    assert len(ran) >= 8


@pytest.mark.slow
def test_readme_examples_run_as_shipped(tmp_path):
    """As a user types them: each line its own process, the studies as shipped."""
    _run_examples(tmp_path, tiny=False)
