"""Stiff and extreme settings: unconditional stability, near incompressibility, thin
domes, many harmonics. The figures come from :mod:`reports.stability_study`, which the report's
stability section prints as well.
"""

import dataclasses

import numpy as np
import pytest

from cases import get_case
from reports import stability_study as study
from reports.stability_study import AGREEMENT_LIMIT, ENERGY_DRIFT_LIMIT
from smfem.runs.registry import REF2D, REF3D, SMFEM


def assert_conservative(rows):
    for r in rows:
        assert r["finite"], r
        assert r["energy_drift"] < ENERGY_DRIFT_LIMIT, r
        assert r["strain_energy_max"] <= 1 + ENERGY_DRIFT_LIMIT, r  # bounded by the initial energy


@pytest.mark.parametrize("name", ["thick_cylinder", "dome"])
def test_free_vibration_is_stable_far_beyond_the_explicit_limit(name):
    """dt = 1, 10 and 100 dt_cr, 10^4 steps each, every mode excited.

    Measured: thick cylinder (6 modes, 352 dof) dt_cr = 1.29e-5 s (the paper's dt is 3.1 dt_cr),
    drift 2.8e-13 / 1.5e-13 / 1.2e-13; dome (195 dof) dt_cr = 4.27e-7 s (the paper's dt is
    11.7 dt_cr), drift 3.2e-12 / 1.0e-12 / 9.5e-13.
    """
    rows = study.free_vibration(name)
    assert [r["factor"] for r in rows] == [1, 10, 100] and all(r["n_steps"] == 10_000 for r in rows)
    assert_conservative(rows)
    assert rows[-1]["dt"] > 2 * get_case(name).dt  # the range covers the paper's step and beyond


def test_explicit_limit_is_that_of_the_smallest_element():
    """dt_cr = 2 / omega_max must shrink in proportion to the element size (refine 1 -> 2)."""
    coarse, _ = study.explicit_limit(get_case("thick_cylinder"))
    fine, omegas = study.explicit_limit(get_case("thick_cylinder", {"refine": 2}))
    assert fine / coarse == pytest.approx(0.5, rel=0.05)
    assert len(omegas) == 6


def test_free_vibration_with_200_harmonics_at_100_dt_cr():
    """51 modes up to l = 198, whose hoop wavelength is shorter than an element: dt_cr =
    2.1e-6 s (the paper's dt is 19 dt_cr). Measured drift 5.0e-13."""
    rows = study.free_vibration("thick_cylinder", {"harmonics": 200}, factors=(100,))
    assert rows[0]["modes"] == 51
    assert_conservative(rows)


@pytest.mark.slow
def test_free_vibration_with_200_harmonics_at_every_factor():
    """Measured drift 1.9e-12 / 3.7e-13 / 5.0e-13 at 1 / 10 / 100 dt_cr."""
    assert_conservative(study.free_vibration("thick_cylinder", {"harmonics": 200}))


@pytest.fixture(scope="module")
def incompressible():
    return study.incompressibility()


def test_near_incompressible_lame_within_two_percent(incompressible):
    """nu = 0.49, 0.499, 0.4999 on the paper mesh. Measured: SMFEM 0.090 / 0.092 / 0.092 %;
    reference 2D 0.0006 / 0.005 / 0.054 %, 3D 0.007 / 0.065 / 0.65 % (the quadratic hexahedron
    stiffens like 1 / (1 - 2 nu), still far inside 2 %)."""
    assert [r["nu"] for r in incompressible] == [0.49, 0.499, 0.4999]
    for r in incompressible:
        for solver in (SMFEM, REF2D, REF3D):
            assert r[solver] < AGREEMENT_LIMIT, (r["nu"], solver, r[solver])
    smfem = [r["smfem"] for r in incompressible]
    assert max(smfem) < 0.001 and max(smfem) - min(smfem) < 5e-5  # no trend towards nu = 1/2


