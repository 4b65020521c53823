"""Each mode's stiffness and mass combined from matrices built once (smfem/mode_blocks.py) equal
the mode assembled by itself, on every kind of map and element; and a run's histories do not
change with the way its blocks are made."""

import numpy as np
import pytest

from cases import get_case
from cases import verification_axis as va
from cases.geometry import RING
from cases.msh_section import read_msh
from smfem import mode_blocks
from smfem.model import Model
from smfem.solver import solve
from helpers import turned_cutouts


def axis_scene(tmp_path):
    """A ring section that reaches the axis: harmonics 0, 1 and the rest have maps of their own."""
    return va.build(read_msh(va.write(tmp_path / "square.msh"), RING), {"dim": 2, "harmonics": 6})


#: name -> (the case of a temporary folder, B-bar, the number of different maps)
SCENES = {
    "prism, quad9, cut-out": (
        lambda _: get_case("moving_load_notched", {"element": "quad9", "harmonics": 8}), False, 1),
    "ring, both families, B-bar": (
        lambda _: turned_cutouts(get_case("notched_cylinder", {"harmonics": 12, "refine": 1}), 0.5), True, 3),
    "ring, the axis": (axis_scene, False, 3),
    "ring, two materials, quad9": (
        lambda _: get_case("ring_in_ring", {"harmonics": 10, "element": "quad9"}), False, 2),
}


@pytest.mark.parametrize("scene", SCENES)
def test_shared_blocks_equal_each_mode_assembled_by_itself(scene, tmp_path, monkeypatch):
    make, bbar, maps = SCENES[scene]
    monkeypatch.setattr(mode_blocks, "pays", lambda n_modes, n_profiles: True)
    model = Model(make(tmp_path), nonlinear=True, bbar=bbar)
    assert all(s is not None for s in model._shared) and len({id(T) for T in model._maps}) == maps
    for homogeneous in (False, True):
        for i in range(len(model.modes)):
            K, M = model.reduced_blocks(i, homogeneous)
            K0, M0 = model.reduced_stiffness(i, homogeneous), model.reduced_mass(i, homogeneous)
            assert abs(K - K0).max() <= 1e-14 * abs(K0).max(), (i, homogeneous)
            assert np.abs(M - M0).max() <= 1e-14 * np.abs(M0).max(), (i, homogeneous)
            assert np.all(K.data != 0)


def test_shared_blocks_only_where_they_hold_fewer_numbers_than_the_blocks():
    """The notched strip's 20 modes at 40 harmonics share a map but are fewer than its matrices
    (two profiles); at 120 harmonics they share them."""
    assert not any(Model(get_case("notched_strip", {"harmonics": 40}), nonlinear=True)._shared)
    assert all(Model(get_case("notched_strip", {"harmonics": 120}), nonlinear=True)._shared)


def test_the_histories_do_not_depend_on_how_the_blocks_are_made(monkeypatch):
    case = get_case("notched_strip", {"harmonics": 40, "t_end": 3.2e-5})
    by_itself = solve(case, with_fields=False)
    monkeypatch.setattr(mode_blocks, "pays", lambda n_modes, n_profiles: True)
    shared = solve(case, with_fields=False)
    for name, h in by_itself.history.items():
        assert np.abs(shared.history[name] - h).max() <= 1e-9 * np.abs(h).max(), name
