"""Where each cheap model holds: exceedance and overturning probabilities against coupled Monte Carlo.

The validity table of the cheap models (the stiff-bed model, with its bed-derived transfer loss read at the impact
(``stiff_bed``, the default law since 2026-11-29) and at the half cycle's amplitude (``stiff_bed bed``), and with
Housner's (``stiff_bed housner``); the condensed model under
each condensation; the stochastic linearization under each condensation) against the coupled model (the judge),
per bed, excitation and intensity level.

Every Monte Carlo model runs on the SAME ground motions (same seed, same synthesis: sample ``i`` of
seed ``s`` is the same realization for every model, the stiff-bed model reading it low-passed at its
own band), so the differences are paired, sample by sample.  Per case and model:

* ``P(|theta| > a atan(b/h))`` for ``a`` in :data:`FRACTIONS` (overturned samples count as exceeding)
  and ``P(overturn)``; the linearization's from its Gaussian moments as the package computes them
  (:func:`screening.analysis.fragility.exceedance_probability`, Vanmarcke's up-crossing; overturning:
  the up-crossing of ``atan(b/h)``, :func:`screening.analysis.probabilities.overturning_probability`);
* the tolerance of each probability: ``max(0.03, 2.5 SE)`` absolute, ``SE`` the standard error of the
  paired differences (Monte Carlo models, over the samples both ran) or the coupled model's binomial
  standard error (the linearization, which has no sampling error);
* peak ``var_theta`` (over the surviving samples) against the coupled model's, where no sample of the coupled
  model overturns: the ratio within ``max(15 %, 2.5 SE)`` of 1 (:func:`variance_tolerance`; ``SE`` the
  standard error of the ratio by the delta method from both models' ``var_theta_se``, as if the samples were
  independent: they are paired and positively correlated, so this is an upper bound of it).  Near toppling
  the probabilities are the answer; the variance is judged only as far as it is measured;
* CPU per sample (one numba thread: run with ``NUMBA_NUM_THREADS=1``) and the coupled / model ratio
  measured in the same run (the linearization: the coupled model's CPU for all its samples against one
  linearization).

The cases (:func:`cases`): the blocks and beds of the scene (the calibration's statue on ``k = 1e10``,
the hospital equipment on ``1e9``, the paper's block on ``1e9`` and ``1e10``, the scene's statue on a
mortar-stiff ``1e11``, the cabinet on hardening pads) and softer beds where the stiff-bed model should
fail (the scene's statue on ``3e6`` and ``1.5e6``, the paper block on the paper's bed), under white noise
and Kanai-Tajimi ground motion, and museum objects on their three bases (the collection's, ``examples/collection.csv``,
and two stocky ones, ``benchmarks/stocky_objects.csv``) under Kanai-Tajimi and Clough-Penzien firm soil, at two
intensities each (three where the second overturns under 10 %): the median PGA of the record (ground band,
:func:`screening.analysis.intensity.s0_for_pga`) a fixed multiple of the rigid block's uplift
acceleration ``g b / h`` (:data:`LEVELS`).

Each case is written atomically to ``--work/<case>.json`` after each of its models, so an interrupted
run resumes where it stopped; ``--minutes`` stops starting new model runs after that much wall time.
``--report`` assembles the table from the work folder (``--csv`` writes it as package data, ``--figure`` draws
it: the whole CSV with ``--csv``, else the work folder's rows; ``--relabel`` names the models of a folder measured
before the default law changed as the table does).  Each stiff-bed run records its ``transfer`` law.  Run (the
shipped table; about 40 minutes of CPU in all, in chunks)::

    NUMBA_NUM_THREADS=1 PYTHONPATH=. nice -n 10 python benchmarks/stiff_bed_validity.py \\
        --samples 1000 --work outputs/stiff_bed_validity --minutes 9
    PYTHONPATH=. python benchmarks/stiff_bed_validity.py --work outputs/stiff_bed_validity --report \\
        --csv screening/data/stiff_bed_validity.csv --figure docs/images/stiff_bed_validity.png

``--band`` prints instead the band and cost table of ``model = "auto"`` (:func:`band_and_cost`): on the
statue's ``k = 1e10`` and ``1e11`` beds, the coupled model at its default band and reading the same
samples at the ground's band limit (25 Hz), and the cheap models, with paired differences, CPU per
sample and the coupled / model cost ratio in one run::

    NUMBA_NUM_THREADS=1 PYTHONPATH=. python benchmarks/stiff_bed_validity.py --band --samples 500
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from pathlib import Path

import numpy as np

from screening.analysis.beds import lam_from_vertical_damping
from screening.core.model import Block, Foundation
from screening.core.excitations.clough_penzien import CloughPenzien
from screening.core.excitations.kanai_tajimi import KanaiTajimi
from screening.core.excitations.white import WhiteNoise
from screening.solvers import mc_registry, stiff_bed
from screening.solvers.montecarlo import monte_carlo
from screening.sweep.inventory import read_inventory

FRACTIONS = (0.05, 0.1, 0.3, 0.5)
#: Names of the probabilities of a row: exceedance of each fraction of atan(b/h), then overturning.
PROBABILITIES = tuple(f"p_exceed_{a:g}" for a in FRACTIONS) + ("p_overturn",)
STATUE = dict(m=1200.0, b=0.25, h=0.9)
FILTER = dict(omega_g=15.6, zeta_g=0.6)        # Kanai-Tajimi ground filter of the calibration's statue
G = 9.81
T_END, DT = 20.0, 0.05
#: Absolute floor of the tolerance on a probability, and the multiple of its standard error.
P_FLOOR, P_SE_MULT = 0.03, 2.5
#: Tolerance on peak var_theta (relative), where no sample of the coupled model overturns: at least this, and
#: at least ``P_SE_MULT`` standard errors of the ratio (:func:`variance_tolerance`).
VAR_TOL = 0.15

#: Blocks [kg, m, m] with the Kanai-Tajimi filter [rad/s, 1] of their family.
BLOCKS = {
    "statue": (dict(m=1200.0, b=0.25, h=0.9), (15.6, 0.6)),          # the scene's marble statue
    "calibration statue": (dict(m=600.0, b=0.2, h=0.8), (15.6, 0.6)),  # the trust calibration's museum statue
    "equipment": (dict(m=300.0, b=0.3, h=0.9), (10.0, 0.4)),         # the calibration's hospital equipment
    "paper block": (dict(m=8.67, b=0.035, h=0.21), (10.0, 0.4)),     # the paper's block (section 3)
    "cabinet": (dict(m=400.0, b=0.3, h=1.0), (15.6, 0.6)),            # the scene's cabinet
    # the error atlas's ends of slenderness (atan(b/h) 0.10 and 0.45, R = 0.5 m, m = 100 kg: its realisation)
    "slender block": (dict(m=100.0, b=0.05, h=0.4975), (15.6, 0.6)),
    "stocky block": (dict(m=100.0, b=0.2175, h=0.45), (15.6, 0.6)),
    # the issue's slender end (atan(b/h) 0.05, R = 0.5 m, m = 100 kg): w_v / w_r about 2 h / b = 40
    "very slender block": (dict(m=100.0, b=0.025, h=0.4994), (15.6, 0.6)),
}
#: The objects of the acceptance collection (``examples/collection.csv``): name -> (block, Kanai-Tajimi firm soil).
COLLECTION_FILE = Path(__file__).resolve().parents[1] / "examples" / "collection.csv"
_COLLECTION = read_inventory(COLLECTION_FILE)[0]
for _row in _COLLECTION:
    BLOCKS.setdefault(_row["name"].split(" on ")[0], (_row["block"], (15.6, 0.6)))
#: Beds of the collection, as its study makes them (material and thickness -> k, lam): ``BEDS`` entries.
COLLECTION_BEDS = tuple((f"{r['name']} k={r['foundation']['k']:.3g}", r["name"].split(" on ")[0],
                         r["foundation"]["k"], 0.0, r["foundation"]["lam"]) for r in _COLLECTION)
COLLECTION_K = {r["name"]: r["foundation"]["k"] for r in _COLLECTION}
#: Two stocky museum objects (an urn, atan(b/h) 0.448, and a stone basin, 0.598) on the collection's three bases,
#: their beds made as the collection's (``benchmarks/stocky_objects.csv``): ``BEDS`` entries.
STOCKY_FILE = Path(__file__).resolve().parent / "stocky_objects.csv"
_STOCKY = read_inventory(STOCKY_FILE)[0]
for _row in _STOCKY:
    BLOCKS.setdefault(_row["name"].split(" on ")[0], (_row["block"], (15.6, 0.6)))
STOCKY_BEDS = tuple((f"{r['name']} k={r['foundation']['k']:.3g}", r["name"].split(" on ")[0],
                     r["foundation"]["k"], 0.0, r["foundation"]["lam"]) for r in _STOCKY)
#: Beds: ``(label, block, k [N m-2], eps [m-2], lam [N s m-4] or None for a vertical damping ratio of 0.05)``.
BEDS = (
    ("calibration statue k=1e10", "calibration statue", 1e10, 0.0, 3e11),
    ("equipment k=1e9", "equipment", 1e9, 0.0, 1e10),
    ("paper block k=1e9", "paper block", 1e9, 0.0, 1e10),
    ("paper block k=1e10", "paper block", 1e10, 0.0, 3e11),
    ("statue k=1e11", "statue", 1e11, 0.0, None),
    ("cabinet pads k=2.1e9 eps=2e9", "cabinet", 2.1e9, 2e9, None),
    ("paper block k=2.89e7 (paper bed)", "paper block", 2.89e7, 0.0, 8.95e8),
    ("statue k=3e6", "statue", 3e6, 0.0, None),
    ("statue k=1.5e6", "statue", 1.5e6, 0.0, None),
    # the error atlas's corners in slenderness x vertical damping ratio (0.02 and 1.3, BED_ZETA), theta_ul / atan(b/h)
    # about 3e-4, where its stiff-bed references lie (--only "block k=": these eight beds)
    ("slender block k=6.5e9 zeta_v=0.02", "slender block", 6.5e9, 0.0, None),
    ("slender block k=6.5e9 zeta_v=1.3", "slender block", 6.5e9, 0.0, None),
    ("stocky block k=7.7e7 zeta_v=0.02", "stocky block", 7.7e7, 0.0, None),
    ("stocky block k=7.7e7 zeta_v=1.3", "stocky block", 7.7e7, 0.0, None),
    # the museum collection of examples/collection.csv (its beds from screening.beds, as the study makes them):
    # each object on its three bases (--only "on mortar,on pad,on timber"), then the box's damping edges
    *COLLECTION_BEDS,
    # the issue's slender end on the slender block's bed, at the ground's band (Kanai-Tajimi only)
    ("very slender block k=6.5e9 zeta_v=0.02", "very slender block", 6.5e9, 0.0, None),
    ("bust on mortar zeta_v=0.5", "bust", COLLECTION_K["bust on mortar"], 0.0, None),
    ("statuette on pad zeta_v=0.5", "statuette", COLLECTION_K["statuette on pad"], 0.0, None),
    ("showcase on pad zeta_v=0.01", "showcase", COLLECTION_K["showcase on pad"], 0.0, None),
    # the stocky objects on their three bases (Kanai-Tajimi firm soil; --only "urn_on,basin_on")
    *STOCKY_BEDS,
)
#: Vertical damping ratio of a bed whose ``lam`` is None, where it is not 0.05.
BED_ZETA = {label: float(label.rsplit("=", 1)[1]) for label, *_ in BEDS if "zeta_v=" in label}
#: Intensity levels: median PGA of the record (ground band) over the rigid block's uplift acceleration
#: ``g b / h``, per block and excitation kind: moderate rocking and near toppling.
#: Chosen from a 60-sample pilot of the stiff-bed model (moderate: some rocking, few or no overturns; strong:
#: 10-50 % overturning; a third, severe, where the strong level overturns under 10 %).  The small paper block
#: topples at a lower ratio than the statues.
LEVELS = {
    **{(name, "kanai_tajimi"): (1.0, 1.5) for name in ("statue", "calibration statue", "cabinet")},
    **{(name, "white"): (2.2, 3.3) for name in ("statue", "calibration statue", "cabinet", "equipment")},
    ("equipment", "kanai_tajimi"): (1.0, 1.3),
    ("paper block", "kanai_tajimi"): (0.85, 1.0),
    ("paper block", "white"): (0.7, 1.2),
    **{(name, "kanai_tajimi"): (1.0, 1.5) for name in ("slender block", "stocky block", "very slender block")},
    **{(name, "white"): (2.2, 3.3) for name in ("slender block", "stocky block")},
    # the collection's objects: the statues' multiples (rocking; near toppling)
    **{(name, kind): (1.0, 1.5) for name in ("statuette", "bust", "amphora", "showcase", "stele", "urn")
       for kind in ("kanai_tajimi", "clough_penzien")},
    # the basin overturns 1-2 % at 1.5 g b/h: severe at 2.0 (a 100-sample pilot of the stiff-bed model on timber: 42 %)
    **{("basin", kind): (1.0, 1.5, 2.0) for kind in ("kanai_tajimi", "clough_penzien")},
}
#: Per-bed levels where the block's do not fit (softer beds topple at a fraction of ``g b / h``; from a
#: 100-sample coupled pilot).
BED_LEVELS = {
    "statue k=1.5e6": {"kanai_tajimi": (0.3, 0.45), "white": (0.45, 0.7)},
    "statue k=3e6": {"kanai_tajimi": (0.45, 0.7), "white": (0.7, 1.2)},
    "paper block k=2.89e7 (paper bed)": {"kanai_tajimi": (0.6, 0.7), "white": (0.8, 1.5)},
}
EXCITATIONS = ("kanai_tajimi", "white", "clough_penzien")
#: Excitation kinds of a bed where not all of :data:`EXCITATIONS`: on the museum objects' beds (the collection's and
#: the stocky ones) Kanai-Tajimi firm soil and Clough-Penzien (it with the high-pass of :data:`CP_FILTER`).
BED_EXCITATIONS = {
    **{label: ("kanai_tajimi", "clough_penzien") for label, *_ in (*COLLECTION_BEDS, *STOCKY_BEDS)},
    "bust on mortar zeta_v=0.5": ("kanai_tajimi",), "statuette on pad zeta_v=0.5": ("kanai_tajimi",),
    "showcase on pad zeta_v=0.01": ("kanai_tajimi",), "very slender block k=6.5e9 zeta_v=0.02": ("kanai_tajimi",),
}
#: Clough-Penzien high-pass filter [rad/s, 1] (firm soil, with the Kanai-Tajimi filter of the block's family).
CP_FILTER = (1.5, 0.6)

#: Monte Carlo models: name -> (model, condensation) for :func:`screening.monte_carlo`.
MC_MODELS = {
    "coupled": ("coupled", "paper"),
    "stiff_bed": ("stiff_bed", "paper"),                  # the default transfer law, "impact" since 2026-11-29
    "stiff_bed housner": (None, "paper"),                 # StiffBedModel(transfer="housner"), made on use
    "stiff_bed bed": (None, "paper"),                     # StiffBedModel(transfer="bed"), made on use
    "stiff_bed impact": (None, "paper"),                  # StiffBedModel(transfer="impact"): work folders before the
                                                          # switch (their "stiff_bed" is the "bed" law)
    "condensed paper": ("condensed", "paper"),
    "condensed cubic": ("condensed", "cubic"),
    "condensed virtual_work": ("condensed", "virtual_work"),
}
#: Linearization under each condensation: name -> condensation.
SL_MODELS = {"linearization paper": "paper", "linearization cubic": "cubic",
             "linearization virtual_work": "virtual_work"}
MODELS = (*MC_MODELS, *SL_MODELS)


def _bed(block, k, eps=0.0, zeta_v=0.05, lam=None):
    if lam is None:
        lam = float(lam_from_vertical_damping(k, block.m, block.b, zeta_v))
    return Foundation(k=k, eps=eps, lam=float(lam))


def _slug(text):
    return "".join(c if c.isalnum() or c in ".-" else "_" for c in text)


def scene_beds():
    """``(label, block, bed, S0 [m2/s3])``: the statue and cabinet beds of the scene at one Kanai-Tajimi intensity
    each (the first measurement of the stiff-bed model; ``benchmarks/multifidelity_savings.py`` reads them)."""
    statue, cabinet = Block(**STATUE), Block(**BLOCKS["cabinet"][0])
    return [
        ("statue k=1e11", statue, _bed(statue, 1e11), 0.015),
        ("statue k=1e10", statue, _bed(statue, 1e10), 0.015),
        ("cabinet pads k=2.1e9 eps=2e9", cabinet, _bed(cabinet, 2.1e9, eps=2e9), 0.02),
        ("statue k=1e8", statue, _bed(statue, 1e8), 0.01),
        ("statue k=1e7", statue, _bed(statue, 1e7), 0.006),
        ("statue k=3e6", statue, _bed(statue, 3e6), 0.004),
    ]


def _band(band_limit_hz):
    """Keyword of an excitation's band [Hz]: ``None`` or ``"none"`` the idealized spectrum, as every case measured
    before the excitations carried a band (a case without ``band_limit_hz``)."""
    return {"band_limit_hz": None if band_limit_hz in (None, "none") else float(band_limit_hz)}


def cases(band_limit_hz=None):
    """The cases of the validity table, cheapest first (by the coupled model's vertical frequency): dicts with
    ``id``, ``bed``, ``block`` (name), ``block_params``, ``bed_params`` (k, eps, lam), ``excitation``,
    ``omega_g``, ``zeta_g``, ``level``, ``pga_ratio`` and ``S0`` [m2 s-3]; with ``band_limit_hz`` [Hz] (the
    excitation's ground band, ``"none"``: the idealized spectrum) also ``band_limit_hz``, the id ending
    ``_band_<f>``."""
    from screening.analysis.intensity import GROUND_BAND_LIMIT_HZ, ground_cutoff, s0_for_pga
    from screening.solvers.synthesis import vertical_frequency

    cutoff = ground_cutoff(GROUND_BAND_LIMIT_HZ)
    out = []
    for label, name, k, eps, lam in BEDS:
        params, (wg, zg) = BLOCKS[name]
        block = Block(**params)
        bed = _bed(block, k, eps, zeta_v=BED_ZETA.get(label, 0.05), lam=lam)
        for kind in BED_EXCITATIONS.get(label, ("kanai_tajimi", "white")):
            band = _band(band_limit_hz)
            shape = (WhiteNoise(1.0, **band) if kind == "white" else KanaiTajimi(1.0, wg, zg, **band)
                     if kind == "kanai_tajimi" else CloughPenzien(1.0, wg, zg, *CP_FILTER, **band))
            ratios = BED_LEVELS.get(label, {}).get(kind) or LEVELS[(name, kind)]
            for level, ratio in zip(("moderate", "strong", "severe"), ratios):
                S0 = float(s0_for_pga(shape, ratio * G * params["b"] / params["h"], T_END, cutoff))
                case = dict(id=_slug(f"{label}_{kind}_{level}"), bed=label, block=name, block_params=params,
                            bed_params=dict(k=k, eps=eps, lam=float(bed.lam)), excitation=kind,
                            omega_g=wg if kind != "white" else None,
                            zeta_g=zg if kind != "white" else None, level=level, pga_ratio=ratio,
                            S0=S0, w_v=float(vertical_frequency(block, bed)))
                if band_limit_hz is not None:
                    case.update(id=case["id"] + _slug(f"_band_{band_limit_hz}"), band_limit_hz=band_limit_hz)
                out.append(case)
    return sorted(out, key=lambda c: (c["w_v"], c["bed"], c["excitation"], c["level"]))


def realize(case):
    """``(block, foundation, excitation)`` of a case."""
    block = Block(**case["block_params"])
    foundation = Foundation(**case["bed_params"])
    band = _band(case.get("band_limit_hz"))
    if case["excitation"] == "white":
        return block, foundation, WhiteNoise(case["S0"], **band)
    if case["excitation"] == "clough_penzien":
        return block, foundation, CloughPenzien(case["S0"], case["omega_g"], case["zeta_g"], *CP_FILTER, **band)
    return block, foundation, KanaiTajimi(case["S0"], case["omega_g"], case["zeta_g"], **band)


def case_indicators(case):
    """The dimensionless indicators of the point (:func:`screening.solvers.model_choice.indicators`) and the
    intensity: median PGA over ``g b / h`` and over the bed's uplift acceleration."""
    from screening.core import condensation
    from screening.analysis.probabilities import uplift_acceleration
    from screening.solvers.model_choice import indicators

    block, foundation, _ = realize(case)
    out = indicators(block, foundation)
    a_ul = float(uplift_acceleration(block, foundation, condensation.get("cubic")))
    out["pga_over_rigid_uplift"] = case["pga_ratio"]
    out["pga_over_uplift"] = case["pga_ratio"] * G * block.b / block.h / a_ul
    return out


def _finite(x):
    x = float(x)
    return x if math.isfinite(x) else None


def run_mc(case, name, samples, seed):
    """One Monte Carlo model on a case: per-sample peaks, overturned and diverged flags, peak var_theta
    and its standard error, CPU per sample (``{"error": ...}`` if the model refuses the case)."""
    block, foundation, excitation = realize(case)
    model, condensation = MC_MODELS[name]
    if name in ("stiff_bed housner", "stiff_bed bed", "stiff_bed impact"):
        model = stiff_bed.StiffBedModel(transfer=name.split()[1])
    table_s = 0.0
    if name in ("stiff_bed", "stiff_bed bed"):        # the per-bed transfer table, once per bed: not per sample
        start = time.process_time()
        try:
            stiff_bed.transfer_table(block, foundation)
        except ValueError as exc:
            return {"kind": "mc", "error": " ".join(str(exc).split())[:300]}
        table_s = time.process_time() - start
    start = time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")          # the validity warning: the table is what measures it
            ds = monte_carlo(block, foundation, excitation, n_samples=samples, model=model, t_end=T_END, dt=DT,
                             seed=seed, progress=False, condensation=condensation)
    except ValueError as exc:
        return {"kind": "mc", "error": " ".join(str(exc).split())[:300]}
    cpu = time.process_time() - start
    v = ds.var_theta.values
    ok = np.isfinite(v)
    i = int(np.nanargmax(v)) if ok.any() else 0
    return {"kind": "mc", "n": samples, "model": ds.attrs["model"],
            "transfer": getattr(mc_registry.get(model), "transfer", None),   # the stiff-bed model's law
            "peak": [float(x) for x in ds.peak_abs_theta.values],
            "overturned": [bool(x) for x in ds.overturned.values],
            "diverged": [bool(x) for x in ds.diverged.values],
            "var_peak": _finite(v[i]) if ok.any() else None,
            "var_peak_se": _finite(ds.var_theta_se.values[i]) if ok.any() else None,
            "cpu_per_sample": cpu / samples, "table_cpu": table_s,
            "steps_per_sample": float(ds.n_steps.mean()),
            "band": _finite(ds.attrs.get("input_band_rad_s", math.nan))}


def run_sl(case, name):
    """The linearization under one condensation: its exceedance and overturning probabilities from its
    Gaussian moments, peak var_theta, status and CPU (``{"error": ...}`` if the condensation refuses)."""
    from screening.analysis.fragility import exceedance_probability
    from screening.analysis.probabilities import overturning_probability
    from screening.analysis.linearization import linearize

    block, foundation, excitation = realize(case)
    start = time.process_time()
    try:
        ds = linearize(block, foundation, excitation, t_end=T_END, dt=DT, condensation=SL_MODELS[name])
    except ValueError as exc:
        return {"kind": "sl", "error": " ".join(str(exc).split())[:300]}
    p = [_finite(exceedance_probability(ds, a, "slenderness")) for a in FRACTIONS]
    p.append(_finite(overturning_probability(ds)[0]))
    return {"kind": "sl", "p": p, "status": int(ds.status), "var_peak": _finite(ds.peak_var_theta),
            "cpu": time.process_time() - start}


def case_path(work, case):
    return Path(work) / f"{case['id']}.json"


def load_case(work, case):
    path = case_path(work, case)
    if path.exists():
        record = json.loads(path.read_text())
        if record["case"] == json.loads(json.dumps(case)):
            return record                        # a case whose definition changed starts again
    return {"case": case, "models": {}}


def pinned(work, case):
    """The case as stored in the work folder when it differs from ``case`` only in ``S0`` (``--keep-s0``: the
    intensity of an earlier run, e.g. before the PGA label moved from RVT to simulation, so the stored coupled
    samples stay comparable), else ``case``."""
    path = case_path(work, case)
    if not path.exists():
        return case
    stored = json.loads(path.read_text())["case"]
    current = json.loads(json.dumps(case))
    same = {k: v for k, v in stored.items() if k != "S0"} == {k: v for k, v in current.items() if k != "S0"}
    return stored if same else case


def save_case(work, record):
    from screening.core.atomicfile import atomic_open

    with atomic_open(case_path(work, record["case"])) as fh:
        json.dump(record, fh)


def run_cases(chosen, work, samples, seed, models, minutes, condensed_samples=None):
    """Run what is missing of each case (model by model, the JSON rewritten after each), cheapest first;
    no new model run starts after ``minutes`` of wall time.  Returns whether everything asked is done."""
    Path(work).mkdir(parents=True, exist_ok=True)
    start = time.monotonic()
    todo = [(c, m) for c in chosen for m in models if m not in load_case(work, c)["models"]]
    print(f"{len(todo)} model runs to do over {len(chosen)} cases", flush=True)
    for i, (case, name) in enumerate(todo):
        if time.monotonic() - start > 60.0 * minutes:
            print(f"stopped after {minutes:g} min: {len(todo) - i} model runs left (run again to resume)", flush=True)
            return False
        t0 = time.monotonic()
        n = condensed_samples if condensed_samples and name.startswith("condensed") else samples
        got = run_mc(case, name, n, seed) if name in MC_MODELS else run_sl(case, name)
        record = load_case(work, case)
        record["models"][name] = got
        save_case(work, record)
        what = got.get("error") or (f"{1e3 * got['cpu_per_sample']:.1f} ms CPU per sample" if name in MC_MODELS
                                    else f"{got['cpu']:.1f} s CPU")
        print(f"[{i + 1}/{len(todo)}] {case['id']} {name}: {what} ({time.monotonic() - t0:.0f} s wall)", flush=True)
    return True


# ----------------------------------------------------------------------------- the table
def variance_tolerance(ratio, m, ref):
    """``(tolerance, se)`` on ``|ratio - 1|`` of peak var_theta, ``ratio`` the model's over the coupled model's:
    ``max(VAR_TOL, P_SE_MULT se)``, ``se = ratio sqrt((se_m / var_m)^2 + (se_ref / var_ref)^2)`` (delta method,
    ``se_*`` the ``var_peak_se`` of each result; a model without one, the linearization, has none).  The samples
    are paired and positively correlated, so this independent-samples ``se`` bounds the ratio's from above."""
    def rel(r):
        var, se = r.get("var_peak"), r.get("var_peak_se")
        return (se / var) ** 2 if var and se is not None and math.isfinite(se) else 0.0

    if not math.isfinite(ratio):                 # the model has no variance: it fails
        return VAR_TOL, math.nan
    se = abs(ratio) * math.sqrt(rel(m) + rel(ref))
    return max(VAR_TOL, P_SE_MULT * se), se


def compare(case, ref, m):
    """One row of the table: the model's probabilities against the coupled model's, with the tolerances
    and verdicts.  ``ref`` and ``m``: the case's results of the coupled model and of the model."""
    alpha = math.atan(case["block_params"]["b"] / case["block_params"]["h"])
    levels = [a * alpha for a in FRACTIONS]

    def indicators(r, n):
        peak = np.asarray(r["peak"][:n], dtype=float)
        over = np.asarray(r["overturned"][:n], dtype=bool)
        ind = np.array([(peak > lv) | over for lv in levels] + [over], dtype=float)
        return ind, ~np.asarray(r["diverged"][:n], dtype=bool)

    n_ref = len(ref["peak"])
    ind_ref, used_ref = indicators(ref, n_ref)
    p_ref = ind_ref[:, used_ref].mean(axis=1)
    se_ref = np.sqrt(p_ref * (1 - p_ref) / used_ref.sum())
    row = dict(n_overturned_coupled=int(np.sum(np.asarray(ref["overturned"], dtype=bool))))
    if m.get("error"):
        return dict(row, error=m["error"], passed=False)
    if m["kind"] == "sl":
        p = np.array([np.nan if v is None else v for v in m["p"]])
        se = np.zeros_like(p)
        diff = p - p_ref
        tol = np.maximum(P_FLOOR, P_SE_MULT * se_ref)
        cost = ref["cpu_per_sample"] * n_ref / m["cpu"] if m["cpu"] > 0 else math.nan
        n = 0
    else:
        n = min(len(m["peak"]), n_ref)
        ind, used = indicators(m, n)
        both = used & used_ref[:n]
        p = ind[:, used].mean(axis=1)
        se = np.sqrt(p * (1 - p) / used.sum())
        d = ind[:, both] - ind_ref[:n][:, both]
        diff = d.mean(axis=1)                    # paired: over the samples both models ran, neither diverged
        tol = np.maximum(P_FLOOR, P_SE_MULT * d.std(axis=1, ddof=1) / np.sqrt(both.sum()))
        cost = ref["cpu_per_sample"] / m["cpu_per_sample"]
    ok_p = bool(np.all(np.abs(diff) <= tol))
    var_ratio, var_tol, var_se, ok_var = None, None, None, True
    if row["n_overturned_coupled"] == 0 and ref.get("var_peak"):
        var_ratio = (m["var_peak"] / ref["var_peak"]) if m.get("var_peak") is not None else math.inf
        var_tol, var_se = variance_tolerance(var_ratio, m, ref)
        ok_var = bool(abs(var_ratio - 1.0) <= var_tol)
    worst = int(np.nanargmax(np.abs(diff) / tol)) if np.isfinite(diff).any() else 0
    ok_p = ok_p and bool(np.isfinite(diff).all())
    return dict(row, p=p, se=se, p_ref=p_ref, se_ref=se_ref, diff=diff, tol=tol, worst=worst, ok_p=ok_p,
                var_ratio=var_ratio, var_tol=var_tol, var_ratio_se=var_se, ok_var=ok_var, passed=ok_p and ok_var,
                cost_ratio=cost, n=n, error=None,
                status=m.get("status"), sl_cpu=m.get("cpu"))


# ----------------------------------------------------------------------------- the band table
def _fmt(p, se):
    return " | ".join(f"{a:.2f} ± {b:.2f}" for a, b in zip(p, se))


def _paired_se(x, y):
    """Standard error of the mean of the paired differences ``x - y`` (same samples)."""
    d = np.asarray(x, dtype=float) - np.asarray(y, dtype=float)
    return float(np.std(d, ddof=1) / np.sqrt(d.size))


def band_and_cost(samples, seed, models=("stiff_bed", "auto")):
    """The band table: on the statue's ``k = 1e10`` and ``1e11`` beds, the coupled model at its default band
    (3 x the vertical frequency) and reading the same samples low-passed at the ground's band limit
    (``band=``), and the cheap ``models`` (on the ground's band by default), all on the same samples:
    the probabilities, peak var_theta, CPU per sample (one numba thread: run with NUMBA_NUM_THREADS=1)
    and the coupled / model cost ratio, with the paired differences against the coupled default."""
    from screening.analysis.intensity import GROUND_BAND_LIMIT_HZ, ground_cutoff

    statue = Block(**STATUE)
    band = ground_cutoff(GROUND_BAND_LIMIT_HZ)
    lines = ["| bed | model | band [rad/s] | " + " | ".join(f"P(>{a:g} alpha)" for a in FRACTIONS)
             + " | P(overturn) | peak var_theta [rad2] | worst paired diff / tol | CPU per sample [ms] "
             "| coupled / model |", "|" + "---|" * 11]
    for k in (1e10, 1e11):
        bed = _bed(statue, k)
        excitation = KanaiTajimi(0.015, FILTER["omega_g"], FILTER["zeta_g"])
        kw = dict(n_samples=samples, seed=seed, progress=False, t_end=20.0)
        runs = [("coupled", "coupled", {}), ("coupled", "coupled", {"band": band})]
        runs += [(m, m, {}) for m in models]
        ref = None
        for label, model, extra in runs:
            start = time.process_time()
            ds = monte_carlo(statue, bed, excitation, model=model, **kw, **extra)
            cpu = (time.process_time() - start) / samples
            alpha = float(statue.slenderness)
            peak, over = ds.peak_abs_theta.values, ds.overturned.values
            ind = np.array([(peak > a * alpha) | over for a in FRACTIONS] + [over], dtype=float)
            p = ind.mean(axis=1)
            se = np.sqrt(p * (1 - p) / samples)
            i_peak = int(np.nanargmax(ds.var_theta.values))
            var, var_se = float(ds.var_theta.values[i_peak]), float(ds.var_theta_se.values[i_peak])
            if ref is None:
                ref, verdict, ratio_ref = (ind, cpu), "", cpu
            else:
                diff = np.abs(p - ref[0].mean(axis=1))
                tol = np.array([max(0.03, 2.5 * _paired_se(x, y)) for x, y in zip(ind, ref[0])])
                worst = int(np.argmax(diff / tol))
                verdict = f"{diff[worst]:.3f} / {tol[worst]:.3f} " + ("ok" if np.all(diff <= tol) else "FAILS")
            lines.append(f"| statue k={k:.0e} | {ds.attrs['model']} ({label}) | {ds.attrs['input_band_rad_s']:.0f} | "
                         f"{_fmt(p, se)} | {var:.3g} ± {var_se:.2g} | {verdict} | {1e3 * cpu:.2f} | "
                         f"{ratio_ref / cpu:.1f} |")
            print(lines[-1], flush=True)
    lines.append(f"\n{samples} samples per row, seed {seed}; Kanai-Tajimi S0 = 0.015 m2/s3, omega_g = "
                 f"{FILTER['omega_g']} rad/s, zeta_g = {FILTER['zeta_g']}; tolerance max(0.03, 2.5 paired SE) on the "
                 f"difference to the coupled model at its default band.")
    return "\n".join(lines)


def table_rows(work, chosen, relabel=None):
    """The rows of the table (one per case and model, the coupled model first) from the work folder: dicts
    with the case, its indicators, the model and :func:`compare`'s fields (``None`` where not run).
    ``relabel``: ``{name in the work folder: name in the table}`` (a folder measured before the default law
    changed: ``{"stiff_bed": "stiff_bed bed", "stiff_bed impact": "stiff_bed"}``)."""
    rows = []
    relabel = relabel or {}
    for case in chosen:
        record = load_case(work, case)
        ref = record["models"].get("coupled")
        if ref is None or ref.get("error"):
            continue
        ind = case_indicators(case)
        models = {relabel.get(k, k): v for k, v in record["models"].items()}
        for name in MODELS:
            m = models.get(name)
            if m is None:
                continue
            if name == "coupled":
                got = compare(case, ref, ref)
                got.update(diff=np.zeros(len(PROBABILITIES)), passed=None, cost_ratio=1.0)
            else:
                got = compare(case, ref, m)
            rows.append(dict(case=case, indicators=ind, model=name, band=m.get("band"), band_ref=ref.get("band"),
                             cpu_ms=(1e3 * m["cpu_per_sample"] if m.get("kind") == "mc" and not m.get("error")
                                     else None), **got))
    return rows


def _p_text(p, se=None):
    if se is None:
        return " | ".join("n/a" if not np.isfinite(v) else f"{v:.3f}" for v in p)
    return " | ".join(f"{v:.3f} ± {s:.3f}" for v, s in zip(p, se))


def markdown(rows):
    """The validity table as Markdown: per case the coupled model's probabilities, then each model's with
    the worst difference against its tolerance, peak var_theta ratio, verdict and cost."""
    head = ("| case | theta_ul/alpha | model | " + " | ".join(f"P(>{a:g} alpha)" for a in FRACTIONS)
            + " | P(overturn) | worst diff / tol | var ratio | verdict | CPU per sample [ms] | coupled / model |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for r in rows:
        c = r["case"]
        label = f"{c['bed']}, {c['excitation']}, {c['level']} (PGA {c['pga_ratio']:g} g b/h)"
        ratio = f"{r['indicators']['theta_ul_over_slenderness']:.2g}"
        if r.get("error"):
            lines.append(f"| {label} | {ratio} | {r['model']} | " + " | ".join(["-"] * 5)
                         + f" | refused: {r['error'][:80]} | | n/a | | |")
            continue
        if r["model"] == "coupled":
            lines.append(f"| {label} | {ratio} | coupled | {_p_text(r['p_ref'], r['se_ref'])} | | | | "
                         f"{r['cpu_ms']:.1f} | 1 |")
            continue
        w = r["worst"]
        var = "" if r["var_ratio"] is None else f"{r['var_ratio']:.2f} (tol {r['var_tol']:.2f})"
        verdict = "ok" if r["passed"] else "FAILS"
        cpu = "" if r["cpu_ms"] is None else f"{r['cpu_ms']:.1f}"
        lines.append(f"| {label} | {ratio} | {r['model']} | {_p_text(r['p'])} | "
                     f"{r['diff'][w]:+.3f} / {r['tol'][w]:.3f} "
                     f"| {var} | {verdict} | {cpu} | {r['cost_ratio']:.3g} |")
    return "\n".join(lines)


def summary(rows):
    """Pass/fail matrix: one line per case, one column per cheap model: the verdict and the worst probability
    difference in units of its tolerance (signed), and the peak var_theta ratio where that fails."""
    cheap = [m for m in MODELS if m != "coupled"]
    head = "| case | theta_ul/alpha | w_v/w_r | zeta_v | P(overturn) coupled | " + " | ".join(cheap) + " |"
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"]["id"], []).append(r)
    for got in by_case.values():
        c, ind = got[0]["case"], got[0]["indicators"]
        cells = {r["model"]: r for r in got}
        ref = cells["coupled"]

        def cell(name):
            r = cells.get(name)
            if r is None:
                return ""
            if r.get("error"):
                return "n/a"
            text = ("ok" if r["passed"] else "**fail**") + f" {r['diff'][r['worst']] / r['tol'][r['worst']]:+.1f}"
            return text + ("" if r["ok_var"] else f" (var x{r['var_ratio']:.2f}, tol {r['var_tol']:.2f})")

        lines.append(f"| {c['bed']}, {c['excitation']}, {c['level']} | {ind['theta_ul_over_slenderness']:.2g} | "
                     f"{ind['vertical_over_rocking']:.3g} | {ind['vertical_damping_ratio']:.2g} | "
                     f"{ref['p_ref'][-1]:.3f} | "
                     + " | ".join(cell(m) for m in cheap) + " |")
    return "\n".join(lines)


def cost_table(rows):
    """CPU per sample of each Monte Carlo model (one numba thread) and the coupled / model ratio, per case; the
    linearization's CPU per run [s] and the coupled model's CPU for all its samples over it."""
    mc_names = [m for m in MC_MODELS if m != "coupled"]
    head = ("| case | coupled [ms] | " + " | ".join(f"{m} [ms] (ratio)" for m in mc_names)
            + " | linearization paper [s] (ratio) |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    by_case = {}
    for r in rows:
        by_case.setdefault(r["case"]["id"], {})[r["model"]] = r
    for cells in by_case.values():
        c = cells["coupled"]["case"]

        def cell(name):
            r = cells.get(name)
            if r is None or r.get("error") or r["cpu_ms"] is None:
                return ""
            return f"{r['cpu_ms']:.1f} ({r['cost_ratio']:.2g})"

        sl = cells.get("linearization paper")
        sl_text = "" if sl is None or sl.get("error") else f"{sl['sl_cpu']:.2f} ({sl['cost_ratio']:.3g})"
        lines.append(f"| {c['bed']}, {c['excitation']}, {c['level']} | {cells['coupled']['cpu_ms']:.1f} | "
                     + " | ".join(cell(m) for m in mc_names) + f" | {sl_text} |")
    return "\n".join(lines)


#: Columns of the shipped table (``screening/data/stiff_bed_validity.csv``).
CSV_COLUMNS = ("case", "bed", "block", "m", "b", "h", "k", "eps", "lam", "excitation", "omega_g", "zeta_g", "level",
               "pga_over_rigid_uplift", "pga_over_uplift", "S0", "theta_ul_over_slenderness", "slenderness",
               "vertical_over_rocking", "vertical_damping_ratio", "model", "n_samples", *PROBABILITIES,
               *(f"{p}_coupled" for p in PROBABILITIES),
               *(f"diff_{p}" for p in PROBABILITIES), *(f"tol_{p}" for p in PROBABILITIES), "n_overturned_coupled",
               "var_ratio", "var_ratio_se", "tol_var_ratio", "passed", "cpu_ms_per_sample", "coupled_over_model_cost",
               "band_limit_hz",
               "input_band_rad_s", "input_band_rad_s_coupled", "note")


def csv_rows(rows):
    out = []
    for r in rows:
        if r["model"] == "coupled":
            continue
        c, ind = r["case"], r["indicators"]
        base = dict(case=c["id"], bed=c["bed"], block=c["block"], **c["block_params"], **c["bed_params"],
                    excitation=c["excitation"], omega_g=c["omega_g"] if c["omega_g"] is not None else "",
                    zeta_g=c["zeta_g"] if c["zeta_g"] is not None else "", level=c["level"],
                    pga_over_rigid_uplift=c["pga_ratio"], pga_over_uplift=ind["pga_over_uplift"], S0=c["S0"],
                    theta_ul_over_slenderness=ind["theta_ul_over_slenderness"], slenderness=ind["slenderness"],
                    vertical_over_rocking=ind["vertical_over_rocking"],
                    vertical_damping_ratio=ind["vertical_damping_ratio"], model=r["model"])
        if r.get("error"):
            out.append(dict(base, passed=False, note="refused: " + r["error"][:120].replace(",", ";")))
            continue
        out.append(dict(base, n_samples=r["n"] or "", **dict(zip(PROBABILITIES, r["p"])),
                        **{f"{p}_coupled": v for p, v in zip(PROBABILITIES, r["p_ref"])},
                        **{f"diff_{p}": v for p, v in zip(PROBABILITIES, r["diff"])},
                        **{f"tol_{p}": v for p, v in zip(PROBABILITIES, r["tol"])},
                        n_overturned_coupled=r["n_overturned_coupled"],
                        var_ratio="" if r["var_ratio"] is None else r["var_ratio"],
                        var_ratio_se="" if r["var_ratio_se"] is None else r["var_ratio_se"],
                        tol_var_ratio="" if r["var_tol"] is None else r["var_tol"], passed=bool(r["passed"]),
                        cpu_ms_per_sample="" if r["cpu_ms"] is None else r["cpu_ms"],
                        coupled_over_model_cost=r["cost_ratio"], band_limit_hz=c.get("band_limit_hz", "none"),
                        input_band_rad_s="" if r.get("band") is None else r["band"],
                        input_band_rad_s_coupled="" if r.get("band_ref") is None else r["band_ref"], note=""))
    return out


def _shipped_rows(path):
    """``(comment lines, rows)`` of the table already at ``path`` (none if absent); a row of a table written before
    the band columns measured the idealized spectra (``band_limit_hz = none``)."""
    import csv

    path = Path(path)
    if not path.exists():
        return [], []
    lines = path.read_text().splitlines()
    comments = [line for line in lines if line.startswith("#")]
    rows = list(csv.DictReader(line for line in lines if not line.startswith("#")))
    for row in rows:
        row.setdefault("band_limit_hz", "none")
        row["band_limit_hz"] = row["band_limit_hz"] or "none"
    return comments, rows


def write_csv(rows, path, command):
    """The table as CSV (atomic), one line per case and cheap model, the commands and dates in the header.  The rows
    of a table already there whose case and model this run did not measure are kept (the work folder of an earlier
    campaign need not be at hand), with its header lines."""
    import csv
    import io

    from screening.core.atomicfile import atomic_open

    comments, kept = _shipped_rows(path)
    new = csv_rows(rows)
    measured = {(r["case"], r["model"]) for r in new}
    kept = [r for r in kept if (r["case"], r["model"]) not in measured]
    buf = io.StringIO()
    comments = comments or [f"# {__doc__.splitlines()[0]}"]
    buf.write("\n".join(comments) + f"\n# measured {time.strftime('%Y-%m-%d')}: {command}\n")
    writer = csv.DictWriter(buf, fieldnames=CSV_COLUMNS, lineterminator="\n", restval="")
    writer.writeheader()
    for row in kept:
        writer.writerow({k: row.get(k, "") for k in CSV_COLUMNS})
    for row in new:
        writer.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in row.items()})
    with atomic_open(path) as fh:
        fh.write(buf.getvalue())


def figure(rows, path):
    """Per cheap model, the worst |difference| / tolerance of each case of the table against
    ``theta_ul / atan(b/h)``: passes filled, fails open in red, the tolerance band shaded (<= 1).  ``rows``: the
    table's rows as :func:`csv_rows` makes them or as read back from the CSV (the whole shipped table)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from screening.core.atomicfile import atomic_path

    cheap = [m for m in MODELS if m != "coupled" and any(r["model"] == m for r in rows)]
    columns = math.ceil(len(cheap) / 2)
    fig, axes = plt.subplots(2, columns, figsize=(3.75 * columns, 7), sharex=True, sharey=True)
    markers = {"kanai_tajimi": "o", "white": "s", "clough_penzien": "^"}
    for ax, name in zip(axes.ravel(), cheap):
        ax.axhspan(1e-3, 1.0, color="0.9", zorder=0)
        ax.axhline(1.0, color="0.4", lw=0.8)
        for r in rows:
            if r["model"] != name or str(r.get("note", "")).startswith("refused"):
                continue
            x = float(r["theta_ul_over_slenderness"])
            y = max(max(abs(float(r[f"diff_{q}"])) / float(r[f"tol_{q}"]) for q in PROBABILITIES), 1e-2)
            if r.get("var_ratio") not in (None, ""):
                y = max(y, abs(float(r["var_ratio"]) - 1.0) / float(r.get("tol_var_ratio") or VAR_TOL))
            ok = r["passed"] in (True, "True")
            ax.scatter([x], [min(y, 300)], marker=markers[r["excitation"]],
                       s=20 if r["level"] == "moderate" else 36, facecolors="tab:blue" if ok else "none",
                       edgecolors="tab:blue" if ok else "tab:red", zorder=3)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title(name, fontsize=10)
        ax.set_ylim(1e-2, 400)
    for ax in axes[-1]:
        ax.set_xlabel("theta_ul / atan(b/h)")
    for ax in axes[:, 0]:
        ax.set_ylabel("worst |diff| / tolerance")
    fig.suptitle("Cheap models against coupled Monte Carlo (same ground motions): filled = within tolerance "
                 "(shaded), open red = fails;\no Kanai-Tajimi, s white noise, ^ Clough-Penzien; "
                 "large = strong or severe level",
                 fontsize=10)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)


def passing_bounds(rows, model, indicator):
    """``(low, high)``: the widest interval of ``indicator``, starting at its smallest measured value, inside
    which every measured case of ``model`` passed (``None`` if the smallest already fails), by excitation kind
    (a dict ``{kind: (low, high)}``)."""
    out = {}
    for kind in EXCITATIONS:
        got = sorted(((r["indicators"][indicator], bool(r["passed"])) for r in rows
                      if r["model"] == model and r["case"]["excitation"] == kind), key=lambda t: t[0])
        good = []
        for value, ok in got:
            if not ok:
                break
            good.append(value)
        # a failing case at the same value as a passing one ends the interval before that value
        bad = [v for v, ok in got if not ok]
        good = [v for v in good if not bad or v < min(bad)]
        out[kind] = (good[0], good[-1]) if good else None
    return out


def rule_check(rows):
    """Lines: for each model of the shipped rule (``screening/data/model_choice.toml``), the measured cases inside
    it, those that failed, and each indicator's measured range inside it (the rule must lie within it)."""
    from screening.solvers.model_choice import rules

    lines = []
    for rule in rules()[0]:
        inside = [r for r in rows if r["model"] == rule.model and r["case"]["excitation"] in rule.excitations
                  and all(lo <= r["indicators"][n] <= hi for n, (lo, hi) in rule.bounds_for(r["case"]["excitation"]))]
        failed = [f"{r['case']['id']}" for r in inside if not r["passed"]]
        ranges = ", ".join(f"{n} [{min(r['indicators'][n] for r in inside):.3g}, "
                           f"{max(r['indicators'][n] for r in inside):.3g}] (rule [{lo:g}, {hi:g}])"
                           for n, (lo, hi) in rule.bounds) if inside else ""
        lines.append(f"shipped rule of {rule.model}: {len(inside)} measured cases inside, "
                     + (f"FAILED: {failed}" if failed else "all pass")
                     + (f"; measured inside: {ranges}" if ranges else ""))
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--work", default="outputs/stiff_bed_validity", help="folder of the per-case JSON results")
    parser.add_argument("--only", help="run only the cases whose id contains one of these comma-separated texts")
    parser.add_argument("--models", default=",".join(MODELS), help="models to run (comma-separated)")
    parser.add_argument("--condensed-samples", type=int,
                        help="samples of the condensed models (default --samples; the first of the same samples)")
    parser.add_argument("--minutes", type=float, default=9.0, help="start no model run after this wall time")
    parser.add_argument("--keep-s0", action="store_true",
                        help="keep the intensity S0 of a case already in the work folder (see pinned)")
    parser.add_argument("--list", action="store_true", help="list the cases and what is done, then stop")
    parser.add_argument("--report", action="store_true", help="print the table from the work folder, run nothing")
    parser.add_argument("--csv", help="with --report: write the table as CSV here")
    parser.add_argument("--figure", help="with --report: draw the figure here (PNG)")
    parser.add_argument("--band-limit-hz", type=lambda v: v if v == "none" else float(v),
                        help="the excitations' ground band [Hz] (the cases' ids end _band_<f>); absent: none, the "
                             "idealized spectra every case of the table before the band was measured with")
    parser.add_argument("--relabel", type=lambda v: dict(p.split("=", 1) for p in v.split(",")),
                        help="with --report: OLD=NEW,... model names of the work folder as the table names them (a "
                             "folder measured before 2026-11-29: 'stiff_bed=stiff_bed bed,stiff_bed impact=stiff_bed')")
    parser.add_argument("--band", action="store_true",
                        help="print the band and cost table instead (statue k=1e10, 1e11; see band_and_cost)")
    args = parser.parse_args()
    if args.band:
        _compile()
        for k in (1e10, 1e11):
            stiff_bed.transfer_table(Block(**STATUE), _bed(Block(**STATUE), k))
        print(band_and_cost(args.samples, args.seed, tuple(args.models.split(",")) if args.models != ",".join(MODELS)
                            else ("stiff_bed", "auto")))
        return
    models = [m for m in args.models.split(",") if m]
    unknown = [m for m in models if m not in MODELS]
    if unknown:
        parser.error(f"--models must be among {list(MODELS)} (got {unknown})")
    chosen = [c for c in cases(args.band_limit_hz) if args.only is None or any(t in c["id"] for t in args.only.split(","))]
    if args.keep_s0:
        chosen = [pinned(args.work, c) for c in chosen]
    if args.list:
        for c in chosen:
            done = sorted(load_case(args.work, c)["models"])
            print(f"{c['id']}: S0 = {c['S0']:.3g} m2/s3, w_v = {c['w_v']:.0f} rad/s, done: {len(done)}/{len(MODELS)}")
        return
    if not args.report:
        _compile()
        if not run_cases(chosen, args.work, args.samples, args.seed, models, args.minutes,
                         args.condensed_samples):
            raise SystemExit(3)                  # not finished: run the same command again to resume
    rows = table_rows(args.work, chosen, args.relabel)
    print(summary(rows))
    print()
    print(cost_table(rows))
    print()
    print(markdown(rows))
    for name in ("stiff_bed", "stiff_bed bed", "stiff_bed housner",
                 *[m for m in MODELS if m.startswith(("condensed", "lin"))]):
        print(f"{name}: passes throughout theta_ul/alpha in {passing_bounds(rows, name, 'theta_ul_over_slenderness')}")
    for line in rule_check(rows):
        print(line)
    if args.csv:
        write_csv(rows, args.csv, "NUMBA_NUM_THREADS=1 PYTHONPATH=. python benchmarks/stiff_bed_validity.py "
                  f"--samples {args.samples} --seed {args.seed} --work {args.work}")
    if args.figure:                              # the whole table when it was just written, else this run's rows
        figure(_shipped_rows(args.csv)[1] if args.csv else csv_rows(rows), args.figure)


def _compile():
    """Compile the kernels outside the timings."""
    from screening.analysis.linearization import linearize

    block = Block(**STATUE)
    excitation = KanaiTajimi(1e-3, 15.6, 0.6)
    for model, condensation in {*MC_MODELS.values()} - {(None, "paper")}:
        monte_carlo(block, _bed(block, 1e10), excitation, n_samples=2, t_end=0.2, dt=0.1, progress=False,
                    model=model, condensation=condensation)
    for condensation in SL_MODELS.values():
        linearize(block, _bed(block, 1e10), excitation, t_end=0.2, dt=0.1, condensation=condensation)


if __name__ == "__main__":
    main()
