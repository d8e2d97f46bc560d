"""Cloud analysis: a study's block on its bed under an ensemble of recorded ground motions.

A cloud study is a study file with a ``[records]`` table (files, units, scale, model, threshold,
intensity measure: ``docs/records.md``, "Cloud analysis").  Each record is integrated
by :func:`screening.simulate` (in process, or one dask task per record); the result holds, on a
``record`` dimension, the peak ``|theta|``, the overturned flag, the exceedance and the record's intensity
measures, and the lognormal fragility is fitted by maximum likelihood to the exceed/not-exceed outcomes
[baker2015].  A failed record is kept with NaNs and ``diverged`` set, named in the warnings.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from screening.analysis.fragility import fit_binomial_fragility
from screening.analysis.intensity import PERIOD_MEASURES, record_measures, RECORD_MEASURES
from screening.applications.records_study import block_and_foundation, load_record_study
from screening.core import limits
from screening.core.records import (check_scale, check_time_step, expand_records, read_record, Record, unit_factor,
                                    write_at2)
from screening.core.status import FitFlag
from screening.io.errors import exception_line
from screening.solvers import model_choice, schema
from screening.solvers.simulate import SIMULATION, simulate
from screening.solvers.synthesis import check_band, ground_acceleration_samples, spectral_plan
from screening.sweep.config import check_choice, check_keys, check_value, StudyError
from screening.sweep.execution import TASK_RETRIES
from screening.sweep.interrupt import interruptible
from screening.solvers.schema import cf, declare, INTENSITY

__all__ = ["MAX_LEVELS", "IMS", "CloudStudy", "load_cloud_study", "run_cloud", "run_stripes", "synthesise_records",
           "write_demand_csv"]

#: The variables of a cloud analysis: one row per record, then the fitted fragility; declared here.
CLOUD = declare("cloud", {
    **{name: SIMULATION[name] for name in ("peak_abs_theta", "overturned", "overturning_time")},
    "diverged": cf("1", "the integration diverged or its task failed (left out of the fit)"),
    "lift_off": SIMULATION["lift_off"],
    **{name: INTENSITY[name] for name in ("pga", "sa", "rms_acceleration", "arias_intensity", "pgv", "avgsa",
                                          "fit_flag")},
    "record": cf("1", "record index"),
    "record_name": {"long_name": "record name"},
    "exceed": cf("1", "peak |theta| above the threshold, or overturned"),
    "threshold_rad": cf("rad", "rotation threshold"),
    "slenderness": cf("rad", "slenderness angle atan(b/h)"),
    "level": cf("1", "intensity level of the stripe (units of the intensity measure)"),
    "n_exceed": cf("1", "records exceeding the threshold at the level"),
    "n_used": cf("1", "records integrated at the level (not diverged)"),
    "fit_median_se": cf("1", "standard error of fit_median (units of the intensity; stripes: observed information, "
                             "sweeps: from the standard errors of the fitted points)"),
    "beta_se": cf("1", "standard error of beta (stripes: observed information, sweeps: from the standard errors of "
                       "the fitted points)"),
    **{f"stripe_{name}": cf("1", f"{name} of the stripe (records scaled to it)") for name in
       ("pga", "sa", "rms_acceleration", "arias_intensity", "pgv", "avgsa")},
})

_RECORD_KEYS = ("files", "units", "dt", "scale", "model", "period", "threshold", "relative_to", "im", "levels",
                "vertical")
#: Most IM levels of a multiple-stripe analysis.
MAX_LEVELS = 100
IMS = {"pga": "pga", "sa": "sa", "rms": "rms_acceleration", "arias": "arias_intensity", "pgv": "pgv",
       "avgsa": "avgsa"}


@dataclass(frozen=True)
class CloudStudy:
    """A validated cloud study: the sweep :class:`~screening.sweep.study.Study` of its block and bed
    and the ``[records]`` settings."""

    study: object
    files: tuple
    units: str | None
    dt: float | None
    scale: float
    model: str
    period: float | None
    threshold: float
    relative_to: str
    im: str
    levels: tuple = ()
    vertical: bool = True


def load_cloud_study(path, units=None, vertical=True):
    """Read a cloud study; :class:`StudyError` with a one-line message naming the key on any problem.

    ``units``: the ``--units`` of the command line (``[records] units`` if absent; both: must agree).
    ``vertical``: False (``--no-vertical``) leaves the records' vertical components out whatever
    ``[records] vertical`` says.

    Parameters
    ----------
    path : str or os.PathLike
        The TOML study file with a ``[records]`` table (module docstring); record paths are relative
        to its folder.
    units : str, optional
        Units of the records' accelerations: ``"g"``, ``"m/s2"``, ``"cm/s2"`` or ``"gal"``.
    vertical : bool, optional
        False leaves the vertical components out.

    Returns
    -------
    CloudStudy
        The study of the block and bed with the ``[records]`` settings (files found, threshold [rad
        or fraction], intensity measure, Sa period [s], IM levels of a multiple-stripe analysis).

    Raises
    ------
    StudyError
        One line naming the file and the key (``docs/records.md`` lists the keys).

    References
    ----------
    [1] ``docs/records.md``.

    Examples
    --------
    >>> import tempfile
    >>> from screening.core.excitations import KanaiTajimi
    >>> from screening.core.model.excitation import Envelope
    >>> folder = tempfile.TemporaryDirectory()
    >>> ground = KanaiTajimi(S0=1e-3, omega_g=15.6, zeta_g=0.6, envelope=Envelope(T1=3.0, T2=1.5), band_limit_hz=None)
    >>> paths = synthesise_records(os.path.join(folder.name, "records"), ground, n_records=3, t_end=10.0,
    ...                            cutoff=120.0, scales=[0.5, 1.0, 2.0], seed=15)
    >>> with open(os.path.join(folder.name, "cloud.toml"), "w") as fh:
    ...     _ = fh.write('''
    ... [block]
    ... m = 8.67
    ... b = 0.035
    ... h = 0.21
    ... [foundation]
    ... k = 2.89e7
    ... lam = 8.95e8
    ... [records]
    ... files = "records/*.at2"
    ... threshold = 0.2
    ... ''')
    >>> cloud = load_cloud_study(os.path.join(folder.name, "cloud.toml"))
    >>> [os.path.basename(f) for f in cloud.files], cloud.im, cloud.threshold, cloud.relative_to
    (['synthetic_00.at2', 'synthetic_01.at2', 'synthetic_02.at2'], 'pga', 0.2, 'slenderness')
    >>> folder.cleanup()
    """
    base, rec = load_record_study(path)
    root = Path(path).parent
    if rec is None:
        raise StudyError(f"{path}: records: required in a cloud study ([records] with files = ...)")
    try:
        check_keys(rec, _RECORD_KEYS, "records.")
        if "files" not in rec:
            raise StudyError("records.files: required (a folder, a glob or a list of them)")
        try:
            files = tuple(expand_records(rec["files"], root=str(root)))
        except (ValueError, TypeError) as exc:
            raise StudyError(f"records.files: {exc}") from None
        if not files:
            raise StudyError("records.files: empty list (give a folder, a glob or a list of them)")
        if len(files) > limits.MAX_RECORD_FILES:
            raise StudyError(f"records.files: {len(files)} files; at most {limits.MAX_RECORD_FILES}")
        model = rec.get("model", "coupled")
        if model not in model_choice.choices():
            raise StudyError(f"records.model: must be one of {', '.join(model_choice.choices())} (got {model!r})")
        im = rec.get("im", "pga")
        if im not in IMS:
            raise StudyError(f"records.im: must be one of {', '.join(IMS)} (got {im!r})")
        period = rec.get("period")
        if im in ("sa", "avgsa") and period is None:
            raise StudyError(f"records.period: required with im = {im!r}")
        relative_to = rec.get("relative_to", "slenderness")
        if relative_to not in ("slenderness", "theta_ul", "rad"):
            raise StudyError(f"records.relative_to: must be 'slenderness', 'theta_ul' or 'rad' (got {relative_to!r})")
        for key, check in (("dt", check_time_step), ("scale", check_scale)):
            if key in rec:
                try:
                    check(rec[key], f"records.{key}:")
                except ValueError as exc:
                    raise StudyError(str(exc)) from None
        if period is not None:
            low, high = limits.SA_PERIOD_RANGE
            period = check_value("records.period", period, lower=low, inclusive=True, upper=high)
        if "threshold" in rec:
            check_value("records.threshold", rec["threshold"], 0.0)
        stated = rec.get("units")
        if stated is not None:
            check_choice("records.units", stated, ("g", "m/s2", "cm/s2", "gal"))
            if units is not None and unit_factor(units) != unit_factor(stated):
                raise StudyError(f"records.units: {stated!r}, but --units {units!r} was given")
        units = units or stated
        levels = _levels(rec.get("levels"), im)
        use_vertical = rec.get("vertical", True)
        if not isinstance(use_vertical, bool):
            raise StudyError(f"records.vertical: must be true or false (got {use_vertical!r})")
    except StudyError as exc:
        raise StudyError(f"{path}: {exc}") from None
    return CloudStudy(study=base, files=files, units=units, dt=rec.get("dt"),
                      scale=float(rec.get("scale", 1.0)), model=model,
                      period=None if period is None else float(period),
                      threshold=float(rec.get("threshold", 0.2)), relative_to=relative_to, im=im, levels=levels,
                      vertical=bool(vertical and use_vertical))


def _model_attrs(cloud, block, foundation):
    """``model``: the Monte Carlo model that ran (``"auto"`` resolved for this block and bed), and
    ``model_requested`` where the study asked for ``"auto"``."""
    ran = model_choice.resolve(cloud.model, block, foundation).name
    return {"model": ran, **({"model_requested": cloud.model} if cloud.model != ran else {})}


def _levels(value, im):
    """``[records] levels``: the IM levels [units of ``im``] of a multiple-stripe analysis (``()``: a cloud)."""
    if value is None:
        return ()
    units = INTENSITY[IMS[im]]["units"]
    ok = isinstance(value, list) and 2 <= len(value) <= MAX_LEVELS and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v > 0 for v in value)
    if not ok or any(b <= a for a, b in zip(value, value[1:])):
        raise StudyError(f"records.levels: must be a list of 2..{MAX_LEVELS} increasing finite numbers > 0 "
                         f"[{units}] (got {value!r})")
    return tuple(float(v) for v in value)


def _run_record(block, foundation, record, model="coupled", condensation="paper", period=None):
    """One record: ``dict`` of the peak ``|theta|``, overturned/diverged flags, overturning time and the
    record's intensity measures."""
    ds = simulate(block, foundation, record, model=model, condensation=condensation, output_dt=max(record.dt, 0.01))
    out = {"peak_abs_theta": float(ds["peak_abs_theta"]), "overturned": bool(ds["overturned"]),
           "diverged": bool(ds["diverged"]), "overturning_time": float(ds["overturning_time"]),
           "lift_off": bool(ds["lift_off"]) if "lift_off" in ds else False}
    out.update(record_measures(record, period=period))
    return out


