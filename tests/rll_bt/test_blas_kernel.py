"""The package pins OpenBLAS's kernel before numpy loads, so a game's floating point (and so the
game) is the same on an AVX-512 machine and an AVX2 one (rll_bt/blas.py)."""
import os
import subprocess
import sys

from rll_bt import blas

PROBE = ("import rll_bt, numpy, threadpoolctl; "
         "print([i['architecture'] for i in threadpoolctl.threadpool_info() if i['internal_api'] == 'openblas'][0])")


def run_probe(**env):
    e = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE"}
    e.update(env)
    return subprocess.run([sys.executable, "-c", PROBE], env=e, capture_output=True, text=True,
                          check=True).stdout.strip()


def test_importing_the_package_gives_numpy_the_common_kernel():
    want = "Haswell" if blas._has_avx2() else None
    got = run_probe()
    if want:
        assert got == want
    else:  # a machine without AVX2 keeps OpenBLAS's own choice
        assert got != "Haswell"


def test_a_kernel_the_user_chose_is_kept():
    assert run_probe(OPENBLAS_CORETYPE="Sandybridge") == "Sandybridge"
    env = {"OPENBLAS_CORETYPE": "Zen"}
    assert blas.pin_kernel(env) == "Zen" and env == {"OPENBLAS_CORETYPE": "Zen"}


def test_too_late_once_numpy_is_loaded():
    import numpy  # noqa: F401  (loaded: OpenBLAS has chosen already)
    env = {}
    assert blas.pin_kernel(env) is None and env == {}
