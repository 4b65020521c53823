"""CalculiX's explicit and modal procedures (reference_fem/calculix/procedures.py): their decks,
the linear split of the reference mesh, the probes-only output, and their histories against the
reference FEM on the same mesh within a stated tolerance."""

import re
import shutil

import numpy as np
import pytest

from cases import get_case
from cases.params import UnsupportedCase
from reference_fem.calculix import build_deck
from reference_fem.calculix.linear import split
from reference_fem.calculix.procedures import element
from reference_fem.frames import SOLID
from smfem.runs.errors import history_errors
from smfem.runs.registry import solve

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None,
                               reason="ccx (CalculiX) is not installed: apt-get install calculix-ccx")


def _worst(a, b, probes) -> dict:
    """probe -> relative max-norm difference of run ``a`` from run ``b`` over the window."""
    return {p: history_errors(a.t, a.history[p], b.t, b.history[p])[0] for p in probes}


def test_the_split_fills_each_quadratic_element_with_positive_linear_ones():
    """Each quad9 of the thick cylinder split 2 x 2 on its own nodes: every sub-quadrilateral
    counter-clockwise, and together they tile the polygon of the parent's corners and
    mid-sides (its area to round-off)."""
    deck = build_deck(get_case("thick_cylinder"), procedure="explicit")
    x, cells, quads = deck.points, deck.cells, deck.elements
    assert np.array_equal(quads, split(cells)) and set(np.unique(quads)) == set(np.unique(cells))

    def area(polygons):
        xp, yp = x[0][polygons], x[1][polygons]
        return 0.5 * (xp * np.roll(yp, -1, axis=1) - np.roll(xp, -1, axis=1) * yp).sum(axis=1)

    assert (area(quads) > 0).all()
    outline = cells[:, [0, 4, 1, 5, 2, 6, 3, 7]]
    assert area(quads).reshape(-1, 4).sum(axis=1) == pytest.approx(area(outline), rel=1e-12)


def test_the_explicit_deck_names_its_increment_and_writes_four_times_a_dt():
    case = get_case("thick_cylinder")
    implicit, explicit = build_deck(case, fields=False), build_deck(case, procedure="explicit", fields=False)
    assert explicit.element == "CPE4" and explicit.elements.shape[0] == 4 * implicit.elements.shape[0]
    # the fourth value, the largest increment: ccx 2.20 selects a zero increment without it
    assert f"*DYNAMIC, EXPLICIT\n{case.dt:.13g}, {case.t_end:.13g}, , {case.dt:.13g}" in explicit.text
    # ccx 2.20 writes an explicit step's output at every increment whatever TIME POINTS say: the
    # deck writes every N increments, N from the predicted increment (reference_fem/calculix/courant.py)
    assert "TIME POINTS" not in explicit.text and explicit.every > 1
    assert explicit.every * explicit.increment <= case.dt / 4 < (explicit.every + 1) * explicit.increment
    assert re.findall(r"\*(?:NODE|EL) FILE.*", explicit.text) == [f"*NODE FILE, OUTPUT=2D, FREQUENCY={explicit.every}, "
                                                                 "NSET=PROBES"]
    # each quadratic face loaded is two linear ones
    assert len(re.findall(r", P\d, ", explicit.text)) == 2 * len(re.findall(r", P\d, ", implicit.text))
    with pytest.raises(UnsupportedCase, match="axisymmetric"):  # ccx's wedges collapse the increment
        build_deck(get_case("dome"), procedure="explicit")
    assert build_deck(get_case("thick_cylinder", {"dim": 3, "t_end": 4e-4}), procedure="explicit").element == "C3D8"