def read_cloud_records(cloud):
    """The records of a :class:`CloudStudy`, read and scaled (:class:`StudyError` naming the bad file);
    without their vertical components when the study leaves them out.

    Parameters
    ----------
    cloud : CloudStudy
        The cloud study.

    Returns
    -------
    list of screening.core.records.Record
        The records (accelerations [m s-2], time step [s]), in the order of ``cloud.files``.

    Raises
    ------
    StudyError
        A record that cannot be read (its file named).
    """
    from dataclasses import replace

    records = []
    for path in cloud.files:
        try:
            rec = read_record(path, dt=cloud.dt, units=cloud.units, option="--units or records.units")
        except ValueError as exc:
            raise StudyError(f"records.files: {exc}") from None
        rec = rec if cloud.vertical else replace(rec, vertical=None)
        records.append(rec.scaled(cloud.scale) if cloud.scale != 1.0 else rec)
    return records


def _failed_record(period=None):
    """The row of a record whose task failed: NaN values, ``diverged`` (left out of the fit)."""
    row = {"peak_abs_theta": math.nan, "overturned": False, "diverged": True, "overturning_time": math.nan,
           "lift_off": False}
    row.update({name: math.nan for name in RECORD_MEASURES if name not in PERIOD_MEASURES or period is not None})
    return row


