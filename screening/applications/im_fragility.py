"""Fragility over an engineering intensity measure, and its export (CSV, OpenQuake NRML).

:func:`fragility_over_im` fits ``P = Phi(ln(IM / median) / beta)`` to the exceedance probability along a
swept excitation dimension (usually ``S0``) over each point's intensity measure (``pga``, ``sa``, ``pgv``,
``avgsa``, ``rms``, ``arias`` or ``s0``).  It refuses a dimension along which the IM does not strictly
increase, and flags ``beta <= 0`` (not exported) and thresholds beyond the slenderness.
:func:`write_csv` and :func:`write_nrml` (NRML 0.5 continuous ``logncdf``: OpenQuake's mean and standard
deviation of the capacity, IMs in g, cm/s, m/s) export the fits: ``docs/fragility.md``.
"""

from __future__ import annotations

import csv
import json
import math
from xml.sax.saxutils import quoteattr

import numpy as np
import xarray as xr

from screening.analysis.fragility import add_fit, fragility_dataset, model_quantity, parameter
from screening.analysis.intensity import intensity_measures
from screening.core.atomicfile import atomic_open
from screening.core.status import FitFlag

__all__ = []

#: ``--im`` names -> (variable, units, OpenQuake IMT or None, factor from the units to the OpenQuake units).
IMS = {
    "pga": ("pga_median", "m s-2", "PGA", 1.0 / 9.80665),
    "sa": ("sa_median", "m s-2", "SA", 1.0 / 9.80665),
    "pgv": ("pgv_median", "m s-1", "PGV", 100.0),
    "avgsa": ("avgsa_median", "m s-2", "AvgSA", 1.0 / 9.80665),
    "rms": ("rms_acceleration", "m s-2", None, None),
    "arias": ("arias_intensity", "m s-1", "IA", 1.0),
    "s0": ("S0", "m2 s-3", None, None),
}


def _im_values(ds, im, period, cutoff):
    if im == "s0":
        return parameter(ds, "S0"), None
    if im in ("sa", "avgsa") and period is None:
        raise ValueError(f"--im {im} needs the oscillator period (--period SECONDS)")
    measures = intensity_measures(ds, period=period if im in ("sa", "avgsa") else None, cutoff=cutoff)
    return measures[IMS[im][0]], measures


def default_dim(grid):
    """The swept intensity a fragility is drawn along by default.

    Returns: ``S0`` [m2 s-3] or ``pga`` [m s-2], whichever the grid sweeps (``None`` if neither).
    """
    return next((d for d in ("S0", "pga") if d in grid), None)


