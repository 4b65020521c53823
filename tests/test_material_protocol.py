"""The material law extension point: both solvers' laws have the shape of cases.law.MaterialLaw,
agree on a uniaxial strain path, a law registered in a solver's table is what its runs use, and
an unknown law is refused when the model is built (docs/architecture.md)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from cases import get_case
from cases.law import LinearisedLaw, MaterialLaw
from cases.material import ELASTIC, VON_MISES, Material, lame
from cases.params import UnsupportedCase
from reference_fem import laws as reference_laws
from smfem import laws as smfem_laws

E, NU, SY = 2.1e11, 0.3, 2.5e8
PROTOCOL = [m for m in vars(MaterialLaw) if not m.startswith("_")] + ["name", "nonlinear"]


def _material(plastic: bool, E_T: float = 0.0) -> Material:
    return Material(E, NU, 7.8e3, SY / np.sqrt(3.0), E_T=E_T, plastic=plastic)


def _renamed(material: Material, law: str) -> Material:
    """The same constants under another law's name (a new law's data is its own dataclass)."""
    named = dataclasses.make_dataclass("Named", [], bases=(Material,), frozen=True,
                                       namespace={"law": property(lambda self: law)})
    return named(**dataclasses.asdict(material))


# each solver's law at one point, in its own vectors: SMFEM's rows first (6, 1), the reference's
# points first (1, 6) (3D Mandel: the normal components are the same as Voigt's)
SOLVERS = {"smfem": (lambda m: smfem_laws.get(m), lambda v: v.reshape(6, 1), lambda s: s[:, 0]),
           "reference": (lambda m: reference_laws.get(m, 3), lambda v: v.reshape(1, 6), lambda s: s[0])}


def _uniaxial(solver: str, material: Material, strains) -> np.ndarray:
    """(sigma11, sigma22, peps) per strain of a uniaxial strain path, the state committed each step."""
    make, vector, point = SOLVERS[solver]
    law = make(material)
    state, previous, out = law.initial_state(1), 0.0, []
    for e in strains:
        d = np.zeros(6)
        d[0], previous = e - previous, e
        sigma, state = law.stress(law.trial(vector(d), state), state)
        out.append((*point(sigma)[:2], law.equivalent_plastic_strain(state)[0]))
    return np.array(out)


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("plastic", [False, True])
def test_each_solvers_laws_have_the_protocols_shape(solver, plastic):
    material = _material(plastic)
    law = SOLVERS[solver][0](material)
    assert all(hasattr(law, m) for m in PROTOCOL)
    assert law.name == material.law == (VON_MISES if plastic else ELASTIC) and law.nonlinear == plastic
    assert law.elastic_matrix().shape == (6, 6)
    lam, mu = lame(E, NU)
    assert law.elastic_matrix()[0, 0] == pytest.approx(lam + 2 * mu) and law.elastic_matrix()[0, 1] == pytest.approx(lam)
    state = law.initial_state(5)
    assert state.sigma.size == 30 and not len(np.flatnonzero(state.yielding))
    assert law.equivalent_plastic_strain(state).shape == (5,)
    if solver == "reference":
        assert all(hasattr(law, m) for m in vars(LinearisedLaw) if not m.startswith("_"))


@pytest.mark.parametrize("H", [0.0, 2.0e9])
@pytest.mark.parametrize("steps", [1, 40])
def test_both_solvers_laws_give_the_same_uniaxial_strain_response(H, steps):
    """Uniaxial strain to 8 times the yield strain through each law's trial and stress: the
    same stresses and plastic strain (and past yield, the closed form's stress difference)."""
    E_T = H * E / (E + H)  # H = E E_T / (E - E_T)
    material = _material(True, E_T)
    lam, mu = lame(E, NU)
    strains = np.linspace(0, 8 * SY / (2 * mu), steps + 1)[1:]
    smfem, reference = (_uniaxial(s, material, strains) for s in SOLVERS)
    assert np.allclose(smfem[:, :2], reference[:, :2], rtol=1e-12, atol=1e-12 * SY)
    assert np.allclose(smfem[:, 2], reference[:, 2], rtol=1e-12, atol=1e-15)
    assert smfem[-1, 0] - smfem[-1, 1] == pytest.approx(SY + H * _alpha(strains[-1], mu, H), rel=1e-12)
    elastic = _uniaxial("smfem", _material(False), strains)
    assert np.allclose(elastic[:, 0], (lam + 2 * mu) * strains, rtol=1e-12) and not elastic[:, 2].any()


def _alpha(eps: float, mu: float, H: float) -> float:
    """Accumulated plastic strain of uniaxial strain eps past yield: (2/3)(eps - eps_y) 3 mu / (3 mu + H)."""
    return (2 / 3) * (eps - SY / (2 * mu)) * 3 * mu / (3 * mu + H)


class _SmfemToy(smfem_laws.Elastic):
    """Elasticity under another name, through the nonlinear path (the additional-loads iterations)."""

    name, nonlinear, used = "toy-elastic", True, 0

    def stress(self, trial, state):
        type(self).used += 1
        return super().stress(trial, state)


class _ReferenceToy(reference_laws.Elastic):
    """Elasticity under another name, through Newton."""

    name, nonlinear, used = "toy-elastic", True, 0

    def stress(self, strain, state, tangent=True):
        type(self).used += 1
        return super().stress(strain, state)


@pytest.mark.parametrize("solver", ["smfem", "reference"])
def test_a_law_registered_in_a_solvers_table_is_what_its_run_uses(solver, monkeypatch):
    """The elastic thick cylinder with its material under a toy law's name, the toy registered:
    the run calls it and gives the default elastic run's histories."""
    from smfem.runs.registry import REFERENCE, SMFEM, solve

    laws, toy, key = (smfem_laws, _SmfemToy, SMFEM) if solver == "smfem" else (reference_laws, _ReferenceToy, REFERENCE)
    monkeypatch.setitem(laws.LAWS, toy.name, toy)
    monkeypatch.setattr(toy, "used", 0)
    case = get_case("thick_cylinder", {"t_end": 8e-4} if solver == "smfem" else {"t_end": 4e-4})
    assert case.material.law == ELASTIC
    default = solve(key, case, fields=False)
    renamed = solve(key, dataclasses.replace(case, material=_renamed(case.material, toy.name)), fields=False)
    assert toy.used > 0
    for name in default.history:
        a, b = np.asarray(default.history[name]), np.asarray(renamed.history[name])
        assert np.allclose(a, b, rtol=1e-8, atol=1e-8 * np.abs(a).max()), name


@pytest.mark.parametrize("where", ["smfem", "reference", "calculix"])
def test_an_unknown_law_is_refused_with_one_clear_line_when_the_model_is_built(where, monkeypatch):
    """Each solver's table refuses it; the deck's cards too, for a law the reference knows."""
    case = get_case("thick_cylinder")
    case = dataclasses.replace(case, material=_renamed(case.material, "mohr-coulomb"))
    if where == "smfem":
        from smfem.model import Model
    elif where == "reference":
        from reference_fem.model import Model
    else:
        from reference_fem.calculix.deck import build_deck as Model
        monkeypatch.setitem(reference_laws.LAWS, "mohr-coulomb", reference_laws.Elastic)
    with pytest.raises(UnsupportedCase) as error:
        Model(case)
    message = str(error.value)
    assert "'mohr-coulomb'" in message and "\n" not in message and VON_MISES in message
    assert message.startswith({"smfem": "smfem", "reference": "reference", "calculix": "calculix"}[where])
