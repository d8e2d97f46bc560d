"""benchmarks/error_atlas.py --redo: the points to evaluate again although the resumed atlas holds them."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[3] / "benchmarks"))
import error_atlas  # noqa: E402


def test_redo_points_are_indices_and_ranges():
    assert error_atlas.parse_points("17,3, 40-42,3") == [3, 17, 40, 41, 42]
    assert error_atlas.parse_points("") == []
    for bad in ("a", "5-2", "1-", "-3", "1.5"):
        with pytest.raises(ValueError, match="--redo must be point indices"):
            error_atlas.parse_points(bad)


@pytest.mark.parametrize("redo, message", [("x", "--redo must be point indices or ranges"),
                                            ("3,1024", "--redo must be point indices in 0..1023")])
def test_a_bad_redo_is_one_line_and_exit_2_before_any_work(redo, message, tmp_path, capsys):
    work = tmp_path / "work"
    assert error_atlas.main(["--redo", redo, "--work", str(work), "--out", str(tmp_path / "a.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and message in err
    assert not work.exists() and not (tmp_path / "a.nc").exists()