def test_the_explicit_procedure_takes_reduced_elements_on_plastic_bodies():
    """Fully integrated linear elements lock in plastic flow (reference_fem/calculix/procedures.py):
    an explicit run of a plastic body takes ccx's reduced ones, an elastic body the full ones."""
    assert build_deck(get_case("notched_strip"), procedure="explicit", fields=False).element == "CPE4R"
    assert build_deck(get_case("notched_strip", {"plastic": False}), procedure="explicit", fields=False).element == "CPE4"
    assert build_deck(get_case("notched_strip"), fields=False).element == "CPE8"  # implicit: serendipity
    deck = build_deck(get_case("notched_cylinder"), procedure="explicit", fields=False)
    assert deck.element == "CPE4R" and "TYPE=CPE4R," in deck.text
    assert element(SOLID, "explicit", plastic=True) == "C3D8R" and element(SOLID, "explicit") == "C3D8"


def test_the_modal_deck_stores_its_modes_then_superposes():
    deck = build_deck(get_case("dome"), procedure="modal", modes=30, fields=False)
    text = deck.text
    assert deck.element == "CAX8"
    assert "*STEP\n*FREQUENCY, STORAGE=YES\n30\n*END STEP\n" in text
    assert text.index("*MODAL DYNAMIC") > text.index("*END STEP") and "*DLOAD, AMPLITUDE=STEPLOAD" in text
    assert "modes" not in build_deck(get_case("dome"), fields=False).text


def test_a_run_deck_writes_only_what_the_probes_read():
    """Displacement probes at nodes: the displacements of the probes' node set, nothing else;
    plastic strains at points and as a maximum: PEEQ on the whole body (the maximum needs it)."""
    text = build_deck(get_case("thick_cylinder"), fields=False).text
    assert re.findall(r"\*(?:NODE|EL) FILE.*\n.*", text) == ["*NODE FILE, OUTPUT=2D, NSET=PROBES\nU"]
    assert "*NODE PRINT" not in text
    plastic = build_deck(get_case("thick_cylinder", {"plastic": True}), fields=False).text
    assert re.findall(r"\*(?:NODE|EL) FILE.*\n.*", plastic) == ["*NODE FILE, OUTPUT=2D, NSET=PROBES\nU",
                                                               "*EL FILE, OUTPUT=2D\nPEEQ"]
    assert "*EL FILE, OUTPUT=2D\nS" in build_deck(get_case("thick_cylinder")).text  # an export: the fields


@needs_ccx
def test_explicit_thick_cylinder_agrees_with_the_reference_and_converges_to_it():
    """ccx's explicit procedure (CPE4 split of the reference's quad9 mesh, lumped mass, its own
    Courant increment, about dt / 8) against the reference on the same mesh at dt / 8 (so that
    Newmark's time error, 3 % of B_ut at dt, does not count), over the first 10 steps.

    Tolerances, measured 0.9, 3.8, 3.1 %: the bilinear elements' own space error on the
    reference's nodes (B_ut, the hoop displacement at a patch's edge, converges slowest) and the
    lumped against the consistent mass. Against the reference on the mesh refined twice, the
    difference must fall at least by half from the mesh coarsened twice to this one (measured
    13.0 -> 5.8 % on B_ut, 3.8 -> 1.6 % on C_ur): the split converges to the same solution.

    The run also checks, for plane elements, fully integrated, what the next test checks of the
    others: the predicted increment is ccx's own or at most 5 % above it, and the outputs fall
    at most dt / 4 apart (one ccx run of the thick cylinder, not two)."""
    window = {"t_end": 4e-4}
    dt = get_case("thick_cylinder").dt / 8
    explicit = solve("calculix", get_case("thick_cylinder", window), options={"procedure": "explicit"})
    assert explicit.converged and explicit.info["element"] == "CPE4"
    assert len(explicit.t) == get_case("thick_cylinder", window).n_steps + 1
    assert 1.0 <= explicit.info["predicted_increment"] / explicit.info["ccx_increment"] < 1.05, explicit.info
    assert explicit.info["output_spacing_dt"] <= 0.25, explicit.info
    same_mesh = solve("reference", get_case("thick_cylinder", {**window, "dt": dt}))
    worst = _worst(explicit, same_mesh, ("A_ur", "B_ut", "C_ur"))
    assert worst["A_ur"] < 0.015 and worst["B_ut"] < 0.05 and worst["C_ur"] < 0.04, worst
    finer = solve("reference", get_case("thick_cylinder", {**window, "dt": dt, "refine": 2}))
    coarse = solve("calculix", get_case("thick_cylinder", {**window, "coarsen": 2}), options={"procedure": "explicit"})
    fine_worst, coarse_worst = _worst(explicit, finer, ("B_ut", "C_ur")), _worst(coarse, finer, ("B_ut", "C_ur"))
    assert all(fine_worst[p] < coarse_worst[p] / 2 for p in fine_worst), (coarse_worst, fine_worst)


