"""Builds tsmcodec's extension with CMake (pyproject.toml names this backend).

Configures this project with only the libraries and the Python module
(TSM_PYTHON=ON, no tests, tool or -Werror) for the running Python, builds
_tsmcodec and puts it into the package. TSM_CMAKE_ARGS adds arguments.
"""
import os
import shlex
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        out = Path(self.get_ext_fullpath(ext.name)).resolve().parent
        build = Path(self.build_temp).resolve() / "cmake"
        args = [
            "-DCMAKE_BUILD_TYPE=Release", "-DTSM_PYTHON=ON", "-DTSM_BUILD_TESTS=OFF", "-DTSM_BUILD_TOOLS=OFF",
            "-DTSM_INSTALL=OFF", "-DTSM_WERROR=OFF", f"-DTSM_PYTHON_EXECUTABLE={sys.executable}",
        ]
        try:  # pybind11 from the build requirements; else CMake finds Debian's pybind11-dev
            import pybind11
            args.append(f"-Dpybind11_DIR={pybind11.get_cmake_dir()}")
        except ImportError:
            pass
        args += shlex.split(os.environ.get("TSM_CMAKE_ARGS", ""))
        subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build)] + args, check=True)
        subprocess.run(["cmake", "--build", str(build), "--target", "_tsmcodec", "-j", str(os.cpu_count() or 2)],
                       check=True)
        built = next((build / "python" / "tsmcodec").glob("_tsmcodec*"))
        out.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built), str(out / built.name))


setup(ext_modules=[Extension("tsmcodec._tsmcodec", sources=[])], cmdclass={"build_ext": CMakeBuild})
