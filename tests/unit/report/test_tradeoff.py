"""Speed-accuracy trade study (screening.report.tradeoff): a tiny end-to-end run."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from helpers import TRADE_STUDY
from screening.report import tradeoff as to
from screening.applications.metrics import peak_relative_error, peak_with_se, time_averaged_relative_error
from screening.applications.tradeoff_study import load_tradeoff_study
from screening.core.model import Block, Foundation
from screening.core.model.excitation import Envelope
from screening.core.excitations.white import WhiteNoise
from screening.report.tradeoff_files import from_file_layout
from screening.report.tradeoff_text import summary_text
from screening.solvers.moments import solve_moments
from screening.solvers.montecarlo import monte_carlo
from screening.solvers.timegrid import output_times
from screening.sweep.config import StudyError

# ============================================================================ end to end
TINY = TRADE_STUDY.replace("[mcs]\nsamples = 50", "[mcs]\nsamples = 50\nseed = 3") + """
[sl]
rtol_sweep = [1e-5, 1e-7]
h_max_sweep = [0.1]
timing_repeats = 1
"""


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("tradeoff")
    path = d / "tiny.toml"
    path.write_text(TINY)
    ds, paths, rules = to.run_tradeoff(path, d / "out", progress=None)
    return d, ds, paths, rules


def test_end_to_end_structure(tiny_run):
    d, ds, paths, rules = tiny_run
    for key in ("nc", "md", "csv", "error_vs_cost", "validity"):
        assert paths[key].exists() and paths[key].stat().st_size > 0, key
    assert paths["nc"].name == "tiny.nc" and paths["validity"].name == "tiny_validity.png"
    raw = xr.open_dataset(paths["nc"])
    assert raw.attrs["Conventions"] == "CF-1.8"
    assert list(raw.approach_name.values) == ["sl", "condensed_mcs", "coupled_mcs"]   # labels: aux coordinates
    assert "approach" not in raw.coords
    saved = from_file_layout(raw)
    assert saved.sizes["point"] == 2 and saved.sizes["t"] == 41 and saved.sizes["approach"] == 3
    assert list(saved.approach.values) == ["sl", "condensed_mcs", "coupled_mcs"]
    np.testing.assert_array_equal(saved.var_theta.values, ds.var_theta.values)
    assert saved.peak_var_theta.attrs["units"] == "rad2"
    np.testing.assert_array_equal(saved.peak_var_theta.sel(approach="coupled_mcs").values,
                                  np.nanmax(ds.var_theta.sel(approach="coupled_mcs").values, axis=-1))
    assert saved.var_theta.attrs["units"] == "rad2" and saved.cost.attrs["units"] == "s"
    assert saved.S0.attrs["units"] == "m2 s-3" and saved.t.attrs["units"] == "s"
    assert saved.peak_rel_error.dims == ("comparison", "quantity", "point")
    assert saved.cv_peak_var_theta.sizes == {"rep_point": 1, "cv_model": 2, "n_samples": 2}
    assert saved.sl_cost.sizes["sl_setting"] == 3
    assert np.all(saved.cost > 0)
    assert "SL within" in saved.attrs["rules"]
    raw.close()
    md = paths["md"].read_text()
    assert "Cost ratio SL : condensed MCS : coupled MCS" in md and "Validity rules" in md
    assert "**Recommended:** Use SL alone for" in md
    assert len(rules) == 4 and {r["reference"] for r in rules} == {"condensed", "coupled"}


def test_end_to_end_numbers_match_direct_calls(tiny_run):
    _, ds, _, _ = tiny_run
    block = Block(m=8.67, b=0.035, h=0.21)
    bed = Foundation(k=2.89e7, lam=8.95e8, eps=6e7)
    t = output_times(2.0, 0.05)
    j = 1
    S0 = float(ds.S0[j])
    assert S0 == 2e-5
    exc = WhiteNoise(S0, Envelope(4.0, 2.0))
    sl = solve_moments(block, bed, exc, t, rtol=1e-7)
    np.testing.assert_array_equal(ds.var_theta.sel(approach="sl").values[j], sl["var_theta"])
    assert float(ds.sl_peak_p_uplift[j]) == float(sl["peak_p_uplift"])
    assert float(ds.k_eq_margin[j]) == pytest.approx(float(sl["min_k_eq"]) / sl["k_eq"][0])
    # rtol=None: the fixed per-model tolerance (the trade study's mcs.rtol default), not the engine's "auto"
    mc = monte_carlo(block, bed, exc, n_samples=50, model="coupled", t_end=2.0, dt=0.05, seed=3, progress=False,
                     rtol=None)
    np.testing.assert_allclose(ds.var_theta.sel(approach="coupled_mcs").values[j], mc.var_theta.values, rtol=1e-12)
    np.testing.assert_allclose(ds.var_theta_se.sel(approach="coupled_mcs").values[j], mc.var_theta_se.values,
                               rtol=1e-12)
    assert int(ds.n_overturned.sel(mcs_model="coupled")[j]) == int(mc.n_overturned)
    err = float(ds.peak_rel_error.sel(comparison="sl_vs_coupled", quantity="var_theta")[j])
    assert err == pytest.approx(peak_relative_error(sl["var_theta"], mc.var_theta.values), rel=1e-12)
    tavg = float(ds.time_avg_rel_error.sel(comparison="sl_vs_coupled", quantity="var_theta")[j])
    assert tavg == pytest.approx(time_averaged_relative_error(sl["var_theta"], mc.var_theta.values, t))
    # the convergence study reuses the grid run at the grid's sample count and is its own reference there
    peak, _ = peak_with_se(mc.var_theta.values)
    assert float(ds.cv_peak_var_theta.sel(cv_model="coupled", n_samples=50)[0]) == pytest.approx(peak, rel=1e-12)
    assert float(ds.cv_deviation_vs_reference.sel(cv_model="coupled", n_samples=50)[0]) == 0.0
    assert float(ds.tol_change_vs_tightest.sel(cv_model="coupled", rtol_factor=1.0)[0]) == 0.0


def test_units_and_long_names_come_from_the_one_schema(tiny_run):
    from screening.solvers.schema import TRADEOFF, attributes

    _, ds, _, _ = tiny_run
    for name in ds.variables:
        declared = attributes(name, TRADEOFF)
        for key in ("units", "long_name"):
            assert ds[name].attrs.get(key) == declared.get(key), (name, key)
    assert ds.sl_status.attrs["flag_meanings"].split() == ["ok", "k_eq_negative", "sigma_theta_beyond_slenderness",
                                                           "step_budget_exhausted", "non_finite_moments",
                                                           "beyond_float_range"]
    assert ds.cost.attrs["note"].startswith("sl: median of 1 single-point")       # per-run notes are kept


CHECKER = Path(sys.executable).parent / "compliance-checker"


@pytest.mark.skipif(not CHECKER.exists(), reason="IOOS compliance-checker is not installed")
def test_result_file_passes_cf18_strict(tiny_run):
    _, _, paths, _ = tiny_run
    proc = subprocess.run([str(CHECKER), "--test=cf:1.8", "--criteria=strict", str(paths["nc"])],
                          capture_output=True, text=True, timeout=300)
    report = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "All tests passed!" in proc.stdout, report
    assert "exceptions occurred" not in report, report


def test_rerender_from_netcdf_and_bad_files_write_nothing(tiny_run):
    d, ds, paths, _ = tiny_run
    paths["md"].unlink()
    saved, written, rules = to.rerender_reports(d / "tiny.toml", d / "out")
    out = summary_text(load_tradeoff_study(d / "tiny.toml"), saved, rules)
    assert "Recommended: " in out and "SL : condensed : coupled = 1 :" in out
    assert paths["md"].exists() and "nc" not in written
    bad = d / "bad.toml"
    bad.write_text(TINY.replace("[mcs]", "[mcs]\nbogus = 1"))
    with pytest.raises(StudyError, match=r"bad\.toml: mcs\.bogus: unknown key"):
        to.run_tradeoff(bad, d / "out2", progress=None)
    assert not (d / "out2").exists()
    with pytest.raises(FileNotFoundError, match="does not exist"):
        to.rerender_reports(d / "tiny.toml", d / "nowhere")


def test_reports_are_never_written_through_planted_links(tiny_run, tmp_path):
    """The .nc, .md and .csv of a trade study: a new file beside each and a rename (screening.core.atomicfile)."""
    d, ds, _, _ = tiny_run
    victim = tmp_path / "victim.txt"
    victim.write_text("precious")
    out = tmp_path / "out"
    out.mkdir()
    for suffix in (".nc", ".md", ".csv"):
        (out / f"tiny{suffix}").symlink_to(victim)
    paths, _ = to.write_reports(load_tradeoff_study(d / "tiny.toml"), ds.copy(), out, "tiny")
    assert victim.read_text() == "precious"
    for key in ("nc", "md", "csv"):
        assert paths[key].is_file() and not paths[key].is_symlink() and paths[key].stat().st_size > 0
