"""README and the examples gallery as a newcomer meets them: the Python example and every
``examples/*.py`` run (the scripts on their small settings), and what README states of the full
report is what the published tables say."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
PUBLISHED = ROOT / "docs" / "full-report"


def _run(args, cwd: Path) -> str:
    done = subprocess.run([sys.executable, *args], cwd=cwd, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    return done.stdout


def test_the_readmes_python_example_prints_the_error_estimate_and_a_history(tmp_path):
    code = re.search(r"```python\n(.*?)```", README, re.S).group(1)
    out = _run(["-c", code], tmp_path)
    estimate, truth = (float(x) for x in re.search(r"estimated error ([0-9.]+)%, against the stored truth ([0-9.]+)%",
                                                    out).groups())
    assert 0 < truth < 1.0 and truth < estimate < 5 * truth  # within 1 %, and the estimate an upper bound here
    assert re.search(r"^\s*t\s+A_ur\s+B_ut\s+C_ur$", out, re.M)  # the history's header
    assert (tmp_path / "out" / "thick" / "fields.vtu").exists()


EXPECTED = {
    "own_scene.py": (r"estimated error [0-9.]+%", r"inner_ur\s+max-norm\s+0\.0", r"written to out/pipe-smfem"),
    "smfem_vs_3d.py": (r"SMFEM, 9-node element.*total error\s+0\.\d\d%", r"reference FEM 3D.*total error"),
    "convergence.py": (r"refine 2, dt/2: total error [0-9.]+%", r"work-precision diagram: out/convergence.png"),
    "fields_pyvista.py": (r"largest equivalent plastic strain 0\.[1-9]", r"picture: out/notched_cylinder_peps.png"),
}


def test_every_example_is_tested():
    assert sorted(p.name for p in (ROOT / "examples").glob("*.py")) == sorted(EXPECTED)


@pytest.mark.parametrize("script", sorted(EXPECTED))
def test_the_example_runs_on_its_small_settings(script, tmp_path):
    out = _run([str(ROOT / "examples" / script), "--small"], tmp_path)
    for pattern in EXPECTED[script]:
        assert re.search(pattern, out), (pattern, out[-2000:])


def test_the_readme_opens_with_the_verdict_a_figure_the_two_commands_and_the_python_example():
    first = "\n".join(README.splitlines()[:60])
    assert "**What it found**" in first and "![" in first
    assert (PUBLISHED / "work-precision.png").exists()
    assert "pip install . && smfem report --out out/report" in first
    assert "pip install '.[test]' && python -m pytest" in first
    assert "```python\nimport smfem" in first and first.count("```") >= 5  # the Python example closes inside


def test_the_readme_holds_no_commit_hash():
    """History is the git log's (a hash has digits and letters a-f)."""
    hashes = re.findall(r"\b(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b", README)
    assert not hashes, hashes


def test_the_readmes_findings_and_verdict_are_what_the_published_tables_make():
    """README's opening paragraph and its verdict table are what ``python -m reports.readme``
    writes from docs/full-report's tables and run.json, never typed by hand; every number in bold
    is the leading number of one of the table's cells."""
    from reports.readme import published, written
    from reports.verdict import summary_table

    head, made = published(PUBLISHED)
    assert README == written(README, head, made), "run python -m reports.readme"
    table = summary_table(head)
    cells = {c.strip() for line in table[2:] for c in line.split("|")}
    leading = {m.group(1) for c in cells if (m := re.match(r"^(?:[<>] )?([0-9.]+)", c))}
    bold = re.findall(r"\*\*([0-9.]+)\*\*", README)
    assert bold and set(bold) <= leading, set(bold) - leading


def test_the_published_page_is_what_its_tables_make(tmp_path):
    """docs/full-report/README.md is written from the published tables and run.json
    (``python -m reports.publish``), never by hand."""
    import shutil

    from reports.publish import page

    copy = tmp_path / "full-report"
    shutil.copytree(PUBLISHED / "tables", copy / "tables")
    shutil.copyfile(PUBLISHED / "run.json", copy / "run.json")
    page(copy)
    expected = (copy / "README.md").read_text().replace(copy.as_posix(), "docs/full-report")
    assert (PUBLISHED / "README.md").read_text() == expected


def test_the_readmes_scene_file_is_examples_pipe_toml_and_runs(tmp_path):
    """The TOML block README shows is examples/pipe.toml without its comment lines, and it runs."""
    import smfem

    block = re.search(r"```toml\n(.*?)```", README, re.S).group(1)
    lines = [x for x in (ROOT / "examples" / "pipe.toml").read_text().splitlines() if not x.startswith("#")]
    assert block.strip() == "\n".join(lines).strip()
    (tmp_path / "pipe.toml").write_text(block)
    run = smfem.run(tmp_path / "pipe.toml", estimate=False, fields=False)
    assert run.history.inner_ur.max() > 0  # the pressure inside pushes the wall out
