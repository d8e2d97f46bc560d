"""``linearize``: the stochastic-linearization response as a labelled dataset, for one point or a grid.

Any numeric field of the model objects may be a scalar, a 1-d numpy array (swept along a
dimension named after the parameter, with its values as coordinate) or an
:class:`xarray.DataArray` (its own dimensions and coordinates).  The fields are broadcast by
dimension name, the batched solver (:func:`screening.solvers.moments.solve_moments`) runs once on
plain numpy arrays, and the result is labelled again (:func:`screening.solvers.datasets.linearization_dataset`).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from screening.core import condensation as condensations
from screening.analysis.trust import add_trust
from screening.core.condensation.base import Condensation
from screening.core.model.points import numeric_fields
from screening.solvers.datasets import linearization_dataset, model_fields, model_labels
from screening.kernels.moment_kernels import uplift_occupancy
from screening.solvers.moments import DEFAULT_RTOL, solve_moments
from screening.solvers.timegrid import output_times

__all__ = ["linearize"]

METHOD = "stochastic linearization + Lyapunov moment equations"


# ----------------------------------------------------------------------------- labelled inputs
def _label(name, value):
    """``value`` as a float DataArray: 0-d, on the dimension ``name`` (1-d array) or as given (DataArray)."""
    if isinstance(value, xr.DataArray):
        if "t" in value.dims:
            raise ValueError(f"parameter '{name}': the dimension name 't' is reserved for time")
        return value.astype(float)
    arr = np.asarray(value, dtype=float)
    if arr.ndim == 0:
        return xr.DataArray(arr)
    if arr.ndim == 1:
        return xr.DataArray(arr, dims=(name,), coords={name: arr})
    raise ValueError(f"parameter '{name}' must be a scalar, a 1-d array (swept along a dimension named '{name}') "
                     f"or an xarray.DataArray (got an array of shape {arr.shape})")


def _same(a, b):
    return np.shape(a) == np.shape(b) and np.array_equal(np.asarray(a, dtype=float), np.asarray(b, dtype=float))


def _labelled_fields(block, foundation, excitation):
    """The model parameters by name as DataArrays aligned on their dimensions (not yet broadcast).

    A default ``I_cm`` (the block's uniform-rectangle value of its ``m``, ``b``, ``h``) is derived
    again from the labelled ``m``, ``b``, ``h``, so that it varies along their dimensions.
    Raises ``ValueError`` for arrays of more than one dimension, coordinates that disagree along a
    shared dimension, and a dimension named after a parameter that does not vary along it.
    """
    raw = model_fields(block, foundation, excitation)
    fields = {name: _label(name, value) for name, value in raw.items()}
    try:
        fields = dict(zip(fields, xr.align(*fields.values(), join="exact")))
    except ValueError as exc:
        raise ValueError("model parameters given as DataArrays must have the same coordinate values along a "
                         f"shared dimension ({' '.join(str(exc).split())})") from None
    geometry = {n: raw[n] for n in ("m", "b", "h", "g")}
    if _same(raw["I_cm"], type(block)(**geometry).I_cm):
        fields["I_cm"] = type(block)(**{n: fields[n] for n in geometry}).I_cm.astype(float)
    for name, field in fields.items():
        for dim in field.dims:
            own = fields.get(dim)
            if own is not None and not (own.dims == (dim,) and (dim not in own.coords or _same(own[dim], own))):
                raise ValueError(f"parameter '{name}' varies along a dimension named '{dim}', which is a parameter: "
                                 f"'{dim}' must then be a 1-d array on it with its values as coordinate")
    return fields


def _broadcast_fields(fields):
    """``(dims, arrays)``: the fields broadcast by dimension name, as numpy arrays on ``dims``."""
    arrays = xr.broadcast(*fields.values())
    dims = arrays[0].dims if arrays else ()
    return dims, {name: np.array(a.transpose(*dims).values, dtype=float) for name, a in zip(fields, arrays)}


def _with_fields(obj, arrays):
    """A copy of a model object whose fields named in ``arrays`` are replaced (the envelope's too)."""
    names = {f.name for f in dataclasses.fields(obj)}
    changes = {name: value for name, value in arrays.items() if name in names and name != "envelope"}
    if "envelope" in names:
        changes["envelope"] = _with_fields(obj.envelope, arrays)
    return dataclasses.replace(obj, **changes)


def _on_own_dims(function, fields, names, block, foundation):
    """``function(block, foundation)`` on the grid of the parameters ``names`` only, as a DataArray."""
    dims, arrays = _broadcast_fields({name: fields[name] for name in names})
    value = function(_with_fields(block, arrays), _with_fields(foundation, arrays))
    return xr.DataArray(np.broadcast_to(value, arrays[names[0]].shape), dims=dims)


# ----------------------------------------------------------------------------- entry point
def linearize(block, foundation, excitation, t_end=20.0, dt=0.05, rtol=DEFAULT_RTOL,
              condensation=condensations.DEFAULT_CONDENSATION,
              trust=True):
    """Time-varying second-order rocking statistics by stochastic linearization (sections 2.4–2.6).

    Parameters
    ----------
    block : screening.core.model.Block
        The rigid block (``m`` [kg], ``b``, ``h`` [m], ...).  Each numeric field of the three model
        objects may be a scalar, a 1-d numpy array (a dimension named after the parameter, with the
        values as coordinate) or an :class:`xarray.DataArray` (its own dimensions and coordinates);
        the fields are broadcast by dimension name and all points are integrated in one batched call.
    foundation : screening.core.model.Foundation
        The bed (``k`` [N m-2], ``eps`` [m-2], its damping), fields as for ``block``.
    excitation : screening.core.excitations.Excitation
        The input (``S0`` [m2 s-3], its parameters and envelope), fields as for ``block``.
    t_end : float, optional
        Record length [s] (default 20).
    dt : float, optional
        Output step [s] (default 0.05; the solver is adaptive and finer).
    rtol : float, optional
        Solver relative tolerance [1].
    condensation : str or screening.core.condensation.Condensation, optional
        A registered condensation (:func:`screening.core.condensation.get`): ``"virtual_work"`` (heavy
        uplift, docs/models.md; the default, :data:`screening.core.condensation.DEFAULT_CONDENSATION`),
        ``"paper"`` (eqs. (17)-(25) in [1]: pin it to reproduce the paper) or ``"cubic"`` (static
        balance with the cubic term); recorded in ``attrs["condensation"]``.
    trust : bool, optional
        Add ``sl_trust`` and the predicted error band ``sl_error_low``/``sl_error_high`` of the
        linearization against the coupled model (:func:`screening.analysis.trust.add_trust`; default).

    Returns
    -------
    xarray.Dataset on the broadcast dimensions and ``t`` [s] with ``var_theta`` [rad2],
    ``var_theta_dot`` [rad2 s-2], ``cov_theta_theta_dot`` [rad2 s-1], ``c_eq`` [N m s rad-1],
    ``k_eq`` [N m rad-1], ``p_uplift`` [1] (eq. 58), the per-point summaries ``peak_var_theta``,
    ``t_peak_var_theta``, ``peak_p_uplift``, ``min_k_eq``, ``status`` (CF flag variable),
    ``t_stop``, ``n_steps``, and ``theta_ul`` [rad] (of the condensation) and ``slenderness``
    [rad] on the dimensions of their parameters.  The parameters are coordinates (scalar when
    fixed); contact law, excitation, envelope and condensation are attributes.  Values after a
    point stopped (status != 0) are NaN.  Scalar inputs give 0-d summaries.

    A condensation with a capacity angle (``"cubic"`` on softening beds: no quasi-static
    equilibrium beyond it; ``inf`` otherwise) adds ``theta_capacity`` [rad] and
    ``peak_p_beyond_capacity``, the Gaussian probability ``P(|theta| > theta_capacity)`` at the
    peak ``var_theta``: attributes for one point, variables for a grid.

    Notes
    -----
    The condensed equation ``m_sdof theta'' + C(theta) theta' + K(theta) theta = m h a_g`` (eq. (22) in
    [1]) is replaced by its equivalent linear system with ``c_eq(t)``, ``k_eq(t)`` (eq. (26)), the
    Gaussian expectations of eq. (31) at the current moments, and the covariance follows the Lyapunov
    equation (eq. (45); eq. (51) for a filtered input), integrated by
    :func:`screening.solvers.moments.solve_moments`; ``p_uplift`` is eq. (58).

    References
    ----------
    [1] [mitseas2026].

    Examples
    --------
    >>> from screening import Block, Foundation, WhiteNoise, linearize
    >>> ds = linearize(Block(m=8.67, b=0.035, h=0.21), Foundation(k=2.89e7, lam=8.95e8),
    ...                WhiteNoise(np.array([1e-5, 1e-4])), t_end=10.0, dt=0.5, trust=False, condensation="paper")
    >>> ds["peak_var_theta"].dims, [f"{v:.3e}" for v in ds["peak_var_theta"].values]
    (('S0',), ['1.160e-07', '1.372e-06'])
    """
    cond = condensations.get(condensation)
    t = output_times(t_end, dt)
    fields = _labelled_fields(block, foundation, excitation)
    dims, arrays = _broadcast_fields(fields)
    point_block, point_foundation = _with_fields(block, arrays), _with_fields(foundation, arrays)
    structure = list(numeric_fields(block, foundation))
    derived = {"theta_ul": _on_own_dims(cond.uplift_threshold, fields, structure, block, foundation),
               "slenderness": _on_own_dims(lambda blk, _: blk.slenderness, fields, ["b", "h"], block, foundation)}
    res = solve_moments(point_block, point_foundation, _with_fields(excitation, arrays), t, rtol=rtol,
                        condensation=cond)
    attrs = {**model_labels(foundation, excitation), "condensation": cond.name, "condensation_note": cond.description,
             "method": METHOD, "rtol": float(rtol)}
    if type(cond).capacity_angle is not Condensation.capacity_angle:
        capacity = _on_own_dims(cond.capacity_angle, fields, structure, block, foundation)
        peak = xr.DataArray(res["peak_var_theta"], dims=dims)
        with np.errstate(invalid="ignore"):         # eq. (58) with the capacity angle in place of theta_ul
            beyond = xr.where(np.isfinite(capacity), xr.apply_ufunc(uplift_occupancy, capacity, peak), 0.0)
        if dims:
            derived.update(theta_capacity=capacity, peak_p_beyond_capacity=beyond)
        else:
            attrs.update(theta_capacity=float(capacity), peak_p_beyond_capacity=float(beyond))
    ds = linearization_dataset(res, t, dims, fields, derived, attrs)
    return add_trust(ds) if trust else ds
