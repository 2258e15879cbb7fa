"""Builds the cffi extension ``virtual_drive._core`` (the virtual drive's C core)."""

from setuptools import setup

setup(cffi_modules=["virtual_drive/_build_core.py:ffibuilder"])
