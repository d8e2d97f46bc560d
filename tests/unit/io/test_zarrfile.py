"""The zarr form of a result (screening.io.zarrfile) without dask: chunks, layout, markers, export."""

import math

import numpy as np
import pytest
import xarray as xr

from helpers import CASES, GRID, failed_result_file

from screening.io.layout import hyperslabs
from screening.sweep.grid import plan_batches
from screening.sweep.study import parse_study
from screening.io.zarrfile import point_chunks, zarr_batch_size

zarr = pytest.importorskip("zarr")

SPOTS = '[mcs]\npoints = [{case = "soft_kt", S0 = 1e-4}, {case = "hard_white", S0 = 2.4e-3}]\nsamples = 3\n'


def _chunk_owners(shape, n_lead, batch_size):
    """Batch index of every grid point, and the chunk grid index of every point."""
    chunks = point_chunks(shape, n_lead, batch_size)
    per_case = math.prod(shape[n_lead:])
    owner = np.empty(math.prod(shape), dtype=int)
    index = 0
    for case in range(math.prod(shape[:n_lead])):
        for lo in range(0, per_case, batch_size):
            hi = min(lo + batch_size, per_case)
            owner[case * per_case + lo:case * per_case + hi] = index
            index += 1
    grid = np.indices(shape).reshape(len(shape), -1)
    chunk_of = tuple(grid[d] // chunks[d] for d in range(len(shape)))
    return chunks, owner, chunk_of


@pytest.mark.parametrize("shape, n_lead, batch", [
    ((7, 13, 11), 0, 495), ((7, 13, 11), 0, 500), ((7, 13, 11), 0, 143), ((1000,), 0, 300), ((1003,), 0, 500),
    ((2, 10, 12), 1, 30), ((3, 5), 1, 7), ((4, 5, 6), 0, 1000), ((6, 4, 5), 0, 10), ((2,), 1, 1)])
def test_every_chunk_lies_in_one_batch(shape, n_lead, batch):
    chunks, owner, chunk_of = _chunk_owners(shape, n_lead, batch)
    seen = {}
    for point, key in enumerate(zip(*chunk_of)):
        assert seen.setdefault(key, owner[point]) == owner[point], (key, chunks)


def test_chunks_are_as_large_as_the_batches_allow():
    assert point_chunks((1000,), 0, 300) == (300,)             # first dimension: a short last chunk is fine
    assert point_chunks((7, 13, 11), 0, 429) == (3, 13, 11)
    assert point_chunks((4, 5, 6), 0, 1000) == (4, 5, 6)       # one batch: one chunk
    assert point_chunks((2, 10, 12), 1, 30) == (1, 1, 6)
    assert zarr_batch_size((7, 13, 11), 0, 495) == 429         # three whole 13 x 11 planes
    assert zarr_batch_size((100_000,), 0, 500) == 500
    assert zarr_batch_size((2, 10, 12), 1, 500) == 500


@pytest.mark.parametrize("text", [CASES + SPOTS, GRID.replace("k = 2.89e7", "k = [2.0e7, 2.89e7]")],
                         ids=["cases_and_spots", "k_swept"])
def test_the_zarr_form_opens_to_the_netcdf_form(tmp_path, text):
    study = parse_study(text, name="w", source="w.toml")
    nc = failed_result_file(study, tmp_path / "w.nc")
    store = failed_result_file(study, tmp_path / "w.zarr", zarr_batch_size=4)
    with xr.open_dataset(nc) as a, xr.open_zarr(store) as b:
        xr.testing.assert_identical(a.load(), b.load())


def test_a_region_target_marks_its_batch_with_the_chunk_files(tmp_path):
    from screening.sweep._submit import write_region
    from screening.sweep.execution import failed_result
    from screening.io.store import PartialStore
    from screening.io.writer import ResultFile, region_variables, result_attributes
    from screening.io.zarrfile import ZarrFormat

    study = parse_study(GRID)
    store = PartialStore(tmp_path / "m.zarr")
    store.open(study.key, {"batch_size": 5}, print)
    try:
        ResultFile(store.zarr_building, study, result_attributes(study, "2024", 5), zarr_batch_size=5).close()
        target = store.region_target(study.shape, study.output.stored, region_variables(study))
        batches = plan_batches(study, 5)
        fmt = ZarrFormat(target.store, "r+")                 # what a worker does (_submit.solve_and_store_batch)
        write_region(fmt, target.shape, target.histories, batches[1], failed_result(5, study.times.size))
        target.mark_done(batches[1], fmt.chunk_files(target.variables, [(slice(1, 2), slice(0, 5))]))
        assert store.marker_ok(batches[1]) and not store.marker_ok(batches[0])
        assert [slab for slab, _, _ in hyperslabs(batches[1].lo, batches[1].hi, study.shape)] == [
            (slice(1, 2), slice(0, 5))]
        chunk = store.zarr_building / "var_theta" / "c" / "1" / "0" / "0"           # its chunk of var_theta
        chunk.write_bytes(chunk.read_bytes()[:-1])                                 # damaged
        assert not store.marker_ok(batches[1])
    finally:
        store.close()
