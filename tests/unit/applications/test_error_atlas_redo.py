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


def test_refit_model_replaces_the_stored_fit_and_keeps_everything_else(tmp_path, capsys):
    """--refit-model on an assembled atlas (the shipped one's first 96 points): the em_* variables are those
    fitted on its points, every other variable and attribute is as it was; without a file, one line, exit 2."""
    from importlib import resources

    import numpy as np
    import xarray as xr

    from screening.analysis import error_model as em

    with resources.as_file(resources.files("screening.data") / em.ATLAS_FILE) as path:
        small = xr.load_dataset(path).isel(point=slice(0, 96))
    out = tmp_path / "atlas.nc"
    small.drop_vars(list(em.STORED_FIT)).to_netcdf(out)            # an atlas without a stored fit
    assert error_atlas.main(["--refit-model", "--out", str(out)]) == 0
    with xr.open_dataset(out) as got:
        got = got.load()
    expected = em.fitted_variables(small)
    for name, value in expected.items():
        np.testing.assert_array_equal(got[name].values, value.values, err_msg=name)
    kept = small.drop_vars(list(em.STORED_FIT))
    xr.testing.assert_identical(got.drop_vars(list(em.STORED_FIT)).drop_attrs(deep=False), kept.drop_attrs(deep=False))
    assert {k: v for k, v in got.attrs.items() if k != "error_model_command"} == \
        {k: v for k, v in kept.attrs.items() if k != "error_model_command"}
    assert got.attrs["error_model_command"].endswith("--refit-model --out " + str(out))
    capsys.readouterr()
    assert error_atlas.main(["--refit-model", "--out", str(tmp_path / "none.nc")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--out must be an assembled atlas" in err
