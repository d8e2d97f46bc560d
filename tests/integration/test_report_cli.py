"""``screening report``: a collection's result (and a site's hazard curve) in, one self-contained HTML page out,
rendered by a real browser (headless Chromium, skipped where it is absent); bad input is one line naming the
file, exit 2, nothing written."""

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from matplotlib import image

from screening.cli import main

MUSEUM = Path(__file__).resolve().parents[1] / "data" / "report" / "museum.nc"
CHROMIUM = next((shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome") if shutil.which(n)), None)


def _hazard(tmp_path, header="PGA [g], annual_rate [1/yr]", slope=-2.0):
    x = np.geomspace(0.005, 3.0, 30)
    path = tmp_path / "hazard.csv"
    path.write_text(header + "\n" + "".join(f"{a:g}, {1e-4 * a**slope:g}\n" for a in x))
    return path


def test_report_ranks_the_collection_at_the_site(tmp_path, capsys):
    out = tmp_path / "museum_report.html"
    assert main(["report", str(MUSEUM), "--hazard", str(_hazard(tmp_path)), "--out", str(out)]) == 0
    page = out.read_text()
    assert "Ranked by the annual frequency of overturn" in page and page.count("data:image/png;base64,") >= 4
    assert "highest risk:" in capsys.readouterr().err
    risk = tmp_path / "risk.csv"                       # the same ranking as `screening risk`
    assert main(["risk", str(MUSEUM), "--hazard", str(_hazard(tmp_path)), "--out", str(risk)]) == 0
    first = next(line.split(",") for line in risk.read_text().splitlines()[1:] if "overturn" in line)
    assert re.search(r"<h3>(.*?)</h3>", page).group(1) in first          # the first object shown


def test_report_without_hazard_ranks_by_median_capacity(tmp_path):
    out = tmp_path / "r.html"
    assert main(["report", str(MUSEUM), "--out", str(out)]) == 0
    assert "Ranked by median capacity" in out.read_text()


@pytest.mark.parametrize("args, where", [
    (["missing.nc"], "missing.nc"),
    ([str(MUSEUM), "--hazard", "HAZARD_UP"], "hazard.csv:3: annual_rate [1/yr]: the hazard curve is not decreasing"),
    ([str(MUSEUM), "--hazard", "HAZARD_SA"], "hazard.csv:1: imt: the hazard curve is for SA(0.3)"),
])
def test_bad_input_is_one_line_naming_the_file_exit_2_nothing_written(tmp_path, capsys, args, where):
    args = [str(_hazard(tmp_path, slope=2.0)) if a == "HAZARD_UP" else
            str(_hazard(tmp_path, header="SA(0.3) [g], annual_rate [1/yr]")) if a == "HAZARD_SA" else
            str(tmp_path / a) if a == "missing.nc" else a for a in args]
    out = tmp_path / "r.html"
    assert main(["report", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and where in err, err
    assert not out.exists()


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium (apt-get install chromium)")
def test_the_page_renders_in_headless_chromium(tmp_path):
    """The browser draws the page with its embedded figures: the screenshot is not blank, and the page is taller
    than one screen of tables (the figures have a height)."""
    page = tmp_path / "r.html"
    assert main(["report", str(MUSEUM), "--hazard", str(_hazard(tmp_path)), "--out", str(page)]) == 0
    shot = tmp_path / "shot.png"
    run = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                          "--window-size=1280,2400", f"--screenshot={shot}", page.as_uri()],
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0 and shot.exists(), run.stderr[-2000:]
    pixels = image.imread(shot)[..., :3]
    assert pixels.shape[:2] == (2400, 1280)
    dark = (pixels.mean(axis=-1) < 0.5).mean(axis=1)                  # dark pixels per row: text, lines, curves
    assert (dark > 0.005).mean() > 0.3                                  # drawn over most of the height
