"""A collection CSV as the study's named cases: ``[collection] file`` or ``run --inventory``; bad tables refused
in one line naming the file, line and field (exit 2) before any work."""

import math

import pytest

from screening.analysis import beds
from screening.cli import main
from screening.sweep.study import StudyError, load_study

STUDY = """
title = "a collection"
[foundation]
contact = "hunt_crossley"
condensation = "paper"
k = 2.89e7
lam = 8.95e8
[excitation]
kind = "white"
pga = [1.0, 2.0]
[time]
t_end = 2.0
dt = 0.1
"""

OBJECTS = """# name, mass [kg], half-width [m], height of the centre of mass [m], depth [m], bed
name,m,b,h,depth,material,thickness,eps
bust-wood,8.67,0.035,0.21,0.1,,,-6e5
vase on pad,20,0.05,0.30,0.1,lime mortar,0.01,
clock,35,0.10,0.60,0.25,timber (across the grain),0.02,
"""


def _files(tmp_path, objects=OBJECTS, study=STUDY + '[collection]\nfile = "objects.csv"\n'):
    (tmp_path / "objects.csv").write_text(objects)
    path = tmp_path / "study.toml"
    path.write_text(study)
    return path


def test_collection_rows_become_named_cases_with_their_beds(tmp_path):
    study = load_study(_files(tmp_path))
    assert study.has_case_dim and [c.name for c in study.cases] == ["bust-wood", "vase on pad", "clock"]
    bust, vase, clock = study.cases
    assert bust.params["m"] == 8.67 and bust.params["eps"] == -6e5 and bust.params["k"] == 2.89e7   # study's k
    # a material: k = E_c depth / thickness at the middle of its ranges
    spec = beds.TYPICAL["lime mortar"]
    e_c = float(beds.oedometric_modulus(math.sqrt(spec["E"][0] * spec["E"][1]), sum(spec["nu"]) / 2))
    assert vase.params["k"] == pytest.approx(e_c * 0.1 / 0.01, rel=1e-12)
    assert vase.params["lam"] == pytest.approx(float(beds.lam_from_vertical_damping(
        vase.params["k"], 20.0, 0.05, sum(spec["zeta_v"]) / 2)), rel=1e-12)
    assert clock.params["h"] == 0.6 and clock.params["k"] < vase.params["k"]        # timber is softer than mortar


def test_inventory_option_replaces_the_collection_and_changes_the_hash(tmp_path):
    path = _files(tmp_path)
    first = load_study(path)
    other = tmp_path / "more.csv"
    other.write_text(OBJECTS.replace("8.67", "9.5"))
    second = load_study(path, inventory=other)
    assert second.cases[0].params["m"] == 9.5 and second.key != first.key     # a changed collection is a new study


@pytest.mark.parametrize("objects, where", [
    ("name,m,b,depth\nvase,1,0.1,0.1\n", "objects.csv:1: h: missing column"),
    ("name,m,b,h,depth\nvase,-2,0.1,0.3,0.1\n", "objects.csv:2: m: -2 must be > 0"),
    ("name,m,b,h,depth\nvase,2,0.1,0.3,0.1\nvase,2,0.1,0.3,0.1\n", "objects.csv:3: name: duplicate name 'vase'"),
    ("# objects\nname,m,b,h,depth\nvase,2,0.1,abc,0.1\n", "objects.csv:3: h: not a number ('abc')"),
    ("name,m,b,h,depth,material\nvase,2,0.1,0.3,0.1,granite\n", "objects.csv:2: material: unknown material 'granite'"),
    ("name,m,b,h,depth,colour\nvase,2,0.1,0.3,0.1,red\n", "objects.csv:1: colour: unknown column"),
])
def test_bad_collection_is_one_line_naming_file_line_and_field(tmp_path, objects, where):
    with pytest.raises(StudyError) as err:
        load_study(_files(tmp_path, objects))
    assert where in str(err.value) and "\n" not in str(err.value)


def test_run_with_a_bad_inventory_exits_2_before_any_work(tmp_path, capsys):
    path = _files(tmp_path, study=STUDY + "[block]\nm = 8.67\nb = 0.035\nh = 0.21\n")
    bad = tmp_path / "bad.csv"
    bad.write_text("name,m,b,h,depth\nvase,-2,0.1,0.3,0.1\n")
    out = tmp_path / "r.nc"
    assert main(["run", str(path), "--inventory", str(bad), "--out", str(out), "--workers", "0", "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "bad.csv:2: m: -2 must be > 0" in err and not out.exists()


def test_cases_and_a_collection_together_are_refused(tmp_path):
    study = STUDY + '[collection]\nfile = "objects.csv"\n[[case]]\nname = "x"\nblock.m = 1.0\n'
    with pytest.raises(StudyError, match="either as \\[\\[case\\]\\] tables or as a collection file"):
        load_study(_files(tmp_path, study=study))
