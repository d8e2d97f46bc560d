"""Record readers on files written here in each supported format."""

import numpy as np
import pytest

from screening.core.records import (STANDARD_GRAVITY, Record, expand_records, read_at2, read_record,
                                    read_single_column, read_two_column, write_at2)

DT = 0.01
ACC_G = np.array([0.0, 0.012, -0.034, 0.0561, -0.1, 0.2, 0.0, 3.5e-3, -1.25e-2, 0.0, 0.07])


def _at2_west2(path):
    with open(path, "w") as fh:
        fh.write("PEER NGA STRONG MOTION DATABASE RECORD\n")
        fh.write("Test event 1999, Station X, 090\n")
        fh.write("ACCELERATION TIME SERIES IN UNITS OF G\n")
        fh.write(f"NPTS=   {ACC_G.size}, DT=   .0100 SEC\n")
        for i in range(0, ACC_G.size, 5):
            fh.write("  ".join(f"{v: .7E}" for v in ACC_G[i:i + 5]) + "\n")


def _at2_west1(path):
    with open(path, "w") as fh:
        fh.write("PEER STRONG MOTION DATABASE RECORD. PROCESSING BY PACIFIC ENGINEERING.\n")
        fh.write("IMPERIAL VALLEY 10/15/79 2316, EL CENTRO ARRAY #6, 230\n")
        fh.write("ACCELERATION TIME SERIES IN UNITS OF G\n")
        fh.write(f" {ACC_G.size}    .01000    NPTS, DT\n")
        for i in range(0, ACC_G.size, 4):
            fh.write("".join(f"{v:15.7E}" for v in ACC_G[i:i + 4]) + "\n")


@pytest.mark.parametrize("writer", [_at2_west2, _at2_west1])
def test_at2_both_header_layouts(tmp_path, writer):
    path = tmp_path / "rec.AT2"
    writer(path)
    rec = read_record(path)
    assert rec.dt == pytest.approx(DT, rel=1e-12)
    np.testing.assert_allclose(rec.acceleration, ACC_G * STANDARD_GRAVITY, rtol=1e-7, atol=1e-12)
    assert rec.units_in == "g" and rec.name == "rec"


def test_at2_npts_mismatch_raises(tmp_path):
    path = tmp_path / "bad.at2"
    _at2_west2(path)
    text = path.read_text().replace(f"NPTS=   {ACC_G.size}", f"NPTS=   {ACC_G.size + 1}")
    path.write_text(text)
    with pytest.raises(ValueError, match="NPTS"):
        read_at2(path)


def test_at2_round_trip(tmp_path):
    rec = Record(ACC_G * STANDARD_GRAVITY, 0.005, name="x")
    write_at2(tmp_path / "x.at2", rec)
    back = read_at2(tmp_path / "x.at2")
    np.testing.assert_allclose(back.acceleration, rec.acceleration, rtol=1e-7, atol=1e-12)
    assert back.dt == 0.005


@pytest.mark.parametrize("sep,header", [(",", "time_s,acc_g\n"), ("\t", "# comment\n"), ("  ", "")])
def test_two_column_text_and_csv(tmp_path, sep, header):
    path = tmp_path / "rec.csv"
    t = 1.0 + DT * np.arange(ACC_G.size)             # starts at 1 s: shifted to 0
    path.write_text(header + "".join(f"{ti:.4f}{sep}{a:.6f}\n" for ti, a in zip(t, ACC_G)))
    rec = read_record(path, units="g")
    assert rec.dt == pytest.approx(DT, rel=1e-9)
    np.testing.assert_allclose(rec.acceleration, ACC_G * STANDARD_GRAVITY, atol=1e-6 * STANDARD_GRAVITY)
    rec_si = read_two_column(path, units="m/s2")
    np.testing.assert_allclose(rec_si.acceleration, ACC_G, atol=1e-6)


def test_two_column_non_uniform_raises(tmp_path):
    path = tmp_path / "rec.txt"
    path.write_text("0 0\n0.01 1\n0.03 2\n")
    with pytest.raises(ValueError, match="not uniform"):
        read_record(path, units="g")


def test_single_column_with_dt(tmp_path):
    path = tmp_path / "rec.txt"
    path.write_text("".join(f"{a * 100:.5f}\n" for a in ACC_G))       # cm/s2
    rec = read_record(path, dt=0.02, units="cm/s2")
    assert rec.dt == 0.02
    np.testing.assert_allclose(rec.acceleration, ACC_G, atol=1e-7)
    with pytest.raises(ValueError, match="dt"):
        read_record(path, units="cm/s2")
    rec2 = read_single_column(path, 0.02, units="gal")
    np.testing.assert_allclose(rec2.acceleration, rec.acceleration)


def test_units_refused(tmp_path):
    path = tmp_path / "rec.txt"
    path.write_text("1\n2\n")
    with pytest.raises(ValueError, match="units"):
        read_record(path, dt=0.1, units="ft/s2")


def test_expand_records_folder_and_glob(tmp_path):
    for name in ("b.at2", "a.csv", "c.txt", "skip.nc"):
        (tmp_path / name).write_text("")
    assert [p.split("/")[-1] for p in expand_records(str(tmp_path))] == ["a.csv", "b.at2", "c.txt"]
    assert [p.split("/")[-1] for p in expand_records("*.at2", root=str(tmp_path))] == ["b.at2"]
    with pytest.raises(ValueError, match="match no file"):
        expand_records("*.xyz", root=str(tmp_path))


class _FailsAfterFirstLine(np.ndarray):
    """An acceleration array whose second block of five values cannot be read (a write that fails half-way)."""

    def __getitem__(self, index):
        if isinstance(index, slice) and (index.start or 0) >= 5:
            raise RuntimeError("disk full")
        return np.asarray(self).__getitem__(index)


def test_write_at2_failure_leaves_old_file(tmp_path):
    path = tmp_path / "x.at2"
    write_at2(path, Record(ACC_G * STANDARD_GRAVITY, DT))
    before = path.read_bytes()

    class _Broken:
        acceleration = (ACC_G[::-1] * STANDARD_GRAVITY).view(_FailsAfterFirstLine)
        dt = DT

    with pytest.raises(RuntimeError, match="disk full"):
        write_at2(path, _Broken())
    assert path.read_bytes() == before                               # the old record, whole
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.at2"]   # no temporary file left behind
