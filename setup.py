"""Builds the one compiled piece: the library that gives every x86 CPU vendor MKL's Intel code path
(neurosym_cli/utils/mkl_intel_path.c; loaded by neurosym_cli/utils/cpu.py). Everything else is in pyproject.toml.
The build is optional: without a C compiler the install goes on, and the runtime record says the vendor's own MKL
path was used."""

import platform

from setuptools import Extension, setup

x86_linux = platform.system() == "Linux" and platform.machine().lower() in ("x86_64", "amd64")
setup(ext_modules=[Extension("neurosym_cli.utils._mkl_intel_path", ["neurosym_cli/utils/mkl_intel_path.c"],
                             optional=True, py_limited_api=False)] if x86_linux else [])
