"""Record readers on hostile or ambiguous input: each case is refused with one line naming the file (and
the line number, never the line's content), or read as the file says."""

import os
import time

import numpy as np
import pytest

from screening.core.records import STANDARD_GRAVITY, Record, check_scale, read_at2, read_record, read_single_column
from screening.core import limits

DT = 0.005
ACC_G = np.array([0.01, -0.02, 0.05, 0.03, -0.04, 0.0, 0.02])


def _columns(path, *cols, header="", fmt="{:.6f}", sep=","):
    path.write_text(header + "".join(sep.join(fmt.format(c[i]) for c in cols) + "\n" for i in range(cols[0].size)))
    return path


def _times(n=ACC_G.size, start=0.0):
    return start + DT * np.arange(n)


def _at2(path, units_line="ACCELERATION TIME SERIES IN UNITS OF G", header=None, values=ACC_G, footer=""):
    header = header or f"NPTS=   {values.size}, DT=   {DT:.4f} SEC"
    body = "".join(f"{v:15.7E}" + ("\n" if i % 5 == 4 else "") for i, v in enumerate(values))
    path.write_text(f"PEER NGA\nevent, station\n{units_line}\n{header}\n{body}\n{footer}")
    return path


# ------------------------------------------------------------------ columns and time step
def test_two_columns_are_time_and_acceleration_whatever_dt_says(tmp_path):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G)
    plain = read_record(path, units="g")
    agreeing = read_record(path, dt=DT, units="g")
    np.testing.assert_allclose(agreeing.acceleration, ACC_G * STANDARD_GRAVITY, atol=1e-6 * STANDARD_GRAVITY)
    assert agreeing.acceleration.size == ACC_G.size and agreeing.dt == pytest.approx(plain.dt, rel=1e-12)
    with pytest.raises(ValueError, match=r"time column gives a step of 0\.005 s but dt = 0\.01") as err:
        read_record(path, dt=0.01, units="g")
    assert "\n" not in str(err.value)
    with pytest.raises(ValueError, match="columns: the first is time"):
        read_single_column(path, DT, units="g")


def test_three_columns_carry_the_vertical_component(tmp_path):
    vertical = -0.5 * ACC_G[::-1]
    path = _columns(tmp_path / "r.txt", _times(start=2.0), ACC_G, vertical, header="time [s] ; h [g] ; v [g]\n",
                    sep=" ; ")
    rec = read_record(path)                                    # units from the column titles
    assert rec.units_in == "g" and rec.dt == pytest.approx(DT, rel=1e-9)
    np.testing.assert_allclose(rec.acceleration, ACC_G * STANDARD_GRAVITY, atol=1e-6 * STANDARD_GRAVITY)
    np.testing.assert_allclose(rec.vertical, vertical * STANDARD_GRAVITY, atol=1e-6 * STANDARD_GRAVITY)
    doubled = rec.scaled(2.0)
    np.testing.assert_allclose(doubled.vertical, 2.0 * rec.vertical)
    np.testing.assert_allclose(doubled.acceleration, 2.0 * rec.acceleration)


def test_a_nan_in_the_time_column_is_refused(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("0.0,0.1\n0.005,0.2\nnan,0.3\n0.015,0.1\n")
    with pytest.raises(ValueError, match=r"r\.csv, line 3: not a row of plain decimal numbers"):
        read_record(path, units="g")


def test_ragged_columns_name_the_line(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("0.0,0.1\n0.005,0.2\n0.01\n")
    with pytest.raises(ValueError, match="line 3: 1 numbers, but the data starts with 2 per line"):
        read_record(path, units="g")


# ------------------------------------------------------------------ units
def test_a_text_record_without_units_is_refused_naming_the_option(tmp_path):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G)
    with pytest.raises(ValueError, match=r"units are not stated; give --units \(g, m/s2 or cm/s2\)") as err:
        read_record(path, option="--units")
    assert "\n" not in str(err.value)
    one = tmp_path / "one.txt"
    one.write_text("".join(f"{a}\n" for a in ACC_G))
    with pytest.raises(ValueError, match="records.units"):
        read_record(one, dt=DT, option="records.units")


@pytest.mark.parametrize("header,units", [("# units: cm/s2\n", "cm/s2"), ("units = g\n", "g"),
                                          ("Time (sec), Accel (g)\n", "g"), ("t [s]\ta [m/s2]\n", "m/s2"),
                                          ("# station (Northridge)\n# units: gal\n", "gal")])
def test_units_read_from_a_header(tmp_path, header, units):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G, header=header)
    rec = read_record(path)
    assert rec.units_in == units
    factor = {"g": STANDARD_GRAVITY, "m/s2": 1.0, "cm/s2": 0.01, "gal": 0.01}[units]
    np.testing.assert_allclose(rec.acceleration, ACC_G * factor, atol=1e-6 * factor)


