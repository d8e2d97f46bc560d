"""Fragility outputs an engineer can hand on: a target-PGA study with ``[accuracy]``, the file set written
all or none, every curve present (or named missing with its reason), several limit states in one
NRML model, fits over the intensity the study sweeps, and curves through unvouched numbers flagged."""

import csv
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest
import xarray as xr

from helpers import study_text

from screening.applications.im_fragility import nrml_limit_state
from screening.cli import main
from screening.core.status import FitFlag, BestMethod, ProbabilitySource

#: Two beds (k) x five target PGAs, 3 s records, with [accuracy] (the combination that used to end in
#: "t_end is needed to turn a target PGA into S0").
#: The paper condensation, pinned: the curve counts and the untrusted points asserted below are its own.
PGA_STUDY = study_text({"foundation.k": "[2.89e7, 5e6]", "foundation.eps": "0.0", "foundation.condensation": '"paper"',
                        "excitation.S0": None,
                        "excitation.pga": "{start = 0.5, stop = 4, num = 5, log = true}", "time.t_end": "3.0"},
                       append="[accuracy]\ntarget = 0.15\nbudget_s = 600000\n")
#: The same grid without [accuracy]: untrusted points keep the linearization's value.
PLAIN_STUDY = PGA_STUDY.split("[accuracy]")[0]
NS = {"n": "http://openquake.org/xmlns/nrml/0.5"}


def _run(folder, text, name):
    (folder / f"{name}.toml").write_text(text)
    assert main(["run", str(folder / f"{name}.toml"), "--out", str(folder / f"{name}.nc"), "--workers", "0",
                 "--quiet", "--no-plots"]) == 0
    return folder / f"{name}.nc"


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    folder = tmp_path_factory.mktemp("frag")
    return _run(folder, PGA_STUDY, "pga"), _run(folder, PLAIN_STUDY, "plain")


def _leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if ".tmp" in p.name)


def test_target_pga_with_accuracy_runs_and_labels_best_estimates(results):
    with xr.open_dataset(results[0]) as ds:
        assert ds["status"].dims == ("k", "pga") and "best_method" in ds
        assert np.all(np.isfinite(ds["S0"].values))


