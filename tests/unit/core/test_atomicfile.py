"""Files written all or nothing, never through a planted link (screening.core.atomicfile)."""

import os

import pytest

from screening.core.atomicfile import atomic_open, atomic_path, create_new, open_nofollow, publish, temporary_beside


def test_a_failing_write_leaves_the_target_as_it_was_and_no_temporary(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_open(target) as fh:
        fh.write("half")
        raise RuntimeError("disk gone")
    assert target.read_text() == "old" and sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


@pytest.mark.parametrize("writer, mode", [(atomic_open, "w"), (lambda path, mode: create_new(path), "wb")])
def test_a_write_replaces_a_link_at_the_target_instead_of_following_it(tmp_path, writer, mode):
    elsewhere = tmp_path / "elsewhere.txt"
    elsewhere.write_text("keep me")
    target = tmp_path / "out.txt"
    target.symlink_to(elsewhere)
    with writer(target, mode) as fh:
        fh.write("new" if mode == "w" else b"new")
    assert not target.is_symlink() and target.read_text() == "new" and elsewhere.read_text() == "keep me"


def test_the_temporary_is_hidden_beside_the_target_and_published_with_the_umask(tmp_path):
    target = tmp_path / "result.nc"
    tmp = temporary_beside(target, ".nc")
    assert tmp.parent == tmp_path and tmp.name.startswith(".result.nc.") and tmp.name.endswith(".tmp.nc")
    mask = os.umask(0o027)
    try:
        publish(tmp, target)
    finally:
        os.umask(mask)
    assert not tmp.exists() and (target.stat().st_mode & 0o777) == 0o640


def test_atomic_path_removes_its_temporary_when_the_block_raises(tmp_path):
    with pytest.raises(KeyError), atomic_path(tmp_path / "x.bin") as tmp:
        tmp.write_bytes(b"1")
        raise KeyError
    assert list(tmp_path.iterdir()) == []


def test_open_nofollow_refuses_a_link_and_anything_but_a_regular_file(tmp_path):
    real = tmp_path / "real"
    real.write_text("x")
    (tmp_path / "link").symlink_to(real)
    with pytest.raises(OSError):
        open_nofollow(tmp_path / "link", os.O_RDONLY)
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(OSError, match="not a regular file"):
        open_nofollow(tmp_path / "fifo", os.O_RDONLY)          # refused at once, never blocks
    os.close(open_nofollow(real, os.O_RDONLY))