def fragility_over_im(ds, threshold, im="pga", dim=None, relative_to=None, method="vanmarcke", period=None,
                      cutoff=None, limit_state="exceed"):
    """Exceedance probability along ``dim`` fitted over the intensity measure ``im``.

    The :func:`~screening.analysis.fragility.fragility_dataset` of the result (``p_exceed``, best
    estimates and Monte Carlo spot values where the result has them) with the IM (``pga_median``, ...)
    over the dataset's dimensions and the fit over the IM.  ``limit_state="overturn"``: the probability
    of overturning instead (:func:`screening.analysis.probabilities.overturning_probability`;
    ``threshold`` and ``relative_to`` are not used, ``threshold_rad`` is ``atan(b/h)``), stored as
    ``p_exceed`` with the attribute ``limit_state`` and exported with that limit state.

    Parameters
    ----------
    ds : xarray.Dataset
        A linearization, sweep or Monte Carlo result.
    threshold : float
        The threshold, [rad] or a fraction [1] (``relative_to``).
    im : str
        A key of :data:`IMS` (``pga`` [m s-2], ``sa``, ``pgv`` [m s-1], ``avgsa``, ``rms``, ``arias``, ``s0``).
    dim : str, optional
        The swept intensity dimension (default :func:`default_dim`).
    relative_to : {None, "slenderness", "theta_ul"}
        What ``threshold`` is a fraction of.
    method : {"vanmarcke", "poisson"}
        The up-crossing approximation.
    period : float, optional
        Oscillator period [s] of ``sa`` and ``avgsa``.
    cutoff : float, optional
        Band limit [rad/s] of the random-vibration intensity measures.
    limit_state : {"exceed", "overturn"}
        :data:`LIMIT_STATES`.

    Returns
    -------
    fragility : xarray.Dataset
        With ``fit_median`` [IM units] (``attrs["intensity"]``), ``beta`` [1], ``fit_flag``
        (:class:`~screening.core.status.FitFlag`) and ``fit_n_unvouched`` over the other dimensions.
    warnings : list of str
        Fits with ``beta <= 0``, thresholds beyond the slenderness angle, unreliable points left out.

    Raises
    ------
    ValueError
        For an unknown ``im``, a ``dim`` that is not swept or not an intensity dimension, or an IM
        that is not strictly increasing along ``dim``.

    Notes
    -----
    ``P(IM) = Phi(ln(IM / median) / beta)`` [baker2015].
    """
    if im not in IMS:
        raise ValueError(f"--im must be one of {', '.join(IMS)} (got {im!r})")
    grid = list(ds["status"].dims) if "status" in ds else [d for d in ds["var_theta"].dims if d != "t"]
    dim = dim if dim is not None else default_dim(grid)
    if dim is None or dim not in grid:
        raise ValueError(f"--dim {dim!r} is not a swept dimension (swept: {', '.join(grid) or 'none'})")
    if ds.sizes[dim] < 2:
        raise ValueError(f"--dim {dim!r} has one value: nothing to fit")
    values, _ = _im_values(ds, im, period, cutoff)
    name = IMS[im][0]
    if dim not in values.dims:
        raise ValueError(f"--dim {dim!r} is not an intensity dimension: {name} does not vary along it")
    step = values.diff(dim)
    if bool((step == 0).all()):
        raise ValueError(f"--dim {dim!r} is not an intensity dimension: {name} does not vary along it")
    if not bool((step > 0).all()):
        raise ValueError(f"{name} is not strictly increasing along --dim {dim!r}: a lognormal fit over it "
                         f"has no meaning")
    if limit_state not in LIMIT_STATES:
        raise ValueError(f"--limit-state must be one of {', '.join(LIMIT_STATES)} (got {limit_state!r})")
    warnings = []
    if limit_state == "overturn":
        from screening.analysis.probabilities import overturning_probability

        p, note = overturning_probability(ds, method)
        warnings += [f"overturning: {note}"] if note else []
        frag = xr.Dataset({"p_exceed": p.rename("p_exceed").assign_attrs(
                               long_name="probability that the block overturns during the record", units="1"),
                           "threshold_rad": model_quantity(ds, "slenderness"),
                           **({"p_exceed_se": ds["p_overturn_se"].where(np.isfinite(p))}
                              if "p_overturn_se" in ds.variables and "p_overturn" in ds.variables else {})},
                          attrs={"threshold": 1.0, "relative_to": "slenderness",
                                 "method": p.attrs.get("method", method)})
    else:
        frag = fragility_dataset(ds, threshold, relative_to, method, dim)
    units = IMS[im][1]
    values = values.drop_vars([c for c in values.coords if c not in values.dims]).assign_attrs(units=units)
    out = add_fit(frag.assign({name: values}), ds, values, dim)
    out["fit_median"].attrs.update(units=units, intensity=name)
    if "fit_median_se" in out:
        out["fit_median_se"].attrs.update(units=units)
    if period is not None and im in ("sa", "avgsa"):
        out[name].attrs.update(period=float(period), damping_ratio=0.05)
    out.attrs.update(intensity_measure=im, intensity_variable=name, intensity_dim=dim, limit_state=limit_state,
                     title="Probability that |theta| exceeds a rotation, fitted over an intensity measure"
                     if limit_state == "exceed" else "Probability of overturning, fitted over an intensity measure")
    n_neg = int((out["fit_flag"] == FitFlag.non_positive_beta).sum())
    if n_neg:
        warnings.append(f"{n_neg} fit(s) have beta <= 0 (probability falling with {name}); flagged in fit_flag "
                        "and left out of the exports")
    try:
        slender = model_quantity(ds, "slenderness")
        if limit_state == "exceed" and bool((out["threshold_rad"] >= slender).any()):
            warnings.append("the threshold is at or beyond the slenderness angle atan(b/h): the rigid block "
                            "overturns there; P(exceed) is then not a rocking measure")
    except KeyError:
        pass
    return out, warnings


