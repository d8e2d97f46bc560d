"""With 15 or 50 objects the fragility figure draws one panel per case, titled with its name, instead of eight
curves under one legend (issue #35 item 6)."""

import numpy as np
import pytest
import xarray as xr
from scipy.special import ndtr

import screening.report.fragility_figures as ff


def _frag(n):
    pga = np.geomspace(0.5, 8, 7)
    med, beta = np.geomspace(1, 5, n), np.linspace(0.2, 0.6, n)
    p = ndtr(np.log(pga[None, :] / med[:, None]) / beta[:, None])
    return xr.Dataset({"p_exceed": (("case", "pga"), p), "fit_median": ("case", med), "beta": ("case", beta),
                       "fit_flag": ("case", np.zeros(n, np.int8)),
                       "fit_n_unvouched": ("case", (np.arange(n) % 5 == 0).astype(np.int32))},
                      coords={"case": np.arange(n), "case_name": ("case", [f"object_{i:02d}" for i in range(n)]),
                              "pga": ("pga", pga, {"units": "m s-2"})},
                      attrs={"threshold": 0.1, "relative_to": "slenderness", "method": "vanmarcke"})


@pytest.mark.parametrize("n", [15, 50])
def test_one_panel_per_case_with_its_name_and_fit(tmp_path, monkeypatch, n):
    drawn = {}
    monkeypatch.setattr(ff, "save_figure", lambda fig, path: drawn.setdefault("fig", fig))
    assert ff.plot_fragility(_frag(n), "pga", tmp_path / "f.png") == tmp_path / "f.png"
    panels = [ax for ax in drawn["fig"].axes if ax.get_visible()]
    assert [ax.get_title() for ax in panels] == [f"object_{i:02d}" for i in range(n)]
    # each panel names its own fit, those with points left out say how many; nothing else crowds the legend
    labels = [[t.get_text() for t in ax.get_legend().get_texts()] for ax in panels]
    assert all(len(lab) == 1 and lab[0].startswith("median ") for lab in labels)
    assert sum("left out]" in lab[0] for lab in labels) == len(range(0, n, 5))


def test_few_cases_keep_one_panel(tmp_path, monkeypatch):
    drawn = {}
    monkeypatch.setattr(ff, "save_figure", lambda fig, path: drawn.setdefault("fig", fig))
    ff.plot_fragility(_frag(ff.PANEL_CASES - 1), "pga", tmp_path / "f.png")
    assert len(drawn["fig"].axes) == 1
