"""Test-session settings."""

import os

# The same BLAS threading as the command line (hexapod sets one OpenBLAS thread before NumPy is
# imported), so that results computed here and by a `hexapod` subprocess agree to the last bit.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