#: Limit states of :func:`fragility_over_im`: ``exceed`` (``|theta|`` beyond a threshold, named by
#: :func:`limit_state_name`) or ``overturn`` (the block overturns; NRML limit state ``overturn``).
LIMIT_STATES = ("exceed", "overturn")

#: Variables of a fragility dataset that do not depend on the threshold (the intensities, the source).
THRESHOLD_FREE = ("best_method", *(v[0] for v in IMS.values()))


class NoExport(ValueError):
    """A file of a fragility's set that this fragility cannot fill (an IM OpenQuake does not know, nothing
    drawn): the set is written without it, with a warning."""


def _single_state(frag):
    """The exported name of the one limit state of a fragility without a ``limit_state`` dimension."""
    return "overturn" if frag.attrs.get("limit_state") == "overturn" else "theta_exceeds_threshold"


def limit_state_name(threshold, relative_to=None):
    """The name of the limit state "``|theta|`` exceeds ``threshold``".

    No spaces: NRML lists limit states separated by blanks.

    Units: ``threshold`` [rad].

    Returns: e.g. ``theta_0.1_slenderness``, ``theta_0.002_rad``.
    """
    return f"theta_{float(threshold):g}_{relative_to or 'rad'}"


def stack_limit_states(frags, thresholds, relative_to=None):
    """Fragility datasets of the same result at increasing thresholds as one dataset over ``limit_state``.

    The variables that depend on the threshold gain the dimension ``limit_state`` (names by
    :func:`limit_state_name`, coordinate ``threshold``); the others (intensities) stay as they are.
    One threshold: that dataset unchanged.

    Units: ``thresholds`` [rad].

    Returns: the stacked dataset.
    """
    if len(frags) == 1:
        return frags[0]
    names = [limit_state_name(t, relative_to) for t in thresholds]
    varying = [n for n in frags[0].data_vars if n not in THRESHOLD_FREE]
    out = xr.concat(frags, dim="limit_state", data_vars=varying, coords="minimal", compat="equals",
                    combine_attrs="override")
    out = out.assign_coords(limit_state=("limit_state", names),
                            threshold=("limit_state", np.asarray(thresholds, dtype=float),
                                       {"long_name": "threshold of the limit state (see relative_to)"}))
    out.attrs["threshold"] = ", ".join(f"{float(t):g}" for t in thresholds)
    return out


# ----------------------------------------------------------------------------- export
def _label_text(labels):
    return ", ".join(f"{d} = {v:g}" if isinstance(v, float) else f"{d} = {v}" for d, v in labels.items())


def curve_table(frag):
    """Every curve of a fragility dataset, fitted or not.

    Returns: ``labels`` (the other dimensions' values, ``limit_state`` included where the dataset has
    several), ``median`` [IM units], ``beta`` [1], ``flag`` (:class:`~screening.core.status.FitFlag`),
    ``reason`` (``""`` when fitted), ``n_unvouched`` (points of the curve whose linearized value is
    untrusted without a best estimate), ``degenerate`` (why a fit is degenerate, the dataset's
    ``fit_degenerate``, else ``""``), ``im_min``, ``im_max`` (the vouched range,
    :func:`~screening.analysis.fragility.vouched_range`; NaN where the dataset has none) and the rotation
    ``threshold_rad`` [rad] of the curve (its range ``"lo..hi"`` if it varies along the curve).
    """
    median, beta = frag["fit_median"], frag["beta"]
    flag = frag["fit_flag"]
    unvouched = frag["fit_n_unvouched"] if "fit_n_unvouched" in frag else xr.zeros_like(flag, dtype=np.int32)
    th = frag["threshold_rad"]
    lo = frag["fit_im_min"] if "fit_im_min" in frag else None
    hi = frag["fit_im_max"] if "fit_im_max" in frag else None
    dims = list(median.dims)
    rows = []
    for index in np.ndindex(*median.shape) if dims else [()]:
        sel = dict(zip(dims, index))
        labels = {d: frag[d].values[i].item() if d in frag.coords else i for d, i in sel.items()}
        code = FitFlag(int(flag[sel]))
        t = np.unique(np.asarray(th.isel({d: i for d, i in sel.items() if d in th.dims}).values, dtype=float))
        t = t[np.isfinite(t)]
        rows.append({"labels": labels, "median": float(median[sel]), "beta": float(beta[sel]), "flag": code,
                     "reason": "" if code == FitFlag.ok else code.meaning, "n_unvouched": int(unvouched[sel]),
                     "degenerate": str(frag.attrs.get("fit_degenerate", "")) if code == FitFlag.ok else "",
                     "im_min": float(lo[sel]) if lo is not None else math.nan,
                     "im_max": float(hi[sel]) if hi is not None else math.nan,
                     "threshold_rad": (f"{t[0]:.8g}" if t.size == 1 else f"{t.min():.8g}..{t.max():.8g}"
                                       if t.size else "")})
    return rows


