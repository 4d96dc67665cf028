# setuptools driving the project's CMake for `pip install .` (see pyproject.toml): configures a
# Release build with only the Python module (no tests, no benchmarks) in the build_temp folder (or
# $OMMA_CMAKE_BUILD_DIR, e.g. to reuse one between installs) and puts omma/_omma*.so into the
# package being built. $CMAKE_BUILD_PARALLEL_LEVEL limits the compile jobs.
import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        out_dir = Path(self.get_ext_fullpath(ext.name)).resolve().parent
        build_dir = Path(os.environ.get("OMMA_CMAKE_BUILD_DIR") or Path(self.build_temp) / "cmake").resolve()
        args = ["-S", str(ROOT), "-B", str(build_dir), "-DCMAKE_BUILD_TYPE=Release", "-DOMMA_PYTHON=ON",
                "-DOMMA_BUILD_TESTS=OFF", "-DOMMA_BUILD_BENCH=OFF", "-DCMAKE_POSITION_INDEPENDENT_CODE=ON",
                f"-DPython_EXECUTABLE={sys.executable}", f"-DOMMA_PYTHON_INSTALL_DIR={out_dir}"]
        try:  # pybind11 from the build environment (PyPI or Debian's python3-pybind11), if importable
            import pybind11
            args.append(f"-Dpybind11_DIR={pybind11.get_cmake_dir()}")
        except ImportError:
            pass
        if shutil.which("ninja"):
            args += ["-G", "Ninja"]
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 2))
        subprocess.run(["cmake", *args], check=True)
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "_omma", "-j", jobs], check=True)


setup(ext_modules=[Extension("omma._omma", sources=[])], cmdclass={"build_ext": CMakeBuild})
