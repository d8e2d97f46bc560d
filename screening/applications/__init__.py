"""Applications built on the solvers and the sweep: the trade study, the cloud and record studies, fragility over an
intensity measure, the excitation fit, the error atlas."""

__all__ = []