def _record_rows(block, foundation, records, model, condensation, period, client=None, progress=None):
    """``_run_record`` for every record, in this process (``client`` None) or as one dask task per record.

    Returns ``(rows, failures)``: one dict per record in the order given, and the messages of the
    records whose task failed (their rows come from :func:`_failed_record`)."""
    def said(i, row):
        if progress:
            progress(f"record {i + 1}/{len(records)} {records[i].name}: peak |theta| {row['peak_abs_theta']:.4g} rad"
                     + (" (overturned)" if row["overturned"] else ""))

    rows, failures = [None] * len(records), []
    if client is None:
        for i, rec in enumerate(records):
            rows[i] = _run_record(block, foundation, rec, model, condensation, period)
            said(i, rows[i])
        return rows, failures
    from distributed import as_completed

    pending = {client.submit(_run_record, block, foundation, rec, model, condensation, period, pure=False,
                             retries=TASK_RETRIES): i for i, rec in enumerate(records)}
    for fut in interruptible(as_completed(list(pending), loop=client.loop)):
        i = pending.pop(fut)
        try:
            rows[i] = fut.result()
        except Exception as exc:                       # noqa: BLE001 - recorded, the record is left out
            rows[i] = _failed_record(period)
            failures.append(f"record {records[i].name} failed: {exception_line(exc)}")
        fut.release()
        said(i, rows[i])
    return rows, failures


