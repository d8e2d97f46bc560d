"""Study files that are not what they seem: a FIFO, a device, a byte-order mark, a huge dotted key, thousands
of cases or thresholds.  Each is one StudyError line, fast, before the work grows."""

import os
import time

import pytest

from screening.core import limits
from screening.sweep.study import StudyError, load_study, parse_study

BASE = """title = "inputs"
[block]
m = 8.67
b = 0.035
h = 0.21
[foundation]
k = 2.89e7
lam = 8.95e8
[excitation]
kind = "white"
S0 = 1e-4
[time]
t_end = 2.0
dt = 0.05
"""


def _fast(call, match, seconds=5.0):
    start = time.monotonic()
    with pytest.raises(StudyError, match=match) as err:
        call()
    assert time.monotonic() - start < seconds
    assert "\n" not in str(err.value)
    return str(err.value)


def test_a_byte_order_mark_is_not_an_invalid_statement(tmp_path):
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + BASE.encode())
    assert load_study(path).title == "inputs"


def test_a_fifo_never_blocks(tmp_path):
    fifo = tmp_path / "study.toml"
    os.mkfifo(fifo)
    _fast(lambda: load_study(fifo), r"study\.toml: cannot read the study file \(is a FIFO \(named pipe\), not a file\)")


@pytest.mark.parametrize("path,said", [("/dev/zero", "is a device, not a file"),
                                       ("/dev/urandom", "is a device, not a file")])
def test_devices_are_refused_before_reading(path, said):
    _fast(lambda: load_study(path), said)


def test_kinds_of_path(tmp_path):
    (tmp_path / "loop.toml").symlink_to(tmp_path / "loop.toml")
    _fast(lambda: load_study(tmp_path / "loop.toml"), "is a symbolic link loop")
    _fast(lambda: load_study(tmp_path), "is a folder, not a file")
    (tmp_path / "s.toml").write_text(BASE)
    assert load_study(os.fsencode(tmp_path / "s.toml")).title == "inputs"        # a bytes path is a path


def test_size_checked_before_reading(tmp_path, monkeypatch):
    path = tmp_path / "big.toml"
    path.write_text(BASE + "#" * 200)
    monkeypatch.setattr(limits, "MAX_STUDY_BYTES", 100)
    _fast(lambda: load_study(path), r"has \d+ bytes; at most 100 are read")


def test_a_dotted_key_of_20000_parts_counts_as_nesting():
    text = BASE + ".".join(["k"] * 20_000) + " = 1\n"
    _fast(lambda: parse_study(text), "nested 20000 deep .*; at most 50 levels", seconds=2.0)


@pytest.mark.parametrize("text,depth", [("a = 1.5\nb = [1.25, 2.5, 3.75, 4.5]\n", 1), ("a.b.c = 1\n", 3),
                                        ("[a.b]\nc = 1\n", 3), ('"x.y".z = 1\n', 2), ("t = {a.b = 1.5}\n", 3)])
def test_nesting_counts_key_dots_not_decimal_points(text, depth):
    assert limits.nesting_depth(text) == depth


def test_twenty_thousand_cases_are_refused_before_validating_them():
    text = BASE + "".join(f'[[case]]\nname = "c{i}"\n' for i in range(20_000))
    _fast(lambda: parse_study(text), r"case: 20000 \[\[case\]\] tables; at most 1000")


def test_fragility_thresholds_are_bounded():
    text = BASE + "[fragility]\nthresholds = [" + ", ".join(f"{1e-4 * (i + 1):.4g}" for i in range(5000)) + "]\n"
    _fast(lambda: parse_study(text), "fragility.thresholds: 5000 thresholds; at most 100")
    ok = BASE + "[fragility]\nthresholds = [" + ", ".join(f"{1e-4 * (i + 1):.4g}" for i in range(100)) + "]\n"
    assert len(parse_study(ok).fragility.thresholds) == 100
