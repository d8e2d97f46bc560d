"""Where the default condensation stops (``k_eq_negative``: the block topples), the user is told at
every level: the status in the result, the printed status line of ``screening run``, the trust label
and the ``[accuracy]`` best estimate (Monte Carlo or ``unreliable``, never the linearization)."""

import numpy as np
import xarray as xr
from helpers import study_text

from screening.cli import main
from screening.core.condensation import DEFAULT_CONDENSATION
from screening.core.status import BestMethod, PointStatus, Trust

# the paper's block on a hardening bed, no condensation chosen; at S0 = 2.4e-3 the default's k_eq
# turns negative during the shaking (the quick study's strongest column), at 1e-5 it barely rocks
STUDY = study_text({"title": '"default condensation, a stopped point"', "eps": "6e7", "S0": "[1e-5, 2.4e-3]",
                    "t_end": "20.0"}, append="[accuracy]\ntarget = 0.15\nbudget_s = 2\n")


def test_a_stopped_default_point_is_flagged_untrusted_and_never_a_linearization_estimate(tmp_path, capsys):
    (tmp_path / "s.toml").write_text(STUDY)
    out = tmp_path / "r.nc"
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(out), "--quiet", "--no-plots"]) == 0
    line = [x for x in capsys.readouterr().err.splitlines() if x.startswith(f"wrote {out}: 2 points")]
    assert len(line) == 1 and "(status: ok 1, k_eq_negative 1;" in line[0] and "untrusted 1" in line[0]
    with xr.open_dataset(out) as ds:
        assert ds.attrs["condensation"] == DEFAULT_CONDENSATION
        status, trust = ds["status"].values, ds["sl_trust"].values
        np.testing.assert_array_equal(status, [PointStatus.ok, PointStatus.k_eq_negative])
        assert trust[1] == Trust.untrusted
        assert np.isnan(ds["sl_error_low"].values[1]) and np.isnan(ds["sl_error_high"].values[1])
        assert np.isnan(ds["var_theta"].values[1, -1]) and 0.0 < float(ds["t_stop"].values[1]) < 20.0
        method = ds["best_method"].values[1]
        assert method in (BestMethod.coupled_monte_carlo, BestMethod.condensed_monte_carlo, BestMethod.unreliable)
        if method == BestMethod.unreliable:               # nothing vouches for a number: no standard error
            assert np.isnan(ds["best_peak_var_theta_se"].values[1])
        else:                                             # the Monte Carlo that ran there
            at = list(ds["esc_grid_index"].values).index(1)
            assert float(ds["best_peak_var_theta"].values[1]) == float(ds["esc_peak_var_theta"].values[at])
