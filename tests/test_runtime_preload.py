"""runtime.preload: imports on a background thread that later imports wait for, and errors left to the real import."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def _run(code: str) -> str:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout.strip()


def test_preload_imports_on_another_thread_and_a_later_import_gets_the_module():
    printed = _run("""
        import sys, threading, numpy
        from rgbt_toolkit.runtime import preload
        assert "scipy.fft" not in sys.modules
        preload("scipy.fft")
        worker = next(t for t in threading.enumerate() if t.name == "rgbt-preload")
        from scipy import fft  # waits for the preload's import if it is still running
        worker.join(60)
        print(fft.rfft2 is sys.modules["scipy.fft"].rfft2, not worker.is_alive())
    """)
    assert printed == "True True"


def test_a_failing_preload_is_silent_and_the_real_import_reports_it():
    printed = _run("""
        import threading, numpy
        from rgbt_toolkit.runtime import preload
        preload("no_such_module_rgbt")
        for t in threading.enumerate():
            if t.name == "rgbt-preload":
                t.join(10)
        try:
            import no_such_module_rgbt
        except ModuleNotFoundError as exc:
            print("reported:", exc.name)
    """)
    assert printed == "reported: no_such_module_rgbt"