def test_the_element_locked_while_the_free_gradients_were_held_at_zero(incompressible):
    """The cause of the locking the fix removed: held at zero, the normal strain that the moment
    scheme does not let vary (e11 along xi) made the gradient of the volumetric strain a second
    constraint per element, weighted by lambda ~ 1 / (1 - 2 nu). Measured: 1.2 / 10 / 54 %."""
    held = [r["smfem_gradients_held"] for r in incompressible]
    assert held[0] < 0.02 < held[1] < held[2] and held[2] > 0.5
    assert held[1] / held[0] > 5  # locking grows like lambda


def test_near_incompressible_patch_load_against_the_reference():
    """The non-axisymmetric harmonics (l = 2, 6, ...) lock no more than l = 0: the partial
    pressure of the case, static, nu = 0.4999. Measured: A 0.05 %, B 0.04 %, C 0.02 %."""
    sets = {"nu": 0.4999, "refine": 2}
    smfem = study.static_probes(get_case("thick_cylinder", dict(sets, harmonics=80)))
    reference = study.reference_static_probes(get_case("thick_cylinder", sets))
    for probe, value in smfem.items():
        assert value == pytest.approx(reference[probe], rel=0.005), probe


@pytest.fixture(scope="module")
def thin_domes():
    return {r["R_over_h"]: r for r in study.thin_dome()}


def test_thin_dome_reference_and_fine_smfem_agree_up_to_r_over_h_1000(thin_domes):
    """Both solvers converge to the same apex deflection (SMFEM 4 x 640 and the reference 4 x 160:
    within 0.01 %): no loss to
    conditioning at R/h = 1000 (cond(K) of the 4 x 20 SMFEM system: 2.6e9). The reference's
    quadratic elements are within 0.7 % at 4 x 20."""
    for r in thin_domes.values():
        assert abs(r["smfem_converged"]) < 2e-4, r
        assert r["cond_4x20"] < 1e10, r
        assert abs(r["reference_4x20"]) < 0.01, r


def test_thin_dome_paper_mesh_meets_two_percent_up_to_r_over_h_100(thin_domes):
    """SMFEM 4 x 20 against the reference. Measured: R/h = 54.3: 0.87 %, 100: 1.2 %; beyond,
    the 2 % is missed: 200: 2.8 %, 543: 7.3 %, 1000: 12.6 %."""
    for ratio, r in thin_domes.items():
        if ratio <= 100:
            assert abs(r["smfem_4x20"]) < AGREEMENT_LIMIT, r
        else:
            assert abs(r["smfem_4x20"]) > AGREEMENT_LIMIT, r


def test_thin_dome_error_is_the_unresolved_edge_layer(thin_domes):
    """Why 4 x 20 misses 2 % beyond R/h ~ 150: the clamped edge's bending layer, of width
    l = sqrt(R h) / (3 (1 - nu^2))^(1/4), holds 4.5 meridian elements at R/h = 54 and 1.06 at
    R/h = 1000. The error is a function of the elements per layer alone: error x (l / ds)^2 is
    the same constant (0.13-0.18) for every thickness (second-order convergence of a smooth
    layer). It is not locking: 1, 4 or 8 elements through the thickness give the same error.
    Three elements per layer (meridian counts 14, 18, 26, 42, 57) meet 2 % at every R/h:
    measured 1.6 / 1.5 / 1.7 / 1.8 / 1.9 %."""
    for r in thin_domes.values():
        assert 0.12 < abs(r["smfem_4x20"]) * r["elements_per_layer_4x20"] ** 2 < 0.2, r
        assert abs(r["smfem_8x20"] - r["smfem_4x20"]) < 0.002, r
        assert abs(r["smfem_1x20"] - r["smfem_4x20"]) < 0.004, r
        assert abs(r["smfem_4x_needed"]) < AGREEMENT_LIMIT, r
    assert [r["meridian_needed"] for r in thin_domes.values()] == [14, 18, 26, 42, 57]


