"""Reading CalculiX's .frd (reference_fem/calculix/frd.py): only the blocks asked for, each
reduced on its own, a block cut short left out."""

import numpy as np

from reference_fem.calculix.frd import read_frd


def _block(t: float, name: str, rows: dict) -> str:
    """One nodal result block as ccx writes it (fixed columns)."""
    lines = [f"  100CL  101{t:12.5E}{len(rows):12d}                     0    1           1",
             f" -4  {name:<8s}    2    1", " -5  D1          1    2    1    0"]
    lines += [f" -1{node:10d}" + "".join(f"{v:12.5E}" for v in values) for node, values in rows.items()]
    return "\n".join(lines + [" -3"]) + "\n"


def test_the_reader_keeps_the_blocks_asked_for_and_reduces_each(tmp_path):
    text = ("    1C\n" + _block(1e-5, "DISP", {1: (1.0, -2.0), 7: (3.0, 4.0)}) + _block(1e-5, "STRESS", {1: (9.0, 9.0)})
            + _block(2e-5, "DISP", {1: (5.0, 6.0), 7: (-7.0, 8.5)}))
    path = tmp_path / "job.frd"
    path.write_text(text + _block(3e-5, "DISP", {1: (0.0, 0.0)})[:-5])  # the last block cut short
    blocks = read_frd(path, {"DISP"})
    assert list(blocks) == ["DISP"] and [t for t, *_ in blocks["DISP"]] == [1e-5, 2e-5]
    nodes, values = blocks["DISP"][1][1:]
    assert nodes.tolist() == [1, 7] and np.array_equal(values, [[5.0, 6.0], [-7.0, 8.5]])
    kept = read_frd(path, {"DISP"}, lambda name, n, v: (n[n == 7], v[n == 7], v[:, 0].max()))
    assert [(b[1].tolist(), b[2].tolist(), b[3]) for b in kept["DISP"]] == [([7], [[3.0, 4.0]], 3.0),
                                                                         ([7], [[-7.0, 8.5]], 5.0)]
    (tmp_path / "empty.frd").write_bytes(b"")
    assert read_frd(tmp_path / "empty.frd", {"DISP"}) == {}
