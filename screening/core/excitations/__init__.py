"""Ground-motion excitations behind one interface (:class:`Excitation`: a shaping filter as
state-space matrices and its PSD) and a registry keyed by ``kind``."""

from screening.core.excitations.base import Excitation, Filter, Parameter, stationary_covariance, transfer_psd
from screening.core.excitations.registry import build, get, names, parameters, register, unregister
from screening.core.excitations.white import WhiteNoise
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.clough_penzien import CloughPenzien

__all__ = ["Excitation", "Filter", "Parameter", "stationary_covariance", "transfer_psd", "build", "get", "names",
           "parameters", "register", "unregister", "WhiteNoise", "KanaiTajimi", "CloughPenzien"]
