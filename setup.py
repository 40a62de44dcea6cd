"""Package discovery only; metadata lives in pyproject.toml.

The click commands live in the top-level ``cli/`` folder (fixed by the design card) but install as ``rgbt_cli`` so
the name cannot clash with other distributions' ``cli`` packages.
"""
from setuptools import find_packages, setup

library = find_packages(include=["rgbt_toolkit", "rgbt_toolkit.*"])
commands = ["rgbt_cli." + name for name in find_packages(where="cli")]
setup(
    packages=library + ["rgbt_cli"] + commands,
    package_dir={"rgbt_cli": "cli"},
)