def curve_count_text(frag):
    """How many curves were fitted, as the printed line says it.

    Returns: e.g. ``"3 of 5 curves fitted (2 without a fit: never_exceeded 2); 1 with points left out of the
    fit: ..."``.
    """
    rows = curve_table(frag)
    fitted = [r for r in rows if r["flag"] == FitFlag.ok]
    missing = [r["flag"] for r in rows if r["flag"] != FitFlag.ok]
    text = f"{len(fitted)} of {len(rows)} curve(s) fitted"
    if missing:
        counts = ", ".join(f"{f.name} {missing.count(f)}" for f in FitFlag if f in missing)
        text += f" ({len(missing)} without a fit: {counts})"
    shaky = sum(1 for r in rows if r["n_unvouched"])
    if shaky:
        text += (f"; {shaky} with points left out of the fit: nothing vouches for them (fit_n_unvouched "
                 f"{sum(r['n_unvouched'] for r in rows)}; Monte Carlo there would answer them: [accuracy], or a "
                 "larger budget_s)")
    return text


def _intensity(frag):
    name = frag["fit_median"].attrs.get("intensity", "intensity")
    period = frag[name].attrs.get("period", "") if name in frag else ""
    return name, frag["fit_median"].attrs.get("units", ""), period


def case_values(frag):
    """The name and values of each swept block/bed a curve belongs to, for the exports.

    Returns ``(shared, per_case)``: ``shared`` ``{name: (value, units)}`` of the scalar block/bed/excitation
    coordinates every curve shares; ``per_case`` ``{case index: {"name": case name, "values": {name: (value,
    units)}}}`` from the ``case_name`` coordinate and the coordinates over ``case`` (empty without a
    ``case`` dimension).
    """
    shared = {n: (float(frag[n]), frag[n].attrs.get("units", "")) for n in frag.coords
              if frag[n].ndim == 0 and frag[n].dtype.kind in "fi" and n != "threshold"}
    per_case = {}
    if "case" in frag.dims:
        names = frag["case_name"].values if "case_name" in frag.coords else frag["case"].values
        cols = [n for n, c in frag.coords.items() if c.dims == ("case",) and n not in ("case", "case_name")
                and c.dtype.kind in "fi"]
        for i, case in enumerate(frag["case"].values.tolist()):
            per_case[case] = {"name": str(names[i]),
                              "values": {n: (float(frag[n].values[i]), frag[n].attrs.get("units", "")) for n in cols}}
    return shared, per_case


def _values_text(values):
    return ", ".join(f"{n} = {v:g}{' ' + u if u else ''}" for n, (v, u) in values.items())


def export_problem(row):
    """Why a curve of :func:`curve_table` is not exported as a fragility others may use, or ``""``.

    Not exported: no fit (its ``fit_flag``, ``untrusted`` among them: too few vouched points once the
    unvouched ones are left out), a fit vouched at a single intensity, or whose records or stripes separate exceeding
    from not exceeding perfectly (the dataset's ``fit_degenerate``: ``degenerate``).

    Returns: the reason (``""``: exported).
    """
    if row["flag"] != FitFlag.ok:
        return f"no fit ({row['flag'].name}: {row['flag'].meaning})"
    if row.get("degenerate"):
        return f"degenerate: {row['degenerate']}"
    lo, hi = row.get("im_min", math.nan), row.get("im_max", math.nan)
    if math.isfinite(lo) and math.isfinite(hi) and not lo < hi:
        return "degenerate: vouched at a single intensity"
    return ""


