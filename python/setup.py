"""setup.py: builds the cffi extension cbvh._native over libcbvh (see native_build.py for where the library
comes from) and ships the cbvh command built beside it, which cbvh.cook_file runs."""
import os
import shutil
import sys

from setuptools import setup
from setuptools.command.build_ext import build_ext

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import native_build  # noqa: E402


class build_ext_with_library(build_ext):
    def run(self):
        native_build.build()
        super().run()
        tool = native_build.tool_path()
        if tool:
            target = os.path.join(self.build_lib, "cbvh", "bin")
            os.makedirs(target, exist_ok=True)
            shutil.copy2(tool, os.path.join(target, "cbvh"))


setup(cffi_modules=["build_ffi.py:ffibuilder"], cmdclass={"build_ext": build_ext_with_library})
