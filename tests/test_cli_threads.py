"""What the `aeroexec` process itself sets up before a command runs."""

from __future__ import annotations

import os

import pytest
from thread_count import threads_with

THREADS_AFTER_NUMPY = """\
import os, sys
from aeroexec.cli import main
sys.argv = ["aeroexec", "--help"]
try:
    main()
except SystemExit:
    pass
import numpy
print(len(os.listdir("/proc/self/task")), os.environ.get("OPENBLAS_NUM_THREADS"))
"""


def _threads(blas_threads: str | None) -> tuple[int, str]:
    return threads_with(THREADS_AFTER_NUMPY, "OPENBLAS_NUM_THREADS", blas_threads)


@pytest.mark.skipif(not os.path.isdir("/proc/self/task"), reason="threads counted in /proc")
def test_numpy_gets_one_blas_thread_unless_the_user_says_otherwise() -> None:
    # OpenBLAS starts a thread per core at numpy's import, spinning a while: CPU for
    # matrix routines aeroexec never calls (benchmarks/properties.py, whole process).
    theirs, kept = _threads("3")
    if theirs == 1:  # a numpy whose BLAS starts no threads (not OpenBLAS, or one core)
        pytest.skip("this numpy's BLAS starts no threads of its own")
    ours, value = _threads(None)
    assert value == "1"
    assert kept == "3"
    assert ours == 1  # the main thread alone
