"""SMFEM's contact layer over section kinds and elements (issue 56; the table:
benchmarks/contact_sections.py, its figures in benchmarks/README.md): the rod against the wall and
the colliding rods, mapped and on gmsh sections, moment4 and quad9, every step size and
refinement of the matrix run to the end and keep their energy within the layer's own limit."""

from __future__ import annotations

from pathlib import Path

import pytest

from smfem.contact import ENERGY_GAIN_LIMIT
from test_benchmarks import load

BENCHMARK = load(Path(__file__).resolve().parents[1] / "benchmarks" / "contact_sections.py")


def check(rows: list[dict]) -> None:
    for row in rows:
        where = {k: row[k] for k in ("scene", "section", "element", "refine", "dt", "nu")}
        assert row["converged"] and row["to_end"], (where, row["message"])
        assert abs(row["energy_change"]) < ENERGY_GAIN_LIMIT, (where, row["energy_change"])


def test_the_gmsh_sections_with_quad9_run_at_the_smallest_step():
    """The gmsh rod against the wall and the gmsh pair of rods (nu = 0.3 and 0), quad9 at
    dt / 4 = 2.5e-7 s through the first 50 us (200 steps; measured |energy change| 2e-13 ... 1e-12):
    before quad9's lumped masses were made none negative (babae36) the rod's axis grew an
    unstable mode by 1.17 a step at dt / 2."""
    rows = BENCHMARK.matrix(sections=("gmsh",), elements=("quad9",), divisors=(4,), refines=(1,), t_end=5e-5)
    assert len(rows) == 3
    check(rows)


@pytest.mark.slow
def test_every_run_of_the_matrix_runs_to_the_end_and_keeps_its_energy():
    """The whole matrix: 2 scenes (the collision also at nu = 0) x 2 sections x 2 elements x
    refine 1, 2 x dt, dt / 2, dt / 4: 72 runs, about 6 CPU minutes."""
    rows = BENCHMARK.matrix()
    assert len(rows) == 72
    check(rows)
