"""Package discovery and the compiled modules; metadata lives in pyproject.toml.

The click commands live in the top-level ``cli/`` folder (fixed by the design card) but install as ``rgbt_cli`` so
the name cannot clash with other distributions' ``cli`` packages.
"""
from setuptools import Extension, find_packages, setup

library = find_packages(include=["rgbt_toolkit", "rgbt_toolkit.*"])
commands = ["rgbt_cli." + name for name in find_packages(where="cli")]
setup(
    packages=library + ["rgbt_cli"] + commands,
    package_dir={"rgbt_cli": "cli"},
    # ECO's feature loops (rgbt_toolkit/features/_kernels.c) and filter arithmetic (rgbt_toolkit/eco/_spectra.c):
    # plain C against the CPython API, no numpy headers. No implicit fused multiply-add (-ffp-contract=off), so the
    # results match the numpy definitions the tests compare against.
    ext_modules=[Extension(name, [source], extra_compile_args=["-O3", "-ffp-contract=off"])
                 for name, source in (("rgbt_toolkit.features._kernels", "rgbt_toolkit/features/_kernels.c"),
                                      ("rgbt_toolkit.eco._spectra", "rgbt_toolkit/eco/_spectra.c"))],
)
