"""The result file writer (screening.io.writer) without dask: every attribute comes from the schema."""

import netCDF4
import numpy as np
import pytest

from helpers import CASES, GRID, failed_result_file as write

from screening import __version__
from screening.solvers.schema import SWEEP, TIME, attributes, global_attributes, grid_coordinate_attributes
from screening.core.status import PointStatus, SpotStatus
from screening.io.errors import SweepError
from screening.sweep.study import parse_study
from screening.io.writer import CACHED_CHUNKS, ResultFile, point_chunks, check_output_path, result_attributes
from screening.sweep.run import relative_peak_error

SPOTS = '[mcs]\npoints = [{case = "soft_kt", S0 = 1e-4}, {case = "hard_white", S0 = 2.4e-3}]\nsamples = 3\n'
K_SWEPT = GRID.replace("k = 2.89e7", "k = [2.0e7, 2.89e7]")


@pytest.mark.parametrize("text", [CASES + SPOTS, K_SWEPT], ids=["cases_and_spots", "k_swept"])
def test_every_attribute_of_every_variable_comes_from_the_schema(tmp_path, text):
    study = parse_study(text, name="w", source="w.toml")
    with netCDF4.Dataset(write(study, tmp_path / "w.nc")) as nc:
        assert set(nc.variables) >= {"status", "theta_ul", "slenderness", "var_theta"}
        for name, var in nc.variables.items():
            declared = (TIME if name == "t" else grid_coordinate_attributes(name) if var.dimensions == ("k",)
                        else attributes("k" if name == "k_value" else name, SWEEP))
            got = {k: var.getncattr(k) for k in var.ncattrs() if k not in ("coordinates", "_FillValue")}
            assert got.keys() == declared.keys(), name
            for key, value in declared.items():
                np.testing.assert_array_equal(got[key], value, err_msg=f"{name}:{key}")
        expected = global_attributes(__version__)
        assert {k: nc.getncattr(k) for k in expected} == expected
        assert nc.getncattr("study_file") == "w.toml" and nc.getncattr("title") == study.title


def test_failed_points_and_spots_carry_the_status_enums(tmp_path):
    study = parse_study(CASES + SPOTS)
    with netCDF4.Dataset(write(study, tmp_path / "f.nc")) as nc:
        nc.set_auto_mask(False)
        assert np.all(nc["status"][:] == PointStatus.task_failed)
        assert np.all(np.isnan(nc["theta_ul"][:])) and np.all(np.isnan(nc["slenderness"][:]))
        np.testing.assert_array_equal(nc["mcs_status"][:], [SpotStatus.task_failed] * 2)
        np.testing.assert_array_equal(nc["spot_case_name"][:], ["soft_kt", "hard_white"])


def test_relative_peak_error():
    assert relative_peak_error([0, 1, 2.2, 1], [0, 2.0, 1.0, np.nan]) == pytest.approx(0.1)
    assert np.isnan(relative_peak_error([1.0], [np.nan]))


def test_output_path_checks(tmp_path):
    assert check_output_path(tmp_path / "r.nc") == tmp_path / "r.nc"
    with pytest.raises(SweepError, match="is a directory"):
        check_output_path(tmp_path)
    with pytest.raises(SweepError, match="output folder .* does not exist"):
        check_output_path(tmp_path / "missing" / "r.nc")


@pytest.mark.parametrize("shape, target, expected", [
    ((1000, 1000), 2**14, (16, 1000)),       # whole rows first
    ((3, 50_000), 2**14, (1, 16384)),        # part of a long row
    ((4, 5, 6), 2**14, (4, 5, 6)),           # a small grid is one chunk
    ((7,), 2, (2,)),
])
def test_point_chunks_are_c_order_runs_of_about_the_target(shape, target, expected):
    chunks = point_chunks(shape, target)
    assert chunks == expected
    assert np.prod(chunks) <= max(target, shape[-1])


def test_per_point_variables_have_bounded_chunks_and_chunk_cache(tmp_path):
    """The netCDF default chunk cache (64 MiB per variable) would hold the whole grid's summaries
    in client memory: every gridded variable gets a cache of a few of its own chunks."""
    study = parse_study(CASES, name="w", source="w.toml")
    path = write(study, tmp_path / "w.nc")
    result = ResultFile(tmp_path / "x.nc", study, result_attributes(study, "2024-01-01T00:00:00+00:00", 4))
    try:
        for name in ("t_stop", "status", "n_steps", "var_theta"):
            v = result.nc[name]
            size = np.prod(v.chunking()) * v.dtype.itemsize
            assert v.get_var_chunk_cache()[0] == CACHED_CHUNKS * size
    finally:
        result.close()
    with netCDF4.Dataset(path) as nc:
        assert nc["t_stop"].chunking() == list(point_chunks(study.shape))


def test_the_spot_comparison_names_have_one_home():
    """The linearization histories a spot check is compared against are execution.SPOT_LINEAR: the spot
    checks' writer uses that name and spells no copy of the tuple."""
    import ast
    import inspect

    from screening.sweep import execution, run

    tree = ast.parse(inspect.getsource(run))
    literals = {tuple(e.value for e in node.elts) for node in ast.walk(tree)
                if isinstance(node, ast.Tuple) and node.elts and all(isinstance(e, ast.Constant) for e in node.elts)}
    assert tuple(execution.SPOT_LINEAR) not in literals
    assert run.SPOT_LINEAR is execution.SPOT_LINEAR