def run_cloud(cloud, case=None, overrides=None, progress=None, client=None, records=None):
    """Run every record of a :class:`CloudStudy`; returns ``(dataset, warnings)`` (see the module docstring).

    ``client``: a ``distributed.Client`` to run one task per record on (default: in this process).
    ``records``: the records already read by :func:`read_cloud_records` (read here if ``None``).

    Parameters
    ----------
    cloud : CloudStudy
        The cloud study.
    case : str, optional
        The study's case to run (:func:`~screening.applications.records_study.pick_case`).
    overrides : dict, optional
        Values of swept block or bed parameters (SI), e.g. ``{"eps": 6e7}`` [m-2].
    progress : callable, optional
        Receives one line per finished record.
    client : distributed.Client, optional
        Runs one task per record (default: in this process).
    records : list of screening.core.records.Record, optional
        The records, already read.

    Returns
    -------
    dataset : xarray.Dataset
        Per record the peak ``|theta|`` [rad], the flags and intensity measures, and the fitted
        lognormal fragility (:func:`cloud_dataset`).
    warnings : list of str
        Failed records and what the fit could not do.

    Notes
    -----
    The fragility :math:`P(\\mathrm{exceed} \\mid IM) = \\Phi(\\ln(IM/\\theta)/\\beta)` is fitted by
    maximum likelihood to the exceed / not-exceed outcome of each record (Bernoulli likelihood) [1].

    References
    ----------
    [1] [baker2015]; [2] ``docs/records.md``.

    Examples
    --------
    The block and bed are checked before any record runs (the integration itself compiles the
    solvers on first use):

    >>> from screening.sweep.study import EXAMPLE_STUDY, parse_study
    >>> cloud = CloudStudy(study=parse_study(EXAMPLE_STUDY), files=(), units=None, dt=None, scale=1.0, model="coupled",
    ...                    period=None, threshold=0.2, relative_to="slenderness", im="pga")
    >>> block, foundation, _ = block_and_foundation(cloud.study, overrides={"eps": 6e7})
    >>> try:
    ...     run_cloud(cloud)                          # eps is swept: one value must be chosen
    ... except StudyError as exc:
    ...     print(exc)
    foundation.eps is swept in the study; fix it with --set eps=VALUE (swept values: 0, 6e+07)
    """
    block, foundation, chosen = block_and_foundation(cloud.study, case, overrides)
    if records is None:
        records = read_cloud_records(cloud)
    mc = model_choice.resolve(cloud.model, block, foundation)           # "auto": once, for this block and bed
    rows, failures = _record_rows(block, foundation, records, cloud.model,
                                  chosen.condensation if mc.uses_condensation else "paper", cloud.period,
                                  client, progress)
    ds, warnings = cloud_dataset(cloud, block, foundation, rows, [rec.name for rec in records])
    ds.attrs["vertical_ground_motion"] = vertical_summary(cloud, records)
    lifted = [rec.name for rec, row in zip(records, rows) if row["lift_off"]]
    if lifted:
        stopped = "flew and landed" if mc.vertical_state else \
            "stopped there (diverged: left out of the fit)"
        warnings.append(f"{len(lifted)} record(s) lift the block off (g + a_v < 0: {', '.join(lifted[:3])}"
                        f"{', ...' if len(lifted) > 3 else ''}); the {mc.name} model {stopped}")
        ds.attrs["warnings"] = "; ".join(warnings)
    ds.attrs["execution"] = "serial, in process" if client is None else \
        f"dask, one task per record on {len(client.nthreads())} worker(s)"
    return ds, failures + warnings


def vertical_summary(cloud, records):
    """What became of the records' vertical components (the ``vertical_ground_motion`` attribute)."""
    n = sum(rec.vertical is not None for rec in records)
    if not cloud.vertical:
        return "left out (vertical = false or --no-vertical): the models took the horizontal components only"
    if n == 0:
        return "none (no record has a vertical component)"
    return (f"used for the {n} of {len(records)} record(s) that have one: g + a_v(t) acts on the block and its bed "
            f"(docs/method.md, 'Vertical ground acceleration')")


def threshold_level(cloud, block, foundation):
    """The rotation threshold [rad] of a cloud study on ``block`` and ``foundation``.

    ``threshold`` times the slenderness angle :math:`\\alpha = \\arctan(b/h)`, times the uplift angle
    :math:`\\theta_{ul}` of the paper's condensation, or in radians, as ``relative_to`` says.

    Parameters
    ----------
    cloud, block, foundation
        The cloud study, its block and its bed.

    Returns
    -------
    float
        The threshold rotation [rad].
    """
    if cloud.relative_to == "slenderness":
        return cloud.threshold * float(block.slenderness)
    if cloud.relative_to == "theta_ul":
        from screening.core import condensation as condensations
        return cloud.threshold * float(condensations.get("paper").uplift_threshold(block, foundation))
    return cloud.threshold


def scaled_to(record, im, level, period=None):
    """``record`` scaled so that its intensity measure ``im`` equals ``level``: the factor is
    ``level / IM`` (PGA, Sa, RMS are proportional to the scale), ``sqrt(level / IM)`` for Arias.

    The vertical component, if any, is scaled by the same factor.

    Parameters
    ----------
    record : screening.core.records.Record
        The record.
    im : str
        The intensity measure, a key of :data:`IMS`.
    level : float
        Its target value, in its unit ([m s-2] for PGA, Sa, RMS; [m s-1] for Arias and PGV).
    period : float, optional
        The period of Sa [s].

    Returns
    -------
    screening.core.records.Record
        The scaled record.

    Notes
    -----
    Arias intensity :math:`I_a = \\frac{\\pi}{2g}\\int a^2\\,dt` grows with the square of the scale,
    hence the square root [arias1970].
    """
    value = record_measures(record, period=period)[IMS[im]]
    factor = level / value if im != "arias" else math.sqrt(level / value)
    vertical = None if record.vertical is None else record.vertical * factor     # both components alike
    return Record(record.acceleration * factor, record.dt, record.name, record.source, record.units_in,
                  vertical=vertical)


