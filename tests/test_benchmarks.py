"""Every benchmark script runs, at its tiny size, so none rots: the figures in docs/verification.md and
benchmarks/README.md come from these scripts at full size."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

BENCHMARKS = sorted((Path(__file__).resolve().parents[1] / "benchmarks").glob("*.py"))


def load(path: Path):
    spec = importlib.util.spec_from_file_location(f"benchmark_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # (a dataclass there looks its module up by name)
    spec.loader.exec_module(module)
    return module


def test_there_are_benchmarks():
    assert len(BENCHMARKS) >= 6


@pytest.mark.parametrize("path", BENCHMARKS, ids=lambda p: p.stem)
def test_benchmark_runs_at_its_tiny_size(path, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # anything a script writes (a run cache) stays in the scratch directory
    load(path).main(["--tiny"])
    printed = capsys.readouterr().out
    assert len(printed.splitlines()) >= 2, printed
