import sys
from pathlib import Path

import pytest

# tests import their helpers as a plain module
sys.path.insert(0, str(Path(__file__).parent))

from smfem.runs import threads  # noqa: E402

# one BLAS thread per test process, as in every smfem entry point: two xdist workers on two
# cores must not oversubscribe
threads.pin()


#: long verification studies, run with ``pytest -m slow`` (and CalculiX's, the benchmarks' and
#: the 3D reference's again in the report): each took 5-19 s of one core on a machine of the
#: slower kind here (AMD EPYC, AVX2 only; 2026-11-27), and together they held the default run
#: past five minutes there. What each checks is in its docstring; the default run keeps a
#: cheaper test of each feature (CalculiX: every exported deck runs in ccx; the benchmarks:
#: the cheaper scripts at their tiny size; the 3D reference, timed loads, mirrors, regions,
#: the registry, the explicit engine, the report's tables: their shorter tests in the same files).
LONG_STUDIES = {
    "test_calculix.py::test_3d_thick_cylinder_within_1_percent_of_the_reference_3d",
    "test_calculix.py::test_elastic_thick_cylinder_within_1_percent_of_the_reference_2d",
    "test_calculix.py::test_dome_apex_extrema_within_2_percent_of_the_reference",
    "test_calculix_timed.py::test_pulse_in_calculix_within_half_a_percent_of_the_reference_2d",
    "test_calculix_timed.py::test_forces_in_calculix_agree_with_the_reference[ring body force, pulse]",
    "test_reference_regions.py::test_calculix_runs_the_two_materials",
    "test_reference_regions.py::test_3d_agrees_with_2d_on_the_layered_cylinder",
    "test_reference_mirror.py::test_calculix_takes_the_mirror_half_from_the_references_supports",
    "test_reference_mirror.py::test_the_mirror_half_of_the_layered_cylinder_gives_the_whole_ones_histories_with_half_the_unknowns",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[tilted_wall]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[turning_patches]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[notched_convergence]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[truth_ladders]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[iterations]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[default_histories]",
    "test_benchmarks.py::test_benchmark_runs_at_its_tiny_size[moving_load_settings]",
    "test_truth.py::test_truth_command_writes_history_and_summary_and_refuses_chosen_keys",
    "test_truth.py::test_thick_cylinder_truth_against_an_independent_spectral_solution",
    "test_truth_timed.py::test_stored_truth_of_a_timed_load_against_its_exact_answer[moving_load-moving_strip_exact-16]",
    "test_truth_timed.py::test_smfem_and_the_reference_on_the_moving_load_against_its_exact_answer",
    "test_smfem_vs_reference.py::test_plastic_strip_without_the_notch_agrees_to_its_plastic_strains",
    "test_inhomogeneous.py::test_matrix_free_iterations_equal_the_coupled_factorization",
    "test_mesh_sections_reference.py::test_the_swept_3d_mesh_of_an_axisymmetric_scene_agrees_with_the_2d_section",
    "test_timed_loads.py::test_the_notched_moving_load_yields_with_coupled_harmonics_in_both_solvers",
    "test_stability.py::test_near_incompressible_lame_within_two_percent",
    "test_reference_linalg.py::test_bbar_frees_the_implicit_reference_of_locking_in_plastic_flow",
    "test_quad_element.py::test_the_plastic_thick_cylinder_runs_and_agrees_with_the_reference_better_than_moment4",
    "test_reference_dynamics.py::test_dome_3d_against_2d",
    "test_reference_static.py::test_hill_collapse",
    "test_plane_strain_bodies.py::test_plane_strain_rings_equal_the_3d_rings",
    "test_explicit.py::test_stable_below_the_critical_step_and_unstable_above",
    "test_reference_static.py::test_strain_operator_matches_skfem_elasticity[overrides1]",
    "test_stability.py::test_the_element_locked_while_the_free_gradients_were_held_at_zero",
    "test_bad_input.py::test_valid_parameters_reference_solver",
    "test_registry.py::test_a_registered_solver_runs_through_a_study_into_its_tables_and_figures",
    "test_report.py::test_stresses_have_their_own_table_and_stay_out_of_the_headline",
}


#: the files that keep one worker longest (--durations: test_report.py's tiny report fixture alone
#: is about a minute), handed out first: --dist loadfile gives the workers whole files in
#: collection order, and a long file handed out last runs on alone after the other worker is done
HEAVY_FIRST = ("test_report.py", "test_benchmarks.py", "test_examples.py", "test_calculix.py",
               "test_calculix_procedures.py", "test_manufactured.py")


def pytest_collection_modifyitems(config, items):
    import pytest

    order = {name: i for i, name in enumerate(HEAVY_FIRST)}
    items.sort(key=lambda item: order.get(item.path.name, len(order)))  # stable: the rest keep their order
    seen = set()
    for item in items:
        key = item.nodeid.removeprefix("tests/")
        if key in LONG_STUDIES:
            item.add_marker(pytest.mark.slow)
            seen.add(key)
    if len(items) > 1000 and seen != LONG_STUDIES:  # a whole run: every name must still be a test
        raise pytest.UsageError(f"tests/conftest.py LONG_STUDIES names no test: {sorted(LONG_STUDIES - seen)}")


@pytest.fixture(scope="session")
def tiny(tmp_path_factory):
    """The tiny report (test_report.TINY: the dome and the thick cylinder, a few runs each),
    timing pass and document included, built once per worker for the report's and the timing
    pass's tests."""
    from reports.build import build
    from test_report import LIGHT_TIMING, TINY

    return build(TINY, tmp_path_factory.mktemp("report"), workers=2, progress=False, settings="tiny",
                 timing=LIGHT_TIMING)
