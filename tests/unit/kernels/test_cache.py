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


def test_a_cache_elsewhere_is_not_judged(package, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(package / "elsewhere"))
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
    from screening import cli

    monkeypatch.setattr(cache, "cache_is_cold", lambda: True)
    cli.announce_compilation(quiet=True)
    assert capsys.readouterr().err == ""
    cli.announce_compilation()
    assert capsys.readouterr().err.startswith("screening: compiling the solvers with numba")
    assert cli.main(["info", str(tmp_path / "missing.nc")]) == 2
    assert "compiling" not in capsys.readouterr().err
