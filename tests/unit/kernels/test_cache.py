"""The first-run compilation notice: a cold numba cache is detected from its index files."""

import io
import os
import sys

import pytest

from screening.kernels import cache


@pytest.fixture
def package(tmp_path, monkeypatch):
    """A fake package folder holding the key kernels' sources and no cache."""
    monkeypatch.setattr(cache, "_PACKAGE", tmp_path)
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    for module, _ in cache.KEY_KERNELS:
        (tmp_path / module).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / module).write_text("# source\n")
        os.utime(tmp_path / module, (1_000_000, 1_000_000))
    return tmp_path


def _write_indexes(package, mtime):
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    for module, function in cache.KEY_KERNELS:
        source = package / module
        index = source.parent / "__pycache__" / f"{source.stem}.{function}-12.{tag}.nbi"
        index.parent.mkdir(exist_ok=True)
        index.write_bytes(b"")
        os.utime(index, (mtime, mtime))


def test_a_fresh_clone_is_cold_and_says_so_in_one_line(package):
    stream = io.StringIO()
    assert cache.announce_compilation(stream)
    assert stream.getvalue().count("\n") == 1 and "compiling the solvers" in stream.getvalue()


def test_current_indexes_are_warm_and_silent(package):
    _write_indexes(package, 2_000_000)
    stream = io.StringIO()
    assert not cache.announce_compilation(stream) and stream.getvalue() == ""


def test_an_index_older_than_its_source_is_cold(package):
    _write_indexes(package, 2_000_000)
    os.utime(package / cache.KEY_KERNELS[1][0], (3_000_000, 3_000_000))     # the source was edited
    assert cache.cache_is_cold()


def test_a_cache_under_numba_cache_dir_is_judged_where_numba_keeps_it(package, monkeypatch, tmp_path):
    """A fresh NUMBA_CACHE_DIR (a cluster node's folder, the portable run) is cold and says so; indexes where
    numba's user-provided locator puts them are warm (the real locator: test_the_installed_package_is_warm...)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    assert cache.cache_is_cold()
    tag = f"py{sys.version_info.major}{sys.version_info.minor}"
    for module, function in cache.KEY_KERNELS:
        source = package / module
        folder = cache._cache_folder(source)
        assert folder.parent == tmp_path / "elsewhere"
        folder.mkdir(parents=True, exist_ok=True)
        index = folder / f"{source.stem}.{function}-1.{tag}.nbi"
        index.write_bytes(b"")
        os.utime(index, (2_000_000, 2_000_000))
        os.utime(source, (1_000_000, 1_000_000))
    assert not cache.cache_is_cold()


def test_the_installed_package_is_warm_after_importing_it():
    """After the test session imported and ran the solvers, the real cache is current."""
    import screening as sc

    sc.linearize(sc.Block(m=8.67, b=0.035, h=0.21), sc.Foundation(k=2.89e7, lam=8.95e8),
                 sc.WhiteNoise(S0=1e-5), t_end=0.2)
    sc.monte_carlo(sc.Block(m=8.67, b=0.035, h=0.21), sc.Foundation(k=2.89e7, lam=8.95e8),
                   sc.WhiteNoise(S0=1e-5), n_samples=2, t_end=0.2)
    assert not cache.cache_is_cold()


def test_only_commands_that_compute_announce_it(package, monkeypatch, tmp_path, capsys):
    """`screening info` compiles nothing and says nothing; `run` says it first, unless --quiet."""
    from screening.cli import commands as cli

    monkeypatch.setattr(cache, "cache_is_cold", lambda: True)
    cli.announce_compilation(quiet=True)
    assert capsys.readouterr().err == ""
    cli.announce_compilation()
    assert capsys.readouterr().err.startswith("screening: compiling the solvers with numba")
    assert cli.main(["info", str(tmp_path / "missing.nc")]) == 2
    assert "compiling" not in capsys.readouterr().err


# ----------------------------------------------------------------------------- stale kernels of other modules
_CALLEE = "import numba\n\n\n@numba.njit(cache=True)\ndef step():\n    return {value}.0\n"
_CALLER = ("import numba\n\nfrom pkg.callee import step\n\n\n@numba.njit(cache=True)\ndef twice():\n"
           "    return 2.0 * step()\n")
_RUN = ("import sys; sys.path.insert(0, {root!r})\n"
        "from screening.kernels.cache import clear_stale_cache\n"
        "{clear}\n"
        "from pkg.caller import twice\n"
        "print(twice())\n")


def _twice(root, clear):
    import subprocess

    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    code = _RUN.format(root=str(root), clear=f"clear_stale_cache({str(root / 'pkg')!r})" if clear else "")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    return float(out.stdout.split()[-1])


def test_a_changed_callee_in_another_module_is_recompiled_not_loaded_stale(tmp_path):
    """numba keys a cached kernel on its own file only; the stamp over all sources drops the cache when
    a callee in another file changes, so the caller is compiled again with the new callee."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "callee.py").write_text(_CALLEE.format(value=1))
    (pkg / "caller.py").write_text(_CALLER)
    assert _twice(tmp_path, clear=True) == 2.0                 # compiled and cached
    assert list((pkg / "__pycache__").glob("caller.twice-*.nbi"))
    (pkg / "callee.py").write_text(_CALLEE.format(value=5))
    assert _twice(tmp_path, clear=True) == 10.0                # the stale cache was dropped
    assert _twice(tmp_path, clear=True) == 10.0                # and the new one is kept: unchanged sources


def test_an_unchanged_package_keeps_its_cache_and_a_cache_elsewhere_is_left_alone(tmp_path, monkeypatch):
    (tmp_path / "m.py").write_text("x = 1")
    (tmp_path / "__pycache__").mkdir()
    index = tmp_path / "__pycache__" / "m.f-1.py311.nbi"
    index.write_bytes(b"")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    assert cache.clear_stale_cache(tmp_path) == 1 and not index.exists()     # no stamp: not vouched for
    index.write_bytes(b"")
    assert cache.clear_stale_cache(tmp_path) == 0 and index.exists()
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    (tmp_path / "m.py").write_text("x = 2")
    assert cache.clear_stale_cache(tmp_path) == 0 and index.exists()


def test_the_stamp_follows_the_layers_compiled_code_can_reach(tmp_path):
    """An edit in a folder above ``solvers/`` (the sweep, the command line) keeps the compiled kernels; an edit in
    ``core/``, ``kernels/``, ``solvers/`` or at the top level recompiles them."""
    for folder in ("core", "kernels", "solvers", "sweep", "cli"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "m.py").write_text("x = 1")
    (tmp_path / "__init__.py").write_text("")
    before = cache.source_stamp(tmp_path)
    for folder in ("sweep", "cli"):
        (tmp_path / folder / "m.py").write_text("x = 2")
    assert cache.source_stamp(tmp_path) == before
    for path in ("core/m.py", "kernels/m.py", "solvers/m.py", "__init__.py"):
        (tmp_path / path).write_text("x = 3")
        assert cache.source_stamp(tmp_path) != before, path
        before = cache.source_stamp(tmp_path)
