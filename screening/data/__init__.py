"""Package data: the trust-rule calibration (``trust_calibration.nc``, made by benchmarks/trust_calibration.py)."""

__all__ = []
