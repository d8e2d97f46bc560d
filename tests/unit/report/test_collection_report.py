"""The collection's HTML report (screening.report.collection_report): ranked as the risk table ranks, every object
with its curves and points, self-contained (no external file or address)."""

import base64
import re
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from screening.applications.risk import HazardCurve, limit_state_fragilities, risk_table
from screening.report.collection_report import report_objects, write_report

MUSEUM = Path(__file__).resolve().parents[2] / "data" / "report" / "museum.nc"


@pytest.fixture(scope="module")
def museum():
    with xr.open_dataset(MUSEUM) as ds:
        ds = ds.load()
    thresholds = ds["threshold"].values.tolist()
    return ds, limit_state_fragilities(ds, "pga", None, thresholds, ds["p_exceed"].attrs["relative_to"])


def _curve():
    x = np.geomspace(0.005, 3.0, 30)                   # g
    return HazardCurve("PGA", "g", x, 1e-4 * x**-2.0, "power law")


def test_ranked_by_median_capacity_without_hazard_and_by_annual_rate_with_it(museum):
    ds, frags = museum
    by_median = report_objects(ds, frags)
    medians = [o["curves"][0][2]["median"] if o["curves"][0][2]["flag"] == 0 else np.inf for o in by_median]
    assert medians == sorted(medians) and {o["name"] for o in by_median} == set(ds["case_name"].values.tolist())
    rows = risk_table(frags[0], _curve(), 50.0)
    by_risk = [o["name"] for o in report_objects(ds, frags, rows)]
    rated = [r["object"] for r in rows if np.isfinite(r["annual_rate"])]       # risk_table ranks highest first
    assert by_risk[:len(rated)] == rated


def test_the_page_is_self_contained_and_names_every_object_source_and_input(museum, tmp_path):
    ds, frags = museum
    out = tmp_path / "r.html"
    objects = write_report(ds, out, "museum.nc", _curve(), 50.0, frags)
    page = out.read_text()
    assert not re.search(r"""(src|href)=['"]?(https?:|//|file:)""", page)        # nothing fetched from elsewhere
    images = re.findall(r"src='data:image/png;base64,([A-Za-z0-9+/=]+)'", page)
    assert len(images) == len(objects) == ds.sizes["case"]
    assert all(base64.b64decode(i)[:4] == b"\x89PNG" for i in images)
    for name in ds["case_name"].values:
        assert f"<h3>{name}</h3>" in page
    meanings = ds["p_source"].attrs["flag_meanings"].split()
    used = {meanings[list(ds["p_source"].attrs["flag_values"]).index(v)] for v in np.unique(ds["p_source"].values)}
    assert all(f"<td>{m}</td>" in page for m in used)                            # which model answered each point
    assert ds.attrs["study_text"].splitlines()[0].replace('"', "&quot;") in page  # the inputs
    assert page.index(f"<h3>{objects[0]['name']}</h3>") < page.index(f"<h3>{objects[-1]['name']}</h3>")
