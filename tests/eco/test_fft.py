"""ECO's real 2-D FFT: SciPy's pocketfft loaded without ``import scipy.fft`` (0.35-0.4 s of start-up)."""

import subprocess
import sys

import numpy as np
import pytest

from rgbt_toolkit.eco import _fft


@pytest.mark.parametrize("shape, dtype", [((7, 10, 63, 63), np.float32), ((3, 9, 8), np.float64), ((5, 4), np.float32)])
def test_the_same_bits_as_scipy_fft(shape, dtype):
    from scipy import fft as sp_fft

    x = np.random.default_rng(sum(shape)).random(shape).astype(dtype)
    got = _fft.rfft2(x)
    np.testing.assert_array_equal(got, sp_fft.rfft2(x, axes=(-2, -1)))
    assert got.dtype == sp_fft.rfft2(x, axes=(-2, -1)).dtype


def test_without_the_module_file_scipy_fft_gives_the_same_results(monkeypatch):
    from scipy import fft as sp_fft

    monkeypatch.setattr(_fft, "_loaded", [None])  # as if this SciPy kept pocketfft elsewhere
    x = np.random.default_rng(2).random((2, 6, 7)).astype(np.float32)
    np.testing.assert_array_equal(_fft.rfft2(x), sp_fft.rfft2(x, axes=(-2, -1)))


def test_the_tracker_path_does_not_import_scipy_fft_and_scipy_fft_still_works_after_it():
    code = (
        "import sys, numpy as np\n"
        "from rgbt_toolkit.eco.fourier import cfft2\n"
        "x = np.random.default_rng(0).random((2, 3, 9, 9)).astype(np.float32)\n"
        "a = cfft2(x)\n"
        "print('scipy.fft' in sys.modules, 'scipy.special' in sys.modules)\n"
        "from scipy import fft\n"  # SciPy must find the module already loaded, not initialise it a second time
        "print(np.array_equal(a, cfft2(x)), np.array_equal(fft.rfft2(x), fft.rfft2(x.copy())))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["False", "False", "True", "True"]
