"""What a result format does: :class:`ResultFormat`, implemented by :class:`~screening.io.writer.NetcdfFormat`
(netCDF4, written by the client) and :class:`~screening.io.zarrfile.ZarrFormat` (zarr, written in place by the
workers)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

__all__ = []


@runtime_checkable
class ResultFormat(Protocol):
    """A result being written: its layout created (``dimension``, ``define``), regions written and read by
    name (``region``: an index tuple, or ``Ellipsis``), attributes set; ``commit`` makes what was defined
    and written durable, ``finish`` closes it.  A result is built under a temporary name and renamed into
    place by its caller once finished: all or nothing."""

    complevel: int

    def dimension(self, name, size): ...

    def dimension_size(self, name): ...

    def define(self, name, dtype, dims, attrs, fill=False, values=None, compress=False, shuffle=None,
               chunks=None): ...

    def has(self, name): ...

    def write(self, name, region, values): ...

    def read(self, name, region=Ellipsis): ...

    def dims(self, name): ...

    def attrs(self, name): ...

    def set_attrs(self, attrs): ...

    def commit(self): ...

    def finish(self): ...
