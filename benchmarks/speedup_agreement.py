"""Whether two headline tables agree on SMFEM's speed-ups: two `smfem report --retime` passes of
one cache (issue 59's must-show: within 10 % on every measured speed-up), or two reports.

    python benchmarks/speedup_agreement.py A/tables/headline.csv B/tables/headline.csv [--within 0.1]
    python benchmarks/speedup_agreement.py --retime DIR [--full]   # two retimes of DIR (a quick report unless --full), one after the other
    python benchmarks/speedup_agreement.py --tiny   # the published full report's table against itself

A measured speed-up is a ratio ("12.3x"); a bound ("> 7.7x"), "neither reaches it" and the like
are not measured and are listed only where the two tables differ. Prints one line per speed-up
and the largest relative difference, B over A. After two retimes, also the runs whose least CPU
moved by more than the agreement asked, each with the median memory probe before its batches in
either pass (``tables/timing_repeats.csv``, ``host_probe_s``): whether the host moved under it.
"""

from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pandas as pd

ROOT = Path(__file__).resolve().parents[1]
PUBLISHED = ROOT / "docs" / "full-report" / "tables" / "headline.csv"
MEASURED = re.compile(r"[0-9.]+(e[+-]?[0-9]+)?x")


def speedups(table: pd.DataFrame) -> dict[tuple[str, str, str], str]:
    """``(case, solver, target) -> cell`` of every speed-up column (``smfem_speedup_1pct`` ...)."""
    columns = [c for c in table.columns if c.startswith("smfem_speedup_") and not c.endswith("_range")]
    return {(row.case, row.solver, c.removeprefix("smfem_speedup_")): str(getattr(row, c))
            for row in table.itertuples() for c in columns if str(getattr(row, c)) not in ("nan", "")}


def compare(a: pd.DataFrame, b: pd.DataFrame) -> tuple[list[str], float, int]:
    """Lines ``case solver target: A -> B (+d %)``, the largest |B / A - 1| over the measured ones and their count."""
    first, second = speedups(a), speedups(b)
    lines, worst, measured = [], 0.0, 0
    for key in sorted(first.keys() | second.keys()):
        x, y = first.get(key, "-"), second.get(key, "-")
        if MEASURED.fullmatch(x) and MEASURED.fullmatch(y):
            change = float(y[:-1]) / float(x[:-1]) - 1
            worst, measured = max(worst, abs(change)), measured + 1
            lines.append(f"{' '.join(key)}: {x} -> {y} ({100 * change:+.1f} %)")
        elif x != y:
            lines.append(f"{' '.join(key)}: {x} -> {y} (not both measured)")
    return lines, worst, measured


def moved_runs(a: pd.DataFrame, b: pd.DataFrame, within: float) -> list[str]:
    """Lines ``case solver label: least A -> B s (+d %), probe median A -> B ms`` of the runs in
    both ``timing_repeats`` tables whose least CPU moved by more than ``within``, most moved first."""
    def per_run(repeats: pd.DataFrame) -> pd.DataFrame:
        return repeats.groupby(["case", "solver", "label"]).agg(least=("cpu_s", "min"), probe=("host_probe_s", "median"),
                                                                 repeats=("cpu_s", "size"))

    both = per_run(a).merge(per_run(b), left_index=True, right_index=True, suffixes=("_a", "_b"))
    both["change"] = both.least_b / both.least_a - 1
    moved = both[both.change.abs() > within].sort_values("change", key=abs, ascending=False)
    return [f"{' '.join(key)}: least {r.least_a:.3g} -> {r.least_b:.3g} s ({100 * r.change:+.1f} %, "
            f"{int(r.repeats_a)} and {int(r.repeats_b)} repeats), probe median {1e3 * r.probe_a:.1f} -> {1e3 * r.probe_b:.1f} ms"
            for key, r in moved.iterrows()]


def retime_twice(out: Path, settings: str) -> tuple[Path, Path]:
    """Two ``smfem report --retime`` passes of ``out``, one after the other; their headline tables
    kept, and their repeats (``timing_repeats-retimeN.csv``) beside them."""
    kept = []
    for n in (1, 2):
        subprocess.run([sys.executable, "-m", "smfem", "report", "--retime", f"--{settings}", "--out", str(out)],
                       check=True)
        kept.append(Path(shutil.copyfile(out / "tables" / "headline.csv", out / f"headline-retime{n}.csv")))
        shutil.copyfile(out / "tables" / "timing_repeats.csv", out / f"timing_repeats-retime{n}.csv")
    return kept[0], kept[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("tables", nargs="*", type=Path, help="two headline.csv files")
    ap.add_argument("--retime", type=Path, metavar="DIR", help="retime the report in DIR twice and compare")
    ap.add_argument("--full", action="store_true", help="DIR holds a full report (default quick)")
    ap.add_argument("--within", type=float, default=0.10, help="the agreement asked for (default 0.10)")
    ap.add_argument("--tiny", action="store_true", help="the published headline against itself")
    args = ap.parse_args(argv)
    if args.tiny:
        paths = (PUBLISHED, PUBLISHED)
    elif args.retime:
        paths = retime_twice(args.retime, "full" if args.full else "quick")
    elif len(args.tables) == 2:
        paths = tuple(args.tables)
    else:
        ap.error("give two headline.csv files, --retime DIR or --tiny")
    lines, worst, measured = compare(*(pd.read_csv(p) for p in paths))
    print("\n".join(lines))
    print(f"{measured} measured speed-ups in both; largest difference {100 * worst:.1f} %: "
          f"{'within' if worst <= args.within else 'NOT within'} {100 * args.within:g} %")
    if args.retime:
        repeats = [pd.read_csv(args.retime / f"timing_repeats-retime{n}.csv") for n in (1, 2)]
        print("runs whose least CPU moved by more than that, and the host's memory probe under them:")
        print("\n".join(moved_runs(*repeats, args.within)) or "none")
    return 0


if __name__ == "__main__":
    sys.exit(main())
