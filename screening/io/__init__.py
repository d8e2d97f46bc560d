"""The result files: their layout, the netCDF and zarr formats, the resume record, CDO export, checked reading."""

__all__ = []
