"""Command-line interface ``cct``."""

import os

# The toolbox's linear algebra is on small matrices (2x2 plants, controllers of
# order <= 20, LMIs of 100 rows): OpenBLAS threads cost more in wake-ups than
# they gain there (a 4x4 expm took 2 ms with the default threads and
# 32 us with one on a shared 2-core machine; paper 003's design went from 4.5 to
# 3.9 s of CPU, outputs identical). Set before numpy is imported; a value the
# user exported wins.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from ._exit import run  # noqa: E402
from ._main import main  # noqa: E402

__all__ = ["main", "run"]
