"""Which sources made a run (smfem.studies.provenance): what run.json counts as made from nothing."""

from __future__ import annotations

import shutil
import subprocess

import pytest

from smfem.studies import provenance

needs_git = pytest.mark.skipif(shutil.which("git") is None or not (provenance.ROOT / ".git").exists(),
                               reason="not a git checkout (an installed package records no commit)")


def git(*args) -> str:
    return subprocess.run(["git", "-C", str(provenance.ROOT), *args], capture_output=True, text=True,
                          check=True).stdout.strip()


def test_a_run_of_no_commit_or_of_uncommitted_changes_is_never_from_these_sources():
    assert not provenance.same_sources(None)
    assert not provenance.same_sources("")
    assert not provenance.same_sources("0" * 40 + "+changes")
    assert not provenance.same_sources("0" * 40)  # a commit this checkout does not know


@needs_git
def test_head_made_these_sources_unless_they_changed_and_the_first_commit_did_not():
    head = git("rev-parse", "HEAD")
    assert provenance.commit().startswith(head)
    changed = git("status", "--porcelain", "--untracked-files=no", "--", *provenance.SOURCES,
                  *(f":(exclude){p}" for p in provenance.NOT_IN_A_RUN)) != ""
    assert provenance.same_sources(head) is not changed
    first = git("rev-list", "--max-parents=0", "HEAD").split()[0]
    assert provenance.same_sources(first) is (first == head and not changed)  # (a clone of depth one)
    made = provenance.made()
    assert made["commit"] == provenance.commit(provenance.SOURCES) and made["at"]


def test_a_run_is_of_its_commit_whatever_changed_outside_the_sources(monkeypatch):
    """An edit of README or the docs while a report runs does not make its runs come from no
    commit; one of the sources does; the report's own commit (run.json) names any change."""
    status = {"README.md": " M README.md", "smfem": " M smfem/model.py"}
    for edited in ("README.md", "smfem"):
        def git(*args, edited=edited):
            if args[0] == "rev-parse":
                return "a" * 40
            paths = args[args.index("--") + 1:] if "--" in args else ()
            hit = not paths or any(edited == p or edited.startswith(p + "/") for p in paths)
            return status[edited] if hit else ""
        monkeypatch.setattr(provenance, "_git", git)
        provenance.commit.cache_clear()
        assert provenance.commit() == "a" * 40 + "+changes"
        assert provenance.made()["commit"] == "a" * 40 + ("+changes" if edited == "smfem" else "")
    provenance.commit.cache_clear()


def test_a_solvers_runs_are_decided_by_its_own_numerics_and_the_common_sources():
    """A change to SMFEM's numerics leaves the reference's runs made from these sources (the two
    share no numerics), and the other way round; the runner, the study framework and the scenes
    decide every run."""
    reference, smfem = provenance.sources_of(("reference_fem",)), provenance.sources_of(("smfem",))
    assert "reference_fem" in reference and "smfem" not in reference and "reference_fem" not in smfem
    for common in ("cases", "smfem/runs", "smfem/studies", "pyproject.toml"):
        assert common in reference and common in smfem
    assert set(reference) | set(smfem) <= set(provenance.SOURCES) | set(provenance.COMMON)


def test_a_studys_runs_do_not_pass_through_the_command_line():
    """Why ``smfem/cli`` is no run's source (provenance.NOT_IN_A_RUN): the study and the worker
    that executes its runs never import it."""
    import subprocess
    import sys
    code = ("import sys, smfem.studies.study, smfem.studies.jobs, smfem.studies.executors; "
            "print(sorted(m for m in sys.modules if m.startswith('smfem.cli')))")
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip() == "[]"


def test_a_change_to_the_plan_alone_leaves_the_runs_made_from_these_sources(monkeypatch):
    """The plan decides which runs a report asks for, provenance where they came from, the
    timing pass how often the decisive ones are timed again and the command line what a user
    asked for, not what one gives: the comparison of sources leaves them out, and only them."""
    asked = []
    monkeypatch.setattr(provenance, "_git", lambda *args: asked.append(args) or "")
    provenance.same_sources.cache_clear()
    assert provenance.same_sources("b" * 40)
    provenance.same_sources.cache_clear()
    (args,) = asked
    assert args[:3] == ("diff", "--quiet", "b" * 40)
    assert [a for a in args if a.startswith(":(exclude)")] == [":(exclude)smfem/studies/plan.py",
                                                                ":(exclude)smfem/studies/provenance.py",
                                                                ":(exclude)smfem/studies/timing.py",
                                                                ":(exclude)smfem/cli"]
    assert set(provenance.SOURCES) <= set(args)