def _curve_ids(frag, rows, pelicun=False):
    """``{labels without limit_state: id}`` of every swept block/bed, in the order of ``rows``.

    ``screening_case=<name>_<dim>=<value>...``; with ``pelicun`` no ``-`` (pelicun splits ids on it):
    a sign is written ``m`` (``-6e+05`` -> ``m6e05``) and a ``-`` in a case name ``_``; repeated ids get
    ``_2``, ``_3``...
    """
    _, per_case = case_values(frag)
    ids, seen = {}, set()
    for r in rows:
        labels = tuple((d, v) for d, v in r["labels"].items() if d != "limit_state")
        if labels in ids:
            continue
        parts = []
        for d, v in labels:
            if d == "case" and v in per_case:
                v = per_case[v]["name"]
            text = f"{v:g}" if isinstance(v, float) else str(v)
            if pelicun:
                text = text.replace("e+", "e").replace("e-", "em").replace("-", "m" if isinstance(v, float) else "_")
            parts.append(f"_{d}={text}")
        cid = "screening" + "".join(parts)
        if pelicun:
            cid = cid.replace("-", "_")
        base, n = cid, 1
        while cid in seen:
            n += 1
            cid = f"{base}_{n}"
        seen.add(cid)
        ids[labels] = cid
    return ids


def _by_curve(frag, rows, ids, states):
    out = {}
    for r in rows:
        labels = tuple((d, v) for d, v in r["labels"].items() if d != "limit_state")
        out.setdefault(ids[labels], {"labels": dict(labels)})[str(r["labels"].get("limit_state", states[0]))] = r
    return out


def _states(frag):
    return [str(v) for v in frag["limit_state"].values] if "limit_state" in frag["fit_median"].dims else [
        _single_state(frag)]


def fragility_intensity(frag):
    """The intensity a fragility dataset is fitted over: its variable's name, units and oscillator period.

    Returns ``(name, units, period)``: ``name`` the intensity variable (``pga_median``, ``pga``,
    ``stripe_pga``...); ``units`` its units (``m s-2``); ``period`` the oscillator period [s] of an Sa
    intensity, ``""`` otherwise.
    """
    return _intensity(frag)


def im_key(name):
    """The ``--im`` key (:data:`IMS`) of an intensity variable, or ``None``.

    Returns: ``pga``, ``sa``, ... (``None`` for another name).
    """
    return _im_key(name)


def curves_by_object(frag, pelicun=False):
    """The curves of a fragility dataset grouped by object (a swept block/bed or case), as the exports name them.

    Returns ``(states, objects)``: ``states`` the limit states; ``objects`` ``{id: {"labels": {dim: value},
    <limit state>: row of curve_table, ...}}`` in the order of :func:`curve_table`.
    """
    rows = curve_table(frag)
    states = _states(frag)
    return states, _by_curve(frag, rows, _curve_ids(frag, rows, pelicun=pelicun), states)


def write_csv(frag, path):
    """Write the fits as CSV, one row per curve, fitted or not.

    Columns: the other dimensions (with ``case``: ``case_name`` and the values each case sets),
    ``intensity_measure``, ``units``, ``median``, ``beta`` (empty without a fit), ``fit_flag`` and the
    ``reason`` there is no fit, ``n_unvouched`` (points left out of the fit: nothing vouches for their values
    without a best estimate), ``threshold_rad``, ``period_s`` and the vouched range ``im_min``,
    ``im_max`` (:func:`~screening.analysis.fragility.vouched_range`).

    Returns: ``path``.
    """
    name, units, period = _intensity(frag)
    dims = list(frag["fit_median"].dims)
    _, per_case = case_values(frag)
    case_cols = [] if not per_case else ["case_name"] + list(next(iter(per_case.values()))["values"])
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(dims + case_cols + ["intensity_measure", "units", "median", "beta", "fit_flag", "reason",
                                       "n_unvouched", "threshold_rad", "period_s", "im_min", "im_max"])
        for r in curve_table(frag):
            ok = r["flag"] == FitFlag.ok
            case = per_case.get(r["labels"].get("case"))
            extra = [] if not case_cols else [case["name"]] + [f"{v:.8g}" for v, _ in case["values"].values()]
            w.writerow([r["labels"][d] for d in dims] + extra
                       + [name, units, f"{r['median']:.8g}" if ok else "", f"{r['beta']:.6g}" if ok else "",
                          r["flag"].name, r["reason"], r["n_unvouched"], r["threshold_rad"], period,
                          f"{r['im_min']:.8g}" if math.isfinite(r["im_min"]) else "",
                          f"{r['im_max']:.8g}" if math.isfinite(r["im_max"]) else ""])
    return path