def run_stripes(cloud, case=None, overrides=None, progress=None, client=None, records=None):
    """Multiple-stripe analysis: every record scaled to every IM level of ``cloud.levels``, run, and the
    exceedances at each level fitted by the binomial likelihood with standard errors
    (:func:`screening.analysis.fragility.fit_binomial_fragility`).  Returns ``(dataset, warnings)``.

    Parameters
    ----------
    cloud : CloudStudy
        The study, with ``[records] levels``.
    case : str, optional
        The study's case to run.
    overrides : dict, optional
        Values of swept block or bed parameters (SI).
    progress : callable, optional
        Receives one line per finished run.
    client : distributed.Client, optional
        Runs one task per record and level (default: in this process).
    records : list of screening.core.records.Record, optional
        The records, already read.

    Returns
    -------
    dataset : xarray.Dataset
        Per level and record the peak [rad], flags and exceedance; per level the counts; the fit
        (:func:`stripe_dataset`).
    warnings : list of str
        Failed runs and what the fit could not do.

    Notes
    -----
    With :math:`z_j` of :math:`n_j` records exceeding at level :math:`x_j`, the median :math:`\\theta`
    and dispersion :math:`\\beta` maximise
    :math:`\\sum_j \\ln\\binom{n_j}{z_j} + z_j\\ln p_j + (n_j - z_j)\\ln(1 - p_j)`,
    :math:`p_j = \\Phi(\\ln(x_j/\\theta)/\\beta)` [1].

    References
    ----------
    [1] [baker2015]; [2] ``docs/records.md``.

    Examples
    --------
    >>> from screening.sweep.study import EXAMPLE_STUDY, parse_study
    >>> cloud = CloudStudy(study=parse_study(EXAMPLE_STUDY), files=(), units=None, dt=None, scale=1.0, model="coupled",
    ...                    period=None, threshold=0.2, relative_to="slenderness", im="pga")
    >>> block, foundation, _ = block_and_foundation(cloud.study, overrides={"eps": 6e7})
    >>> try:
    ...     run_stripes(cloud)
    ... except StudyError as exc:
    ...     print(exc)
    foundation.eps is swept in the study; fix it with --set eps=VALUE (swept values: 0, 6e+07)
    """
    block, foundation, chosen = block_and_foundation(cloud.study, case, overrides)
    records = read_cloud_records(cloud) if records is None else records
    scaled = [scaled_to(rec, cloud.im, level, cloud.period) for level in cloud.levels for rec in records]
    condensation = chosen.condensation if model_choice.resolve(cloud.model, block, foundation).uses_condensation else "paper"
    rows, failures = _record_rows(block, foundation, scaled, cloud.model, condensation, cloud.period, client,
                                  progress)
    ds, warnings = stripe_dataset(cloud, block, foundation, rows, [rec.name for rec in records])
    return ds, failures + warnings


