"""The files of a zarr result (screening.io._zarr_store): sizes and checksums (against hashlib), the completion
mark listing every file, what in a folder screening did not write, the removal of a finished store that keeps
anything else, and attributes as netCDF can store them."""

import hashlib
import json
import os

import numpy as np
import pytest

from screening.io import _zarr_store as zs
from screening.io.errors import SweepError


def _store(root):
    (root / "var" / "c").mkdir(parents=True)
    (root / "zarr.json").write_text('{"zarr_format": 3}')
    (root / "var" / "c" / "0").write_bytes(b"\x00" * 1000 + b"chunk")
    return root


def test_a_file_check_is_its_size_and_blake2b_digest_and_nothing_for_a_link(tmp_path):
    path = tmp_path / "f"
    path.write_bytes(b"abc" * 1000)
    assert zs.file_check(path) == [3000, hashlib.blake2b(b"abc" * 1000, digest_size=16).hexdigest()]
    os.symlink(path, tmp_path / "link")
    assert zs.file_check(tmp_path / "link") == [-1, ""] == zs.file_check(tmp_path / "missing")


def test_the_completion_mark_lists_every_file_with_its_check(tmp_path):
    root = _store(tmp_path / "r.zarr")
    zs.write_completion_mark(root)
    mark = json.loads((root / zs.COMPLETION_MARK).read_text())
    assert mark["files"] == {p: zs.file_check(root / p) for p in ("var/c/0", "zarr.json")}
    assert zs.read_completion_mark(root) == mark["files"]
    assert zs.foreign_files(root) == []
    (root / "notes.txt").write_text("mine")
    assert zs.foreign_files(root) == ["notes.txt"]


def test_a_store_without_its_mark_is_all_foreign_and_a_link_refuses_the_mark(tmp_path):
    root = _store(tmp_path / "r.zarr")
    assert zs.read_completion_mark(root) is None
    assert zs.foreign_files(root) == ["var/c/0", "zarr.json"]
    os.symlink(tmp_path, root / "elsewhere")
    with pytest.raises(OSError, match="holds elsewhere, which is not a regular file"):
        zs.write_completion_mark(root)


def test_removing_a_finished_store_keeps_what_screening_did_not_write(tmp_path):
    root = _store(tmp_path / "r.zarr")
    zs.write_completion_mark(root)
    (root / "var" / "mine.txt").write_text("keep")
    assert zs.remove_store(root) is False
    assert sorted(p.relative_to(root).as_posix() for p in root.rglob("*")) == ["var", "var/mine.txt"]
    (root / "var" / "mine.txt").unlink()
    zs.write_completion_mark(root)
    assert zs.remove_store(root) is True and not root.exists()


def test_attributes_become_what_netcdf_can_store():
    out = zs.netcdf_attributes({"a": None, "b": True, "c": [1, 2], "d": ["x", "y"], "e": {"k": 1}, "f": [1, "x"],
                                "g": "text", "flag_values": [0, 1, 2]}, dtype=np.int8)
    assert "a" not in out and out["b"] == 1 and out["g"] == "text"
    assert out["c"].tolist() == [1, 2] and out["d"].tolist() == ["x", "y"]
    assert json.loads(out["e"]) == {"k": 1} and json.loads(out["f"]) == [1, "x"]
    assert out["flag_values"].dtype == np.int8 and out["flag_values"].tolist() == [0, 1, 2]
    with pytest.raises(SweepError, match="the flag_values of v are not a flat list of numbers"):
        zs.netcdf_attributes({"flag_values": [[0], [1]]}, dtype=np.int8, where="v")
