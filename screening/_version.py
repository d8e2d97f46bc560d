"""The package's version, read by ``screening.__version__`` and by the schema's history attribute."""

__version__ = "0.1.0"
