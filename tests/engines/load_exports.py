"""Load screening's fragility exports with the engines' own readers; print what they read as JSON.

Run by tests/integration/test_engine_exports.py with the Python of .venv-engines (pelicun, OpenQuake):
``python load_exports.py PELICUN_CSV NRML_XML``.  Nothing of screening is imported here.
"""

import json
import sys

import numpy as np


def pelicun_read(path):
    from pelicun import file_io
    from pelicun.assessment import Assessment

    data = file_io.load_data(path, None, orientation=1, reindex=False)
    ids = [str(i) for i in data.index]
    assessment = Assessment({"PrintLog": False, "Seed": 0})
    assessment.damage.load_model_parameters([path], cmp_set=set(ids))
    params = assessment.damage.ds_model.damage_params
    out = {}
    for cid in params.index:
        row = params.loc[cid]
        states = sorted({c[0] for c in params.columns if c[0].startswith("LS")})
        out[str(cid)] = {"incomplete": int(row[("Incomplete", "")]) if ("Incomplete", "") in params.columns else None,
                         "demand": str(row[("Demand", "Type")]),
                         "theta_0": [float(row[(s, "Theta_0")]) for s in states],
                         "theta_1": [float(row[(s, "Theta_1")]) for s in states]}
    return {"loaded_ids": ids, "damage_params": out}


def openquake_read(path):
    from openquake.hazardlib import nrml
    from openquake.risklib import read_nrml  # noqa: F401  (registers the fragilityModel converter)
    from openquake.risklib.scientific import FragilityFunctionContinuous

    model = nrml.to_python(path)
    functions = {}
    for (imt, fid), ffl in model.items():
        lo, hi = float(ffl.minIML), float(ffl.maxIML)
        curves = [FragilityFunctionContinuous(ls, float(m), float(s), lo, hi)
                  for ls, (m, s) in zip(model.limitStates, ffl.array)]
        grid = np.geomspace(lo, hi, 7)
        functions[fid] = {"imt": imt, "minIML": lo, "maxIML": hi, "grid": grid.tolist(),
                          "poes": [c(grid).tolist() for c in curves],
                          "mean": ffl.array[:, 0].tolist(), "stddev": ffl.array[:, 1].tolist()}
    return {"limit_states": list(model.limitStates), "functions": functions}


if __name__ == "__main__":
    print(json.dumps({"pelicun": pelicun_read(sys.argv[1]), "openquake": openquake_read(sys.argv[2])}))
