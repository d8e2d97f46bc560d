"""Every file a command writes goes through one temporary file made beside it and a rename
(:mod:`screening.core.atomicfile`): never through a link planted at its name or at a fixed temporary
name, and never over the command's own inputs."""

import os

import numpy as np
import pytest

from helpers import one_line_error

from screening.core.atomicfile import atomic_open, atomic_path
from screening.cli import main
from screening.core.model.excitation import Envelope
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.records import Record, write_at2
from screening.applications.cloud import synthesise_records

BED = """
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
eps = 6e7
"""
CLOUD = BED + '[records]\nfiles = "rec"\nperiod = 0.5\nthreshold = 0.1\nim = "pga"\n'


def _victim(tmp_path):
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    return victim


def test_atomic_open_replaces_a_planted_link_and_leaves_nothing_on_failure(tmp_path):
    victim = _victim(tmp_path)
    out = tmp_path / "out.csv"
    out.symlink_to(victim)
    with atomic_open(out, "w") as fh:
        fh.write("new")
    assert victim.read_text() == "precious" and not out.is_symlink() and out.read_text() == "new"
    with pytest.raises(ZeroDivisionError), atomic_path(out) as tmp:
        tmp.write_text("half")
        1 / 0
    assert out.read_text() == "new" and sorted(p.name for p in tmp_path.iterdir()) == ["out.csv", "victim.txt"]


@pytest.fixture(scope="module")
def record_folder(tmp_path_factory):
    root = tmp_path_factory.mktemp("writers")
    (root / "bed.toml").write_text(BED)
    dt = 0.005
    t = np.arange(0.0, 2.0, dt)
    write_at2(root / "pulse.at2", Record(2.0 * np.sin(2 * np.pi * 2.0 * t) * np.exp(-((t - 1.0) / 0.4) ** 2), dt))
    synthesise_records(root / "rec", KanaiTajimi(1e-3, 15.6, 0.6, Envelope(2.0, 1.0), band_limit_hz=None), 5, 4.0, 100.0,
                       np.geomspace(0.5, 2.5, 5), seed=3)
    (root / "cloud.toml").write_text(CLOUD)
    return root


def test_simulate_does_not_write_through_a_planted_temporary_link(record_folder, tmp_path):
    victim = _victim(tmp_path)
    out = tmp_path / "sim.nc"
    (tmp_path / "sim.nc.tmp").symlink_to(victim)
    assert main(["simulate", str(record_folder / "pulse.at2"), "--study", str(record_folder / "bed.toml"),
                 "--out", str(out), "--no-plots"]) == 0
    assert victim.read_text() == "precious" and out.is_file() and not out.is_symlink()


@pytest.mark.parametrize("which", ["record", "study"])
def test_simulate_refuses_to_overwrite_its_input(record_folder, tmp_path, capsys, which):
    import shutil

    record, study = tmp_path / "pulse.at2", tmp_path / "bed.toml"
    shutil.copy(record_folder / "pulse.at2", record)
    shutil.copy(record_folder / "bed.toml", study)
    target = record if which == "record" else study
    before = target.read_bytes()
    assert main(["simulate", str(record), "--study", str(study), "--out", str(target), "--no-plots"]) == 2
    assert "is the input file" in one_line_error(capsys.readouterr().err)
    assert target.read_bytes() == before


def test_cloud_writes_no_file_through_planted_links_and_not_over_its_inputs(record_folder, tmp_path, capsys):
    victim = _victim(tmp_path)
    out = tmp_path / "c.nc"
    for name in ("c.csv", "c.xml", "c.nc.tmp", "c.csv.tmp"):
        (tmp_path / name).symlink_to(victim)
    study = record_folder / "cloud.toml"
    assert main(["cloud", str(study), "--out", str(out), "--quiet", "--workers", "0"]) == 0
    assert victim.read_text() == "precious"
    for suffix in (".nc", ".csv", ".xml"):
        path = out.with_suffix(suffix)
        assert path.is_file() and not path.is_symlink() and path.stat().st_size > 0, suffix
        assert path.stat().st_mode & 0o777 == 0o666 & ~_umask()
    capsys.readouterr()
    record = sorted((record_folder / "rec").iterdir())[0]
    for target in (study, record):
        before = target.read_bytes()
        assert main(["cloud", str(study), "--out", str(target), "--quiet", "--workers", "0"]) == 2
        assert "is the input file" in one_line_error(capsys.readouterr().err)
        assert target.read_bytes() == before


def _umask():
    mask = os.umask(0)
    os.umask(mask)
    return mask


@pytest.mark.parametrize("command", ["simulate", "cloud", "fit-excitation"])
def test_ctrl_c_in_a_command_that_keeps_nothing_says_so(record_folder, tmp_path, capsys, monkeypatch, command):
    import screening.applications.fit_excitation
    import screening.solvers.simulate
    import screening.applications.cloud

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    for module, name in ((screening.solvers.simulate, "simulate"), (screening.applications.cloud, "run_cloud"),
                         (screening.applications.fit_excitation, "fit_excitation")):
        monkeypatch.setattr(module, name, interrupted)
    argv = {"simulate": ["simulate", str(record_folder / "pulse.at2"), "--study", str(record_folder / "bed.toml"),
                         "--out", str(tmp_path / "s.nc")],
            "cloud": ["cloud", str(record_folder / "cloud.toml"), "--out", str(tmp_path / "c.nc"), "--quiet",
                      "--workers", "0"],
            "fit-excitation": ["fit-excitation", str(record_folder / "pulse.at2")]}[command]
    assert main(argv) == 130
    lines = [line for line in capsys.readouterr().err.splitlines()
             if line.strip() and not line.startswith("screening: compiling")]     # a fresh numba cache says so
    assert lines == ["screening: interrupted; nothing is kept to resume from, re-run the command to start again"]
    assert list(tmp_path.iterdir()) == []