def stripe_dataset(cloud, block, foundation, rows, names):
    """The result of a multiple-stripe analysis from its rows (level-major): per level and record the
    peak, flags and exceedance; per level the counts; the binomial fit with its standard errors.

    Parameters
    ----------
    cloud : CloudStudy
        The study, with its IM ``levels``.
    block : screening.core.model.Block
        The block.
    foundation : screening.core.model.Foundation
        The bed.
    rows : list of dict
        One per level and record, level-major: ``peak_abs_theta`` [rad], ``overturned``,
        ``diverged``, ``overturning_time`` [s], ``lift_off`` and the intensity measures.
    names : list of str
        The record names.

    Returns
    -------
    dataset : xarray.Dataset
        On ``(level, record)``; ``n_exceed``, ``n_used`` on ``level``; ``fit_median`` (the IM's
        unit), ``beta`` [1], their standard errors and ``fit_flag``.
    warnings : list of str
        What the fit could not do.
    """
    levels, n_rec = np.asarray(cloud.levels), len(names)
    level = threshold_level(cloud, block, foundation)
    grid = {k: (("level", "record"), np.array([r[k] for r in rows]).reshape(levels.size, n_rec)) for k in rows[0]}
    ds = xr.Dataset(grid, coords={"level": ("level", levels), "record": ("record", np.arange(n_rec)),
                                  "record_name": ("record", np.array(names, dtype=object))})
    used = ~ds["diverged"].values
    exceed = ((ds["peak_abs_theta"].values > level) | ds["overturned"].values) & used
    ds["exceed"] = (("level", "record"), exceed)
    ds["n_exceed"] = ("level", exceed.sum(axis=1))
    ds["n_used"] = ("level", used.sum(axis=1))
    ds["threshold_rad"] = ((), level)
    ds["slenderness"] = ((), float(block.slenderness))
    name = IMS[cloud.im]
    warnings = []
    fit = {"median": math.nan, "beta": math.nan, "median_se": math.nan, "beta_se": math.nan}
    try:
        fit = fit_binomial_fragility(levels, ds["n_exceed"].values, ds["n_used"].values)
        flag = fit["flag"]
    except ValueError as exc:
        flag = FitFlag.never_exceeded if not exceed.any() else FitFlag.always_exceeded if exceed[used].all() \
            else FitFlag.no_fit
        warnings.append(f"no fragility fit: {exc}")
    degenerate = ""
    if flag == FitFlag.separated:
        degenerate = ("the stripes separate exceeding from not exceeding perfectly: beta is not identified "
                      "(standard errors undefined)")
        warnings.append("the stripes separate exceeding from not exceeding perfectly: beta is not determined "
                        "(fit_flag separated, no fit exported); add levels near the median")
    elif flag != FitFlag.ok and "flag" in fit:
        warnings.append(f"no fragility fit: {FitFlag(flag).meaning} (fit_flag {FitFlag(flag).name})")
    if flag != FitFlag.ok:
        fit = {key: math.nan for key in ("median", "beta", "median_se", "beta_se")}
    ds["fit_median"] = ((), fit["median"])
    ds["beta"] = ((), fit["beta"])
    ds["fit_median_se"] = ((), fit["median_se"])
    ds["beta_se"] = ((), fit["beta_se"])
    ds["fit_flag"] = ((), np.int8(flag))
    ds["stripe_" + name] = ("level", levels)
    ds = schema.apply_schema(ds, CLOUD)
    units = ds[name].attrs["units"]
    for v in ("fit_median", "fit_median_se", "stripe_" + name, "level"):
        ds[v].attrs.update(units=units)
    ds["fit_median"].attrs["intensity"] = "stripe_" + name
    ds.attrs.update(title=f"Multiple-stripe analysis: {cloud.study.title}", **_model_attrs(cloud, block, foundation),
                    study=cloud.study.source, intensity_measure=cloud.im, intensity_variable="stripe_" + name,
                    intensity_dim="level", threshold=cloud.threshold, relative_to=cloud.relative_to,
                    fit="lognormal, binomial maximum likelihood over the stripes (Baker 2015), standard errors "
                        "from the observed information", warnings="; ".join(warnings) or "none",
                    **({"fit_degenerate": degenerate} if degenerate else {}))
    return ds, warnings