def test_stated_units_and_given_units_must_agree(tmp_path):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G, header="# units: g\n")
    assert read_record(path, units="g").units_in == "g"
    with pytest.raises(ValueError, match="line 1 states the units 'g' but --units 'm/s2' was given"):
        read_record(path, units="m/s2", option="--units")
    bad = _columns(tmp_path / "b.csv", _times(), ACC_G, header="# units: ft/s2\n")
    with pytest.raises(ValueError, match="line 1: states acceleration units other than"):
        read_record(bad, units="g")


def test_at2_units_line_without_units_of(tmp_path):
    path = _at2(tmp_path / "r.at2", units_line="ACCELERATION TIME SERIES")
    with pytest.raises(ValueError, match="units are not stated; give --units .* IN UNITS OF G"):
        read_record(path, option="--units")
    rec = read_record(path, units="cm/s2")                       # explicit: taken as said
    np.testing.assert_allclose(rec.acceleration, ACC_G * 0.01, rtol=1e-7)
    with pytest.raises(ValueError, match="states the units 'g' but units 'm/s2'"):
        read_at2(_at2(tmp_path / "g.at2"), units="m/s2")
    with pytest.raises(ValueError, match="line 3: units other than"):
        read_at2(_at2(tmp_path / "ft.at2", units_line="ACCELERATION IN UNITS OF FT/S2"))


# ------------------------------------------------------------------ tokens
@pytest.mark.parametrize("token", ["nan", "NaN", "Infinity", "-inf", "1_0", "0x10", "1e5000"])
def test_only_plain_finite_decimal_numbers(tmp_path, token):
    path = tmp_path / "r.txt"
    path.write_text("0.1\n0.2\n" + token + "\n0.3\n")
    with pytest.raises(ValueError, match=r"r\.txt(, line 3|: a value overflows)"):
        read_record(path, dt=DT, units="g")


def test_a_utf8_bom_does_not_turn_the_first_row_into_a_header(tmp_path):
    path = tmp_path / "r.csv"
    path.write_bytes(b"\xef\xbb\xbf" + "".join(f"{t:.3f},{a}\n" for t, a in zip(_times(), ACC_G)).encode())
    rec = read_record(path, units="g")
    assert rec.acceleration.size == ACC_G.size
    np.testing.assert_allclose(rec.acceleration[0], ACC_G[0] * STANDARD_GRAVITY)


def test_at2_footer_is_not_a_sample_and_data_after_it_is_refused(tmp_path):
    rec = read_at2(_at2(tmp_path / "f.at2", footer="END OF DATA 2019\n"))
    assert rec.acceleration.size == ACC_G.size and rec.pga < 1.0
    with pytest.raises(ValueError, match=r"line 7: not a row of plain decimal numbers, inside the data"):
        read_at2(_at2(tmp_path / "g.at2", footer="END OF DATA\n 0.5\n"))
    with pytest.raises(ValueError, match="NPTS=7 but the file has 6 values"):
        read_at2(_at2(tmp_path / "h.at2", header=f"NPTS=   7, DT=   {DT:.4f} SEC", values=ACC_G[:6]))


def test_at2_fortran_fields_that_touch(tmp_path):
    path = _at2(tmp_path / "t.at2", values=ACC_G[:2])
    head, data = path.read_text().split("SEC\n")
    path.write_text(head + "SEC\n" + data.replace(" ", ""))
    np.testing.assert_allclose(read_at2(path).acceleration, ACC_G[:2] * STANDARD_GRAVITY, rtol=1e-7)


@pytest.mark.parametrize("header,npts,dt", [(f"7    {DT}    NPTS, DT", 7, DT), (f"{DT}    7    DT, NPTS", 7, DT),
                                            (f"NPTS=7, DT={DT} SEC", 7, DT)])
def test_at2_header_layouts_by_their_labels(tmp_path, header, npts, dt):
    rec = read_at2(_at2(tmp_path / "r.at2", header=header))
    assert rec.acceleration.size == npts and rec.dt == dt


