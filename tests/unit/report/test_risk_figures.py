"""The risk figure: one bar per object and limit state in the order given (ranked), none for a row without a
rate, and the share from outside the vouched range written beside its bar."""

import math

import numpy as np

import screening.report.risk_figures as rf


def _row(name, rate, share, note=""):
    return {"object": name, "limit_state": "overturn", "annual_rate": rate, "annual_rate_low": rate / 2,
            "annual_rate_high": rate * 2, "annual_rate_se": rate / 10, "share_outside_vouched": share, "note": note}


def test_bars_follow_the_ranking_and_say_the_share_outside(tmp_path, monkeypatch):
    drawn = {}
    monkeypatch.setattr(rf, "save_figure", lambda fig, path: drawn.setdefault("fig", fig))
    rows = [_row("vase", 3e-3, 0.25), _row("bust", 1e-3, 0.0, note="untrusted"), _row("lamp", math.nan, math.nan)]
    rf.plot_risk(rows, tmp_path / "r.png", years=50)
    ax = drawn["fig"].axes[0]
    assert [t.get_text() for t in ax.get_yticklabels()] == ["vase  overturn", "bust  overturn"]
    texts = [t.get_text() for t in ax.texts]
    assert any("25 % from outside the vouched range" in t for t in texts)
    assert any(t.startswith(f"P(50 yr) = {-np.expm1(-3e-3 * 50):.2g}") for t in texts)


def test_nothing_to_draw_returns_none(tmp_path):
    assert rf.plot_risk([_row("lamp", math.nan, math.nan)], tmp_path / "r.png") is None
    assert not (tmp_path / "r.png").exists()
