"""The studies and scripts of ``examples/``: the studies load and validate, their bed numbers are the
ones their scripts derive from the materials, and the scripts run (on a tiny grid: 3 intensities,
a few Monte Carlo samples) to a fragility curve over PGA."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from screening.sweep.study import load_study

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _script(name):
    spec = importlib.util.spec_from_file_location(f"example_{name}", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _tiny(name, tmp_path):
    """The example's study with 3 intensities and a few Monte Carlo samples (the statue: a 3 s accuracy
    budget), in ``tmp_path``."""
    text = (EXAMPLES / f"{name}.toml").read_text()
    fewer = ("budget_s = 60", "budget_s = 3") if name == "statue" else ("samples = 100", "samples = 6")
    for old, new in (("num = 13", "num = 3"), fewer):
        assert old in text, (name, old)
        text = text.replace(old, new)
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("name", ["statue", "cabinet"])
def test_example_study_loads_with_the_beds_its_script_derives(name):
    study = load_study(EXAMPLES / f"{name}.toml")
    (case,) = study.cases
    assert list(study.sweeps) == ["pga"] and len(study.sweeps["pga"]) == 13
    k, lam = _script(name).bed()
    # the study file gives the derived values to 3 significant digits
    np.testing.assert_allclose([case.params["k"], case.params["lam"]], [k, lam], rtol=5e-3)
    if name == "statue":                    # Monte Carlo where the linearization is not trusted, by [accuracy]
        assert study.accuracy is not None and list(study.fragility.thresholds) == [0.3]
    else:
        assert study.mcs.count == 1


def test_statue_script_writes_a_fragility_curve_over_pga(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    fragility = _script("statue").main(_tiny("statue", tmp_path), str(tmp_path / "statue.nc"))
    p = fragility["p_exceed"]
    assert p.dims == ("pga",) and p.sizes["pga"] == 3
    known = p.values[np.isfinite(p.values)]                # NaN: a point nothing vouches for (left out)
    assert np.all((known >= 0) & (known <= 1))
    assert fragility.attrs["method"] == "stored (p_source)"   # the study's own answers at its threshold
    assert int(fragility["fit_n_unvouched"]) == int(np.sum(np.isnan(p.values)))
    assert (tmp_path / "statue_fragility.png").is_file()
    assert "median PGA" in capsys.readouterr().out


@pytest.mark.slow
def test_cabinet_script_fits_its_fragility_in_python(tmp_path, capsys):
    curves = _script("cabinet").main(_tiny("cabinet", tmp_path), str(tmp_path / "cabinet.nc"))
    p = curves["p_exceed"]
    assert p.dims == ("pga",) and p.sizes["pga"] == 3
    known = p.values[np.isfinite(p.values)]                # NaN: nothing vouches for the point (left out)
    assert np.all((known >= 0) & (known <= 1))
    assert int(curves["fit_n_unvouched"]) >= int(np.sum(np.isnan(p.values)))
    out = capsys.readouterr().out
    assert "pads: k = 9.75e+09" in out and "trusted check untrusted" in out


def test_the_collection_is_five_objects_on_three_bases_of_screening_beds():
    """``examples/collection.toml`` (the README's quickstart, issue 40 item 6): 5 objects x 3 bases, each bed made
    from its material and thickness as ``screening.beds`` makes it, 10 PGA levels 0.05-0.5 g of Kanai-Tajimi
    firm soil, ``[fragility]`` at 0.05, 0.1, 0.3 of the slenderness and ``[accuracy]``."""
    from screening.analysis import beds

    study = load_study(EXAMPLES / "collection.toml")
    names = [case.name for case in study.cases]
    objects = sorted({name.split(" on ")[0] for name in names})
    bases = sorted({name.split(" on ")[1] for name in names})
    assert len(names) == 15 and len(objects) == 5 and bases == ["mortar", "pad", "timber"]
    for case in study.cases:
        p = case.params
        assert case.excitation == "kanai_tajimi" and (p["omega_g"], p["zeta_g"]) == (15.6, 0.6)
        assert 1e8 <= p["k"] <= 1e12
        zeta = beds.TYPICAL[{"mortar": "lime mortar", "pad": "elastomeric pad (natural rubber / neoprene)",
                             "timber": "timber (across the grain)"}[case.name.split(" on ")[1]]]["zeta_v"]
        lam = beds.lam_from_vertical_damping(p["k"], p["m"], p["b"], 0.5 * (zeta[0] + zeta[1]))
        np.testing.assert_allclose(p["lam"], lam, rtol=1e-12)
    pga = np.asarray(study.sweeps["pga"]) / 9.81
    assert len(pga) >= 10 and abs(pga[0] - 0.05) < 1e-3 and abs(pga[-1] - 0.5) < 1e-3
    assert list(study.fragility.thresholds) == [0.05, 0.1, 0.3] and study.fragility.relative_to == "slenderness"
    assert study.accuracy is not None and study.accuracy.budget_s > 0