#: pelicun's names of the acceleration and velocity units (``settings/default_units.json``).
PELICUN_UNITS = {"m s-2": "mps2", "m s-1": "mps", "g": "g"}


def _pelicun_demand(frag):
    name, units, period = _intensity(frag)
    key = _im_key(name)
    factor, unit_out = (IMS[key][3], "g") if key in ("pga", "sa") else (1.0, PELICUN_UNITS.get(units, units))
    demand = {"pga": "Peak Ground Acceleration", "sa": f"Spectral Acceleration ({period:g} s)" if period else
              "Spectral Acceleration"}.get(key, name)
    return demand, unit_out, factor


def write_pelicun_csv(frag, path):
    """Write the fits as a pelicun damage-model collection's CSV.

    pelicun's fragility-database columns: ``ID`` (no ``-``: pelicun splits ids on it; the case's name
    and the other dimensions' values), ``Incomplete``, ``Demand-Type`` (``Peak Ground Acceleration``,
    ``Spectral Acceleration (T s)`` in g, else the IM's own name), ``Demand-Unit``, ``Demand-Offset``
    (0: the ground), ``Demand-Directional`` (1: the block rocks in one plane), and per limit state
    ``LS<i>-Family`` = ``lognormal``, ``LS<i>-Theta_0`` = median, ``LS<i>-Theta_1`` = beta.  A block/bed
    with a limit state that is not exported (:func:`export_problem`) has ``Incomplete`` = 1 and empty
    parameters there; the reasons, the case's name and values are in the collection's JSON
    (:func:`write_pelicun_json`).

    Returns: ``path``.
    """
    demand, unit_out, factor = _pelicun_demand(frag)
    rows = curve_table(frag)
    states = _states(frag)
    ids = _curve_ids(frag, rows, pelicun=True)
    header = ["ID", "Incomplete", "Demand-Type", "Demand-Unit", "Demand-Offset", "Demand-Directional"]
    for i in range(1, len(states) + 1):
        header += [f"LS{i}-Family", f"LS{i}-Theta_0", f"LS{i}-Theta_1"]
    with atomic_open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(header)
        for cid, by_state in _by_curve(frag, rows, ids, states).items():
            cells, incomplete = [], 0
            for state in states:
                r = by_state[state]
                if export_problem(r):
                    cells += ["", "", ""]
                    incomplete = 1
                else:
                    cells += ["lognormal", f"{r['median'] * factor:.8g}", f"{r['beta']:.6g}"]
            w.writerow([cid, incomplete, demand, unit_out, 0, 1] + cells)
    return path