def test_fragility_defaults_to_the_swept_pga_and_names_the_fit_fit_median(results, capsys):
    out = results[0].with_name("default_frag.nc")
    assert main(["fragility", str(results[0]), "--threshold", "0.02", "--relative-to", "slenderness",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "lognormal fit over pga: 2 of 2 curve(s) fitted" in err
    with xr.open_dataset(out) as frag:
        assert "median" not in frag.variables          # Dataset.median would shadow it
        assert frag["fit_median"].dims == ("k",) and frag["fit_median"].attrs["intensity"] == "pga"
        assert frag["fit_median"].attrs["units"] == "m s-2" and np.all(frag["fit_flag"] == FitFlag.ok)
    assert out.with_suffix(".png").stat().st_size > 10_000
    # the fits over the swept (target median) PGA go out as CSV, pelicun CSV and NRML (PGA in g)
    rows = list(csv.DictReader(out.with_suffix(".csv").open()))
    assert [r["intensity_measure"] for r in rows] == ["pga", "pga"] and all(r["fit_flag"] == "ok" for r in rows)
    imls = ET.parse(out.with_suffix(".xml")).getroot().find("n:fragilityModel/n:fragilityFunction/n:imls", NS)
    assert imls.get("imt") == "PGA" and float(imls.get("maxIML")) == pytest.approx(4.0 / 9.80665, rel=1e-5)
    assert main(["info", str(out)]) == 0                 # info describes the fragility file
    text = capsys.readouterr().out
    assert "(fragility file)" in text and "lognormal fit over pga: 2 of 2 curve(s) fitted" in text


def test_im_fragility_writes_every_curve_and_several_limit_states(results, capsys):
    folder = results[0].parent
    out = folder / "ls.nc"
    # 0.02 x slenderness is crossed within the swept PGAs on both beds; 0.005 x slenderness already at the
    # lowest PGA (P = 1, or within a few 1e-6 of it where the atlas vouches for the corrected linearization's
    # Gaussian probability: nothing to fit)
    assert main(["fragility", str(results[0]), "--threshold", "0.02", "--threshold", "0.005", "--relative-to",
                 "slenderness", "--im", "pga", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "2 of 4 curve(s) fitted (2 without a fit: " in err
    rows = list(csv.DictReader(out.with_suffix(".csv").open()))
    states = ["theta_0.005_slenderness", "theta_0.02_slenderness"]
    assert len(rows) == 4 and {r["limit_state"] for r in rows} == set(states)
    missing = [r for r in rows if r["fit_flag"] != "ok"]
    assert len(missing) == 2 and all(r["reason"] and r["median"] == "" for r in missing)
    assert all(r["limit_state"] == states[0] for r in missing)
    with xr.open_dataset(out) as frag:               # the flag of each: P above 1 - 1e-6 at every PGA or not
        p = frag["best_p_exceed"].sel(limit_state=states[0])
        expected = {float(k): "always_exceeded" if bool((p.sel(k=k) > 1 - 1e-6).all()) else "no_fit"
                    for k in frag["k"].values}
    assert {float(r["k"]): r["fit_flag"] for r in missing} == expected
    root = ET.parse(out.with_suffix(".xml")).getroot()
    model = root.find("n:fragilityModel", NS)
    assert model.find("n:limitStates", NS).text.split() == [nrml_limit_state(s) for s in states]
    # no bed has both limit states fitted: no function, each named in a comment with its reason
    assert model.findall("n:fragilityFunction", NS) == []
    text = out.with_suffix(".xml").read_text()
    assert text.count("<!-- no fragility function for screening_k=") == 2
    pelicun = list(csv.DictReader(folder.joinpath("ls_pelicun.csv").open()))
    assert len(pelicun) == 2 and all(r["LS2-Theta_0"] and not r["LS1-Theta_0"] for r in pelicun)
    meta = json.loads(folder.joinpath("ls_pelicun.json").read_text())
    assert all(r["Incomplete"] == "1" and "no fit" in meta[r["ID"]]["Comments"] for r in pelicun)
    for ls in states:
        assert folder.joinpath(f"ls_{ls}.png").stat().st_size > 10_000
    assert _leftovers(folder) == []


def test_nrml_holds_both_limit_states_per_bed(results):
    out = results[0].with_name("two.nc")
    assert main(["fragility", str(results[0]), "--threshold", "0.05", "--threshold", "0.02", "--relative-to",
                 "slenderness", "--im", "pga", "--out", str(out)]) == 0
    model = ET.parse(out.with_suffix(".xml")).getroot().find("n:fragilityModel", NS)
    functions = model.findall("n:fragilityFunction", NS)
    assert sorted(f.get("id") for f in functions) == ["screening_k=2.89e+07", "screening_k=5e+06"]
    assert "<!-- every function: the block and bed of m = 8.67 kg, b = 0.035 m, h = 0.21 m" in \
        out.with_suffix(".xml").read_text()
    for f in functions:
        means = [float(p.get("mean")) for p in f.findall("n:params", NS)]
        assert [p.get("ls") for p in f.findall("n:params", NS)] == ["theta_0p02_slenderness", "theta_0p05_slenderness"]
        assert means[0] < means[1]                     # the larger rotation needs the stronger shaking


def test_the_set_is_written_all_or_none(results, capsys, monkeypatch):
    """A failing NRML write leaves the files of the earlier run as they were and no temporary behind;
    the command that used to fail in the CSV writer (a threshold relative to the slenderness, stored
    per point) writes the whole set."""
    import screening.applications.im_fragility as imf

    folder = results[0].parent
    out = folder / "set.nc"
    args = ["fragility", str(results[0]), "--threshold", "0.02", "--relative-to", "slenderness", "--im", "pga",
            "--out", str(out)]
    assert main(args) == 0
    names = ["set.nc", "set.png", "set.csv", "set_pelicun.csv", "set_pelicun.json", "set.xml"]
    before = {n: folder.joinpath(n).read_bytes() for n in names}
    assert len(list(csv.DictReader(folder.joinpath("set.csv").open()))) == 2

    def broken(frag, path, **kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(imf, "write_nrml", broken)
    args[3] = "0.05"
    assert main(args) == 2
    assert "No space left on device" in capsys.readouterr().err
    assert {n: folder.joinpath(n).read_bytes() for n in names} == before
    assert _leftovers(folder) == []


def test_fits_leave_out_untrusted_points_without_best_estimates_and_say_so(results, capsys):
    """A point nothing vouches for (untrusted, or stopped, without a best estimate) is left out of the fit and
    counted; the printed line, the CSV and the NRML say so (the collection issue: fits use what is vouched for)."""
    with xr.open_dataset(results[1]) as ds:
        stopped = ds["status"].isin([1, 2])
        unvouched = int((((ds["sl_trust"] == 2) & (ds["status"] == 0)) | stopped).sum())
    assert unvouched > 0, "the grid needs unvouched points for this test"
    out = results[1].with_name("plain_frag.nc")
    assert main(["fragility", str(results[1]), "--threshold", "0.02", "--relative-to", "slenderness", "--im", "pga",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    with xr.open_dataset(out) as frag:
        n = frag["fit_n_unvouched"].values
        assert int(n.sum()) == unvouched
        flags = frag["fit_flag"].values
        shaky = int(np.sum(n > 0))
        assert np.all(np.isnan(frag["fit_median"].values[flags != FitFlag.ok]))
    assert f"{shaky} with points left out of the fit" in err
    rows = list(csv.DictReader(out.with_suffix(".csv").open()))
    assert sum(int(r["n_unvouched"]) for r in rows) == unvouched
    xml = out.with_suffix(".xml").read_text()
    fitted_with_left_out = int(np.sum((n > 0) & (flags == FitFlag.ok)))
    assert xml.count("left out of the fit (nothing vouches for them)") == fitted_with_left_out
    # with [accuracy] every point has a vouched best estimate or is left out as unreliable
    out2 = results[0].with_name("vouched.nc")
    assert main(["fragility", str(results[0]), "--threshold", "0.02", "--relative-to", "slenderness", "--im", "pga",
                 "--out", str(out2)]) == 0
    with xr.open_dataset(results[0]) as ds, xr.open_dataset(out2) as frag:
        unreliable = int((~ds["p_source"].isin([ProbabilitySource.linearization_gaussian,
                                                ProbabilitySource.corrected_linearization_gaussian])
                          & (ds["best_method"] == BestMethod.unreliable)).sum())
        assert int(frag["fit_n_unvouched"].sum()) == unreliable


def test_a_point_whose_s0_cannot_follow_from_its_pga_is_flagged_and_the_others_solved(tmp_path, capsys):
    """zeta_g = 1e-9 makes the Kanai-Tajimi spectral moments unintegrable: those points are flagged
    beyond_float_range with NaN S0; the zeta_g = 0.6 points of the same batch are solved."""
    from screening.analysis.intensity import s0_for_pga
    from screening.core.model.excitation import Envelope
    from screening.core.excitations.kanai_tajimi import KanaiTajimi
    from screening.core.status import PointStatus

    text = study_text({"foundation.eps": "0.0", "excitation.kind": '"kanai_tajimi"', "excitation.S0": None,
                       "excitation.pga": "[0.5, 1.0, 2.0]", "excitation.omega_g": "15.0",
                       "excitation.zeta_g": "[1e-9, 0.6]", "time.t_end": "3.0"})
    path = _run(tmp_path, text, "kt")
    err = capsys.readouterr().err
    assert "task_failed" not in err and "Traceback" not in err and "Warning" not in err
    with xr.open_dataset(path) as ds:
        status = ds["status"].transpose("zeta_g", "pga").values
        s0 = ds["S0"].transpose("zeta_g", "pga").values
    assert np.all(status[0] == PointStatus.beyond_float_range) and np.all(np.isnan(s0[0]))
    assert np.all(status[1] != PointStatus.task_failed) and np.all(np.isfinite(s0[1]))
    shape = KanaiTajimi(1.0, 15.0, 0.6, Envelope())
    expected = s0_for_pga(shape, np.array([0.5, 1.0, 2.0]), 3.0, shape.reference_cutoff())   # the 25-Hz band, to its top
    np.testing.assert_allclose(s0[1], expected, rtol=1e-9)
