"""The name -> model registry every model axis shares (screening.core.registry) and the registries of the
axes built on it (condensations, contact laws, excitations)."""

import pickle

import pytest

from screening.core.registry import NamedModel, Registry


class _Toy(NamedModel):
    axis = "toy"

    def __init__(self, name, value):
        self.name, self.value = name, value


def test_a_registry_resolves_names_in_order_and_refuses_others_naming_its_parameter():
    reg = Registry("toy", is_model=lambda x: isinstance(x, _Toy))
    a, b = reg.add("a", _Toy("a", 1)), reg.add("b", _Toy("b", 2))
    assert reg.names() == ("a", "b") and reg.values() == (a, b) and reg.get("b") is b
    other = _Toy("c", 3)
    assert reg.get(other) is other                          # a model object passes as it is
    with pytest.raises(ValueError, match=r"^parameter 'toy' must be one of \('a', 'b'\) \(got 'c'\)$"):
        reg.get("c")
    reg.remove("a")
    assert reg.names() == ("b",)


def test_named_models_are_equal_by_class_and_state_so_a_copy_sent_to_a_worker_equals_the_original():
    toy = _Toy("a", 1)
    copy = pickle.loads(pickle.dumps(toy))
    assert copy == toy and hash(copy) == hash(toy) and repr(toy) == "<toy 'a'>"
    assert _Toy("a", 2) != toy


@pytest.mark.parametrize("module, parameter, builtin", [
    ("screening.core.condensation.registry", "condensation", "paper"),
    ("screening.core.laws.registry", "law", "winkler"),
])
def test_each_model_axis_resolves_its_builtin_once_and_refuses_an_unknown_name(module, parameter, builtin):
    import importlib

    reg = importlib.import_module(module)
    model = reg.get(builtin)
    assert model.name == builtin and reg.get(model) is model and builtin in reg.names()
    with pytest.raises(ValueError, match=f"^parameter '{parameter}' must be one of"):
        reg.get("no_such_model")


def test_the_excitation_registry_turns_a_kind_into_its_class_and_builds_it():
    from screening.core.excitations import registry
    from screening.core.model.excitation import ConstantEnvelope

    cls = registry.get("kanai_tajimi")
    assert cls.kind == "kanai_tajimi" and set(cls.parameters) <= set(registry.parameters())
    params = {"omega_g": 15.0, "zeta_g": 0.6}
    built = registry.build("kanai_tajimi", 0.01, params, ConstantEnvelope())
    assert isinstance(built, cls) and built.S0 == 0.01
    with pytest.raises(ValueError, match="^parameter 'kind' must be one of"):
        registry.get("pink")
    with pytest.raises(TypeError, match="Excitation subclass"):
        registry.register(int)