def test_thin_dome_quadratic_element_meets_two_percent_on_the_paper_mesh(thin_domes):
    """The quadratic element (quad9) on the paper's 4 x 20, where the bilinear one misses 2 %
    beyond R/h ~ 150: measured 0.10 / 0.086 / 0.17 / 0.44 / 0.67 % at R/h = 54 ... 1000."""
    for r in thin_domes.values():
        assert abs(r["smfem_quad9_4x20"]) < 0.01 and abs(r["smfem_quad9_4x20"]) < abs(r["smfem_4x20"]) / 5, r


@pytest.fixture(scope="module")
def harmonics():
    return {r["harmonics"]: r for r in study.many_harmonics()}


def test_200_harmonics_are_accurate_and_stable(harmonics):
    """Thick cylinder, refine 2, the paper's dt (19.7 dt_cr of the 200-term system): 51 modes
    computed, up to l = 198. Measured against 80 terms: A 0.008 %, B 0.29 %, C 0.0 %; against
    the reference (refine 2): A 0.32 %, B 1.0 %, C 0.18 %."""
    r = harmonics[200]
    assert r["finite"] and r["modes"] == 51 and r["dt_over_dt_cr"] > 10
    for probe in ("A_ur", "B_ut", "C_ur"):
        assert r[f"{probe}_vs_80"] < 0.005, (probe, r)
        assert r[f"{probe}_vs_reference"] < AGREEMENT_LIMIT, (probe, r)
    # 20 terms are not enough for B_ut on the patch edge (measured 2.0 % off 80 terms)
    assert harmonics[20]["B_ut_vs_80"] > 5 * r["B_ut_vs_80"]


def test_modes_and_dof_grow_linearly_with_the_harmonics(harmonics):
    """Only the loaded harmonics (l = 0 and l = 2 mod 4) are computed: a quarter of the terms,
    each adding the same number of dof (benchmarks/harmonics_cost.py measures the time)."""
    modes = [r["modes"] for r in harmonics.values()]
    dof = [r["n_dof"] for r in harmonics.values()]
    assert modes == [6, 21, 51]
    assert (dof[2] - dof[1]) / (modes[2] - modes[1]) == (dof[1] - dof[0]) / (modes[1] - modes[0])


@pytest.mark.slow
def test_stability_table_for_the_report():
    rows = study.stability_table()
    assert {r["check"] for r in rows} >= {"unconditional stability", "near incompressibility", "thin dome",
                                          "many harmonics", "bad input"}
    expected_failures = [r for r in rows if not r["passed"]]
    for r in expected_failures:  # the documented limits: the element before the fix, 4 x 20 beyond R/h ~ 150
        assert "before the fix" in r["setting"] or "4 x 20" in r["setting"], r
    assert len(expected_failures) == 2 + 3


def test_material_contrast_1e2_to_1e10_converges_and_reports_iterations():
    # measured (t_end 12 ms): iterations mean/max 2.52/4, 2.82/5, 3.26/6, 3.60/8, 3.58/8 for
    # contrast 1e-2 ... 1e-10; change against 1e-8: 5.4 %, 0.25 %, 0.11 %, 0, 0.13 %
    from reports.stability_study import contrast_sweep

    rows = contrast_sweep()
    assert [r["contrast"] for r in rows] == [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]
    for r in rows:
        assert r["converged"] and r["finite"] and r["iterations_max"] <= 20
        if r["contrast"] <= 1e-4:
            assert r["change_vs_1e-8"] < 0.005


def test_contact_at_100_times_v0_with_friction_0_to_1_stays_out_of_the_wall():
    # measured: SMFEM layer compressed 0.15 of its thickness; reference penetration < 1e-18 m
    from reports.stability_study import contact_extremes

    for r in contact_extremes():
        assert r["converged"] and r["finite"], r
        assert 0 <= r["into_wall"] < r["into_wall_limit"], r