@pytest.mark.parametrize("header,match", [("NPTS=0, DT=0.005", "NPTS must be an integer"),
                                          ("NPTS=7.5, DT=0.005", "NPTS must be an integer"),
                                          ("NPTS=7, DT=0", r"DT must be a number of seconds in \[1e-06, 1\]"),
                                          ("NPTS=7, DT=1e300", "DT must be a number of seconds"),
                                          ("NPTS=7, DT=nan", "DT is not a plain decimal number"),
                                          ("7 0.005", "expected 'NPTS= n, DT= dt SEC'"),
                                          ("NPTS=99999999999, DT=0.005", "NPTS must be an integer")])
def test_at2_header_values_are_checked(tmp_path, header, match):
    with pytest.raises(ValueError, match=r"r\.at2, line 4: " + match):
        read_at2(_at2(tmp_path / "r.at2", header=header))


def test_at2_dt_given_must_agree_with_the_header(tmp_path):
    path = _at2(tmp_path / "r.at2")
    assert read_record(path, dt=DT).dt == DT
    with pytest.raises(ValueError, match="header gives DT = 0.005 s but dt = 0.01"):
        read_record(path, dt=0.01)


def test_errors_name_the_line_never_its_content(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("0.0,0.1\n0.005,0.2\npassword=hunter2\n0.01,0.3\n")
    with pytest.raises(ValueError) as err:
        read_record(path, units="g")
    assert "line 3" in str(err.value) and "hunter2" not in str(err.value)


# ------------------------------------------------------------------ the file itself
def test_file_kinds_are_named_not_called_missing(tmp_path):
    (tmp_path / "loop").symlink_to(tmp_path / "loop")
    (tmp_path / "broken").symlink_to(tmp_path / "absent")
    cases = {str(tmp_path): "is a folder, not a file", str(tmp_path / "loop"): "is a symbolic link loop",
             str(tmp_path / "broken"): "is a broken symbolic link", str(tmp_path / "none.csv"): "does not exist",
             "/dev/zero": "is a device, not a file", "/dev/urandom": "is a device, not a file"}
    for path, said in cases.items():
        with pytest.raises(ValueError, match=said) as err:
            read_record(path, units="g", dt=DT)
        assert "\n" not in str(err.value)


def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    start = time.monotonic()
    with pytest.raises(ValueError, match="is a FIFO"):
        read_record(fifo, units="g")
    assert time.monotonic() - start < 5.0


def test_a_bytes_path_is_read(tmp_path):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G)
    assert read_record(os.fsencode(path), units="g").acceleration.size == ACC_G.size


def test_the_size_is_checked_before_reading(tmp_path, monkeypatch):
    path = _columns(tmp_path / "r.csv", _times(), ACC_G)
    monkeypatch.setattr(limits, "MAX_RECORD_BYTES", 50)
    with pytest.raises(ValueError, match=r"has \d+ bytes; at most 50 are read"):
        read_record(path, units="g")


def test_the_number_of_samples_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(limits, "MAX_RECORD_SAMPLES", 5)
    with pytest.raises(ValueError, match="more than 5 data lines"):
        read_record(_columns(tmp_path / "r.csv", _times(), ACC_G), units="g")
    with pytest.raises(ValueError, match="has 7 samples; at most 5"):
        Record(ACC_G, DT)


# ------------------------------------------------------------------ the record object
@pytest.mark.parametrize("dt", [0.0, -0.01, 1e300, float("nan"), True, 2.0, "0.01"])
def test_record_time_step_range(dt):
    with pytest.raises(ValueError, match="time step 'dt' must be a number of seconds in"):
        Record(ACC_G, dt)


@pytest.mark.parametrize("values", [np.array([True, False, True]), np.array(["2020-01-01", "2020-01-02"],
                                                                             dtype="datetime64[D]")])
def test_record_values_must_be_numbers(values):
    with pytest.raises(ValueError, match="must be numbers"):
        Record(values, DT)


def test_record_vertical_must_match():
    with pytest.raises(ValueError, match="'vertical' has 3 samples, 'acceleration' 7"):
        Record(ACC_G, DT, vertical=ACC_G[:3])


@pytest.mark.parametrize("scale", [float("nan"), float("inf"), 1e308, 0.0, -1.0, True])
def test_scale_checked(scale):
    with pytest.raises(ValueError, match=r"must be a finite number with 0 < scale <= 1000"):
        check_scale(scale)
    assert check_scale(-2.0, signed=True) == -2.0


def test_separators_the_fast_path_does_not_know(tmp_path):
    path = tmp_path / "r.txt"
    path.write_text("".join(f"{t:.3f}\u00a0{a}\n" for t, a in zip(_times(), ACC_G)))     # non-breaking spaces
    np.testing.assert_allclose(read_record(path, units="m/s2").acceleration, ACC_G)