@needs_ccx
def test_modal_dome_agrees_with_the_reference_in_time_and_its_truncation_shows():
    """ccx's modal procedure on the dome (CAX8 on the reference's nodes, 30 modes, each exact in
    time) against the reference on the same mesh at dt / 8: within 1 % (measured 0.28 %: the
    serendipity against the Lagrange element, and what is left of the reference's time error;
    at the case's dt that is 2 %). Truncated to 2 modes the apex's history is far off (the
    truncation in N is the procedure's error, measured by its levels)."""
    case = get_case("dome")
    modal = solve("calculix", case, options={"procedure": "modal", "modes": 30})
    assert modal.converged and modal.info["modes"] == 30 and len(modal.t) == case.n_steps + 1
    reference = solve("reference", get_case("dome", {"dt": case.dt / 8}))
    assert _worst(modal, reference, ("apex_uz",))["apex_uz"] < 0.01
    truncated = solve("calculix", case, options={"procedure": "modal", "modes": 2})
    assert _worst(truncated, reference, ("apex_uz",))["apex_uz"] > 0.03


@needs_ccx
@pytest.mark.slow
def test_explicit_reduced_elements_carry_the_plastic_strip_within_one_percent_of_its_truth():
    """The notched strip in ccx's explicit procedure at refine 1 (CPE4R, 118 CPU s): mid_uz
    0.69 % from the stored truth, where the fully integrated CPE4 locks to 1.76 % (2.54 % at
    refine 2)."""
    import smfem
    from smfem.studies.metrics import headline_errors

    case = get_case("notched_strip")
    run = solve("calculix", case, options={"procedure": "explicit"})
    assert run.converged and run.info["element"] == "CPE4R"
    errors = headline_errors(case, smfem.truth(case), run.t, run.history)
    assert errors and max(errors.values()) < 0.01, errors


@needs_ccx
def test_a_failed_eigensolve_is_a_failed_run_not_zero_histories():
    """200 modes of the dome's 551 free dofs: ccx 2.20's ARPACK gives up (info = -3), and ccx
    goes on with zero modes to zero histories; the run says it did not converge, and why."""
    modal = solve("calculix", get_case("dome", {"t_end": 2e-5}), options={"procedure": "modal", "modes": 200})
    assert not modal.converged and "eigensolver failed" in modal.message


@needs_ccx
@pytest.mark.parametrize("name, params", [("thick_cylinder", {"dim": 3}), ("notched_strip", {}),
                                          ("notched_cylinder", {})],
                         ids=["solid", "plane-reduced", "solid-reduced"])
def test_the_predicted_explicit_increment_is_ccxs_or_a_little_above(name, params):
    """The increment :mod:`reference_fem.calculix.courant` predicts is ccx's own (its output's
    "SELECTED time increment") or at most 5 % above it, on solid, and plane and solid reduced
    elements (plane full ones: the thick cylinder's run above): so N increments span at most
    the dt / 4 asked, and the outputs written (two steps of each case, the end of the step
    always among them) fall at most dt / 4 apart."""
    case = get_case(name, {**params, "t_end": 2 * get_case(name).dt})
    run = solve("calculix", case, options={"procedure": "explicit"})
    assert run.converged and len(run.t) == 3
    assert 1.0 <= run.info["predicted_increment"] / run.info["ccx_increment"] < 1.05, run.info
    assert run.info["output_spacing_dt"] <= 0.25, run.info
