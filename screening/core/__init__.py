"""The foundations and the model: input checks, registries, status codes, limits, progress, atomic files, records,
the block and its bed, contact laws, physics, excitations and condensations.  Imports no other folder."""

__all__ = []
