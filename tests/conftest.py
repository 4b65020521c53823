import sys
from pathlib import Path

# tests import their helpers as a plain module
sys.path.insert(0, str(Path(__file__).parent))

from smfem.runs import threads  # noqa: E402

# one BLAS thread per test process, as in every smfem entry point: two xdist workers on two
# cores must not oversubscribe
threads.pin()
