"""One BLAS kernel on every x86-64 machine, so a game plays the same whatever runs it.

numpy's OpenBLAS picks its kernels by the CPU: on a machine with AVX-512 it takes the
SkylakeX kernels, elsewhere Haswell's, and the two round some products differently.  A
game is a long feedback loop (localisation, control, planning on what the robots saw),
so one last-bit difference grows into another game: seed 1 of rcll2016 scored 339 on
an AVX-512 machine and 356 on an AVX2 one.  Tournaments on a cluster and benchmark
tables compared across machines need the same game for the same seed, so the package
asks OpenBLAS for the Haswell kernels (AVX2, every x86-64 server of the last decade)
before numpy is loaded.  A user who sets ``OPENBLAS_CORETYPE`` keeps their choice.

OpenBLAS reads the variable once, when numpy loads it: this module must run before
anything imports numpy (``rll_bt/__init__`` calls it first thing).
"""
from __future__ import annotations

import os
import platform
import sys

KERNEL = "Haswell"


def _has_avx2() -> bool:
    try:
        with open("/proc/cpuinfo", encoding="ascii", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return "avx2" in line.split()
    except OSError:
        pass
    return False


def pin_kernel(environ=os.environ) -> str | None:
    """Set ``OPENBLAS_CORETYPE`` to the common kernel when numpy is not loaded yet, the
    machine is x86-64 with AVX2 and the user chose none; returns the kernel in force
    (None: left to OpenBLAS)."""
    if "OPENBLAS_CORETYPE" in environ:
        return environ["OPENBLAS_CORETYPE"]
    if "numpy" in sys.modules or platform.machine().lower() not in ("x86_64", "amd64"):
        return None
    if not _has_avx2():
        return None
    environ["OPENBLAS_CORETYPE"] = KERNEL
    return KERNEL