def cloud_dataset(cloud, block, foundation, rows, names):
    """The result dataset of a cloud analysis from its per-record ``rows``: the records, the
    exceedance of each, and the maximum-likelihood lognormal fragility; returns ``(ds, warnings)``.

    A record exceeds when its peak ``|theta|`` is above :func:`threshold_level` or it overturned;
    diverged records are left out of the fit.

    Parameters
    ----------
    cloud : CloudStudy
        The study.
    block : screening.core.model.Block
        The block.
    foundation : screening.core.model.Foundation
        The bed.
    rows : list of dict
        One per record: ``peak_abs_theta`` [rad], ``overturned``, ``diverged``, ``overturning_time``
        [s], ``lift_off`` and the intensity measures.
    names : list of str
        The record names.

    Returns
    -------
    ds : xarray.Dataset
        On ``record``: the rows and ``exceed``; ``threshold_rad`` and ``slenderness`` [rad];
        ``fit_median`` (the IM's unit), ``beta`` [1] and ``fit_flag``.
    warnings : list of str
        What the fit could not do (no fit, perfect separation, a threshold beyond the slenderness).

    Notes
    -----
    :math:`P(\\mathrm{exceed} \\mid IM) = \\Phi(\\ln(IM/\\theta)/\\beta)`, with :math:`\\theta` and
    :math:`\\beta` maximising the Bernoulli likelihood of the records' outcomes [baker2015].
    """
    from screening.solvers import schema
    from screening.analysis.fragility import fit_flag_of, fit_lognormal_fragility

    slender = float(block.slenderness)
    level = threshold_level(cloud, block, foundation)
    data = {k: ("record", np.array([r[k] for r in rows])) for k in rows[0]}
    ds = xr.Dataset(data, coords={"record": ("record", np.arange(len(rows))),
                                  "record_name": ("record", np.array(names, dtype=object))})
    used = ~ds["diverged"].values
    exceed = (ds["peak_abs_theta"].values > level) | ds["overturned"].values
    ds["exceed"] = ("record", exceed)
    ds["threshold_rad"] = ((), level)
    ds["slenderness"] = ((), slender)
    name = IMS[cloud.im]
    im_values = ds[name].values
    warnings = []
    try:
        if not used.any():
            raise ValueError("no record was integrated (all diverged or failed):")
        if exceed[used].all() or not exceed[used].any():
            raise ValueError("all records exceed" if exceed[used].all() else "no record exceeds")
        median, beta = fit_lognormal_fragility(im_values[used], n_exceed=exceed[used].astype(float), n_total=1.0)
    except ValueError as exc:
        median, beta = math.nan, math.nan
        warnings.append(f"no fragility fit: {exc} the threshold")
    degenerate, separated = "", False
    if np.isfinite(beta) and beta > 0:
        x_in, x_out = im_values[used][exceed[used]], im_values[used][~exceed[used]]
        if x_in.min() > x_out.max():
            separated = True
            degenerate = (f"the records are perfectly separated by {name}: beta is not identified (the likelihood "
                          "grows as beta -> 0)")
            warnings.append(f"the records are perfectly separated by {name} (every exceeding record has a larger "
                            "IM than every other): beta is not identified (the likelihood grows as beta -> 0; "
                            "fit_flag separated, no fit exported); add records near the median")
    if level >= slender:
        warnings.append("the threshold is at or beyond the slenderness angle atan(b/h)")
    if separated:
        flag = FitFlag.separated
    elif np.isfinite(beta):
        flag = fit_flag_of(im_values[used], median, beta)
        if flag not in (FitFlag.ok, FitFlag.non_positive_beta):
            warnings.append(f"no fragility fit: {flag.meaning} (fit_flag {flag.name})")
    elif used.any() and (exceed[used].all() or not exceed[used].any()):
        flag = FitFlag.always_exceeded if exceed[used].all() else FitFlag.never_exceeded
    else:
        flag = FitFlag.no_values if not used.any() else FitFlag.no_fit
    if flag == FitFlag.non_positive_beta:
        warnings.append("the fitted beta is <= 0 (exceedance falls with the intensity measure)")
    ds["fit_median"] = ((), median if flag == FitFlag.ok else math.nan)
    ds["beta"] = ((), beta if flag == FitFlag.ok else math.nan)
    ds["fit_flag"] = ((), np.int8(flag))
    ds = schema.apply_schema(ds, CLOUD)
    ds["fit_median"].attrs.update(units=ds[name].attrs["units"], intensity=name)
    for name_with_period in ("sa", "avgsa"):
        if name_with_period in ds:
            ds[name_with_period].attrs.update(period=cloud.period, damping_ratio=0.05)
    ds.attrs.update(title=f"Cloud analysis: {cloud.study.title}", **_model_attrs(cloud, block, foundation),
                    study=cloud.study.source,
                    intensity_measure=cloud.im, intensity_variable=name, intensity_dim="record",
                    threshold=cloud.threshold, relative_to=cloud.relative_to,
                    fit="lognormal, maximum likelihood on the exceed / not-exceed outcome of each record",
                    warnings="; ".join(warnings) or "none", **({"fit_degenerate": degenerate} if degenerate else {}))
    return ds, warnings


def synthesise_records(folder, excitation, n_records, t_end, cutoff, scales, seed=0, dt=0.01):
    """Write ``n_records`` synthesised records of ``excitation`` (spectral representation, seed ``seed``),
    resampled to ``dt`` and multiplied by ``scales[i]``, as PEER-style ``.AT2`` files in ``folder``.

    For examples and tests (no download): returns the file paths.

    Parameters
    ----------
    folder : str or os.PathLike
        Where to write (created if missing).
    excitation : screening.core.excitations.Excitation
        The ground motion model (its PSD and envelope).
    n_records : int
        Records to write.
    t_end : float
        Record length [s].
    cutoff : float
        Highest circular frequency of the spectral representation [rad s-1]; the excitation's band
        (``band_limit_hz``, its low-pass in the PSD) must lie below it and below the Nyquist frequency of ``dt``.
    scales : sequence of float
        Factor of each record [1].
    seed : int, optional
        Seed of the random phases.
    dt : float, optional
        Time step of the files [s].

    Returns
    -------
    list of str
        The paths written, ``synthetic_00.at2``, ...

    Notes
    -----
    Spectral representation: :math:`a(t) = q(t)\\,\\sqrt{2}\\sum_k \\sqrt{2 S(\\omega_k)\\Delta\\omega}\\,
    \\cos(\\omega_k t + \\varphi_k)` with independent phases :math:`\\varphi_k \\sim U[0, 2\\pi)` and
    :math:`S` the PSD of the excitation (:mod:`screening.solvers.synthesis`) [1].

    References
    ----------
    [1] [shinozuka1991]; [2] PEER Ground Motion
    Database, "AT2 file format", https://ngawest2.berkeley.edu.

    Examples
    --------
    >>> import tempfile
    >>> from screening.core.excitations import KanaiTajimi
    >>> from screening.core.model.excitation import Envelope
    >>> ground = KanaiTajimi(S0=1e-3, omega_g=15.6, zeta_g=0.6, envelope=Envelope(T1=3.0, T2=1.5), band_limit_hz=None)
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     paths = synthesise_records(folder, ground, n_records=2, t_end=10.0, cutoff=120.0, scales=[1.0, 2.0])
    ...     [os.path.basename(p) for p in paths], open(paths[0]).readline().strip()
    (['synthetic_00.at2', 'synthetic_01.at2'], 'PEER NGA STRONG MOTION DATABASE RECORD')
    """
    check_band(excitation, t_end, min(float(cutoff), math.pi / float(dt)))   # the band below the files' Nyquist
    plan = spectral_plan(excitation, t_end, cutoff)
    acc, _ = ground_acceleration_samples(excitation, plan, seed, np.arange(n_records))
    t = np.arange(0.0, t_end + 0.5 * dt, dt)
    os.makedirs(folder, exist_ok=True)
    paths = []
    for i in range(n_records):
        a = np.interp(t, plan.times, acc[i]) * float(scales[i])
        path = os.path.join(folder, f"synthetic_{i:02d}.at2")
        write_at2(path, Record(a, dt, name=f"synthetic_{i:02d}"),
                  title=f"screening synthetic record {i}, scale {float(scales[i]):g}", station=excitation.kind)
        paths.append(path)
    return paths


