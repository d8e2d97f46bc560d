"""Every CF attribute declared once (screening.solvers.schema): each sweep-grid variable of the output registry has its
units (a flag its values and meanings) and long name, the prefixed names (``spot_``, ``mcs_``) find their base declaration, ``apply_schema`` puts
the declarations on data variables and coordinates and keeps other attributes, and an undeclared name is refused."""

import pytest
import xarray as xr

from screening.solvers import schema
from screening.solvers.outputs import GRID_OUTPUTS


@pytest.mark.parametrize("output", GRID_OUTPUTS, ids=lambda o: o.name)
def test_every_sweep_grid_variable_is_declared_with_units_or_flags_and_a_long_name(output):
    """A flag carries ``flag_values`` and ``flag_meanings`` (one word per value), any other variable its units."""
    attrs = schema.attributes(output.name)
    assert attrs.get("long_name")
    if output.is_flag:
        assert len(attrs["flag_meanings"].split()) == len(attrs["flag_values"])
    else:
        assert attrs.get("units") is not None


def test_a_spot_parameter_is_the_parameter_at_the_spot_point():
    base, spot = schema.attributes("h"), schema.attributes("spot_h")
    assert spot["units"] == base["units"] == "m"
    assert spot["long_name"] == base["long_name"] + " at the spot point"


def test_a_table_given_is_tried_first_and_an_undeclared_name_is_refused():
    assert schema.attributes("k", table={"k": {"units": "kN m-2"}}) == {"units": "kN m-2"}
    with pytest.raises(KeyError, match="'no_such_thing' is not declared"):
        schema.attributes("no_such_thing")


def test_apply_schema_sets_the_declarations_keeps_other_attributes_and_adds_the_global_ones():
    ds = xr.Dataset({"theta_ul": ("h", [1e-3, 2e-3], {"units": "wrong", "comment": "mine"})},
                    coords={"h": ("h", [0.21, 0.3])})
    out = schema.apply_schema(ds, title="example")
    assert out["theta_ul"].attrs["units"] == schema.attributes("theta_ul")["units"]
    assert out["theta_ul"].attrs["comment"] == "mine"
    assert out["h"].attrs["units"] == "m"
    assert out.attrs["Conventions"] == schema.CONVENTIONS and out.attrs["title"] == "example"
    assert ds["theta_ul"].attrs["units"] == "wrong"                      # the input is left as it was
    with pytest.raises(KeyError, match="undeclared"):
        schema.apply_schema(xr.Dataset({"undeclared": ("x", [1.0])}))