def write_pelicun_json(frag, path):
    """Write the JSON metadata of the pelicun collection of :func:`write_pelicun_csv`.

    ``_GeneralInformation`` (name, description, the limit states and the values every block/bed
    shares) and per ``ID``: ``Description`` (the case's name and values), ``Comments`` (why a limit
    state is not exported, or "vouched over IM lo..hi"), ``SuggestedComponentBlockSize`` ``1 EA``,
    ``RoundUpToIntegerQuantity``, ``LimitStates`` (``LS<i>`` -> ``DS<i>`` with the limit state's name
    and rotation), and the values (``Case``, ``Values``) as numbers.

    Returns: ``path``.
    """
    from screening import __version__

    name, units, _ = _intensity(frag)
    demand, unit_out, factor = _pelicun_demand(frag)
    rows = curve_table(frag)
    states = _states(frag)
    shared, per_case = case_values(frag)
    info = {"_GeneralInformation": {
        "ShortName": "screening rocking-block fragilities",
        "Description": f"P(max |theta| > threshold) of rocking blocks on flexible beds, lognormal fits over "
                       f"{name} ({demand}, {unit_out}) by screening {__version__}",
        "Version": __version__, "LimitStates": states, "SharedValues": _values_text(shared)}}
    for cid, by_state in _by_curve(frag, rows, _curve_ids(frag, rows, pelicun=True), states).items():
        labels = by_state["labels"]
        case = per_case.get(labels.get("case"))
        others = {d: v for d, v in labels.items() if d != "case"}
        text = (f"case {case['name']!r}: {_values_text(case['values'])}" if case else "") + \
            ("; " if case and others else "") + _label_text(others)
        comments = []
        for s in states:
            r = by_state[s]
            problem = export_problem(r)
            comments.append(f"{s}: {problem}" if problem else
                            f"{s}: vouched over {name} {r['im_min'] * factor:.4g}..{r['im_max'] * factor:.4g} "
                            f"{unit_out}" if math.isfinite(r["im_min"]) else f"{s}: fitted")
        info[cid] = {"Description": text or "the one block and bed of the study",
                     "Comments": "; ".join(comments),
                     "SuggestedComponentBlockSize": "1 EA", "RoundUpToIntegerQuantity": "True",
                     "Case": case["name"] if case else None,
                     "Values": {**{n: v for n, (v, _) in (case["values"] if case else {}).items()},
                                **{d: v for d, v in others.items()}},
                     "LimitStates": {f"LS{i}": {f"DS{i}": {"Description": f"{s}: max |theta| > "
                                                            f"{by_state[s]['threshold_rad']} rad"}}
                                     for i, s in enumerate(states, 1)}}
    with atomic_open(path, "w", encoding="utf-8") as fh:
        json.dump(info, fh, indent=2)
        fh.write("\n")
    return path


def _im_key(name):
    """The ``--im`` key of an intensity variable: ``pga_median`` (a point's input), ``pga`` (a record's),
    ``stripe_pga`` (a multiple-stripe level) -> ``pga``; ``None`` for another name."""
    base = name.removeprefix("stripe_")
    return next((k for k, v in IMS.items() if base in (v[0], k) or (k == "rms" and base == "rms_acceleration")
                 or (k == "arias" and base == "arias_intensity")), None)


def nrml_limit_state(name):
    """A limit state's name as OpenQuake accepts it (letters, digits, ``_``, ``-``, ``:``).

    Returns: ``.`` written ``p``, ``+`` dropped.
    """
    return name.replace(".", "p").replace("+", "")


def nrml_parameters(median, beta):
    """OpenQuake ``logncdf`` ``(mean, stddev)`` of a lognormal capacity with ``median`` and ``beta``.

    Units: ``median`` [IM units], ``beta`` [1].

    Returns: mean and standard deviation of the capacity [IM units].

    Notes
    -----
    ``mean = median exp(beta^2 / 2)``, ``stddev = mean sqrt(exp(beta^2) - 1)``.

    References
    ----------
    .. [1] [mitseas2026] in the bibliography, ``docs/bibliography.md``.
    .. [2] [baker2015] in the bibliography, ``docs/bibliography.md``.
    .. [3] GEM Foundation, OpenQuake Engine manual, "Fragility models" (NRML 0.5 ``logncdf``
       functions), https://docs.openquake.org
    """
    mean = median * math.exp(0.5 * beta * beta)
    return mean, mean * math.sqrt(math.expm1(beta * beta))


def _comment(text):
    return "    <!-- " + text.replace("--", "- -") + " -->"