def write_demand_csv(ds, path):
    """The per-record demands of a cloud analysis as CSV, one row per record (per level and record for a
    multiple-stripe analysis, with the ``level`` column): its name, its intensity measures, the peak
    ``|theta|`` [rad] and as a fraction of the slenderness angle, and the flags (overturned, diverged:
    left out of the fit, exceed) - the table a PSDM or a pelicun demand sample is built from.  Headers
    carry the units in brackets.

    Parameters
    ----------
    ds : xarray.Dataset
        A cloud or multiple-stripe result.
    path : str or os.PathLike
        The CSV file to write.

    Returns
    -------
    str or os.PathLike
        ``path``.

    References
    ----------
    [1] A. Zsarnóczay and G. G. Deierlein, "PELICUN - A computational framework for estimating damage, loss
    and community resilience", Proceedings of the 17th World Conference on Earthquake Engineering, Sendai
    (2020); [2] ``docs/records.md``.

    Examples
    --------
    >>> import tempfile
    >>> from screening.sweep.study import EXAMPLE_STUDY, parse_study
    >>> cloud = CloudStudy(study=parse_study(EXAMPLE_STUDY), files=(), units=None, dt=None, scale=1.0, model="coupled",
    ...                    period=None, threshold=0.2, relative_to="slenderness", im="pga")
    >>> block, foundation, _ = block_and_foundation(cloud.study, overrides={"eps": 6e7})
    >>> rows = [{"peak_abs_theta": p, "overturned": o, "diverged": False, "overturning_time": float("nan"),
    ...          "lift_off": False, "pga": a, "rms_acceleration": a / 4, "arias_intensity": a, "pgv": a / 10}
    ...         for p, o, a in [(0.001, False, 0.5), (0.04, False, 1.0), (0.002, False, 1.5), (0.01, True, 2.0)]]
    >>> ds, _ = cloud_dataset(cloud, block, foundation, rows, ["r1", "r2", "r3", "r4"])
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     lines = open(write_demand_csv(ds, os.path.join(folder, "demands.csv"))).read().splitlines()
    >>> lines[0].split(",")[-5:]
    ['peak_abs_theta [rad]', 'peak_abs_theta / slenderness [1]', 'overturned', 'diverged', 'exceed']
    >>> lines[4]                                                  # r4: overturned, so it exceeds
    '3,r4,2,0.5,2,0.2,0.01,0.0605515,1,0,1'
    """
    import csv

    ims = [name for name in RECORD_MEASURES if name in ds]
    slender = float(ds["slenderness"])
    stripes = "level" in ds.dims
    flat = ds.stack(run=("level", "record")) if stripes else ds.rename(record="run").assign_coords(
        record=("run", ds["record"].values))
    with open(path, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(([f"level [{ds['level'].attrs.get('units', '')}]"] if stripes else []) + ["record", "record_name"]
                   + [f"{n} [{ds[n].attrs.get('units', '')}]" for n in ims]
                   + ["peak_abs_theta [rad]", "peak_abs_theta / slenderness [1]", "overturned", "diverged", "exceed"])
        names = ds["record_name"].values
        for i in range(flat.sizes["run"]):
            one = flat.isel(run=i)
            record = int(one["record"].values)
            peak = float(one["peak_abs_theta"].values)
            w.writerow(([f"{float(one['level'].values):.8g}"] if stripes else []) + [record, str(names[record])]
                       + [f"{float(one[n].values):.8g}" for n in ims]
                       + [f"{peak:.8g}", f"{peak / slender:.6g}"]
                       + [int(bool(one[n].values)) for n in ("overturned", "diverged", "exceed")])
    return path