def write_nrml(frag, path, model_id="screening_rocking", description="rocking blocks on flexible beds"):
    """Write the fits as an OpenQuake NRML 0.5 fragility model.

    One continuous ``logncdf`` function per swept block/bed (its taxonomy id names the case and the
    values of the other dimensions; a comment gives the case's values), with one ``params`` per limit
    state (the ``limit_state`` dimension where the dataset has several, else
    ``theta_exceeds_threshold``; names by :func:`nrml_limit_state`).  ``minIML`` / ``maxIML`` are the
    range the function was vouched over (:func:`~screening.analysis.fragility.vouched_range`, common to its limit states).  A
    block/bed with a limit state that is not exported (:func:`export_problem`: no fit, untrusted,
    degenerate) is left out and named in a comment with the reason.  Raises :class:`NoExport` (a
    ``ValueError``) for an IM OpenQuake does not know.

    Returns: ``path``.

    Notes
    -----
    Parameters by :func:`nrml_parameters`; PGA, SA and AvgSA in g, PGV in cm/s, ``IA`` in m/s.
    """
    name, _, period = _intensity(frag)
    key = _im_key(name)
    if key is None or IMS[key][2] is None:
        raise NoExport(f"OpenQuake has no intensity measure type for {name!r}; export CSV instead")
    imt = IMS[key][2]
    if imt in ("SA", "AvgSA"):
        imt = f"{imt}({float(period):g})"
    factor = IMS[key][3]
    values = frag[name].values[np.isfinite(frag[name].values)] * factor
    lo_all, hi_all = float(values.min()), float(values.max())
    states = _states(frag)
    names = [nrml_limit_state(s) for s in states]
    rows = curve_table(frag)
    shared, per_case = case_values(frag)
    lines = ['<?xml version="1.0" encoding="UTF-8"?>',
             '<nrml xmlns="http://openquake.org/xmlns/nrml/0.5">',
             f'  <fragilityModel id={quoteattr(model_id)} assetCategory="buildings" lossCategory="contents">',
             f"    <description>{description}: P(max |theta| &gt; threshold) fitted by screening over "
             f"{name}</description>",
             f"    <limitStates>{' '.join(names)}</limitStates>"]
    if names != states:
        lines.append(_comment("limit states: " + ", ".join(f"{n} = {s}" for n, s in zip(names, states))))
    if shared:
        lines.append(_comment("every function: the block and bed of " + _values_text(shared)
                              + "; the function id names the swept values"))
    lines.append(_comment("minIML..maxIML: the range each function was vouched over (OpenQuake holds the "
                          "curve constant beyond it)"))
    for fid, by_state in _by_curve(frag, rows, _curve_ids(frag, rows), states).items():
        case = per_case.get(by_state["labels"].get("case"))
        if case:
            lines.append(_comment(f"{fid}: case {case['name']!r}: {_values_text(case['values'])}"))
        missing = [f"{s}: {export_problem(by_state[s])}" for s in states if export_problem(by_state[s])]
        lo = max((by_state[s]["im_min"] for s in states), default=math.nan) * factor
        hi = min((by_state[s]["im_max"] for s in states), default=math.nan) * factor
        lo, hi = (lo, hi) if math.isfinite(lo) and math.isfinite(hi) else (lo_all, hi_all)
        if not missing and not lo < hi:
            missing = ["degenerate: the limit states have no common vouched range"]
        params = {}
        for s in ([] if missing else states):
            try:
                params[s] = nrml_parameters(by_state[s]["median"] * factor, by_state[s]["beta"])
            except OverflowError:
                params[s] = (math.inf, math.inf)
            if not all(math.isfinite(v) for v in params[s]):
                missing.append(f"{s}: beta {by_state[s]['beta']:.3g} gives a logncdf mean or stddev beyond a float")
        if missing:
            lines.append(_comment(f"no fragility function for {fid}: " + "; ".join(missing)))
            continue
        for s in states:
            if by_state[s]["n_unvouched"]:
                lines.append(_comment(f"{fid} {s}: {by_state[s]['n_unvouched']} point(s) left out of the fit "
                                      "(nothing vouches for them)"))
        lines += [f'    <fragilityFunction id={quoteattr(fid)} format="continuous" shape="logncdf">',
                  f'      <imls imt="{imt}" minIML="{lo:.6g}" maxIML="{hi:.6g}"/>']
        for s, n in zip(states, names):
            mean, std = params[s]
            lines.append(f'      <params ls="{n}" mean="{mean:.8g}" stddev="{std:.8g}"/>')
        lines.append("    </fragilityFunction>")
    lines += ["  </fragilityModel>", "</nrml>", ""]
    with atomic_open(path, "w", encoding="utf-8") as fh:
        fh.write("\n".join(lines))
    return path
