# setuptools driving the project's CMake for `pip install .` (see pyproject.toml): configures a
# Release build with the Python module and the `omma` command-line binary (no tests, no benchmarks)
# in the build_temp folder (or $OMMA_CMAKE_BUILD_DIR, e.g. to reuse one between installs), puts
# omma/_omma*.so into the package being built and the binary into omma/bin/omma, which the
# package's `omma` console command (omma._cli, [project.scripts]) executes.
# $CMAKE_BUILD_PARALLEL_LEVEL limits the compile jobs. $OMMA_PREBUILT_DIR=BUILD packages what an
# existing build folder holds instead (BUILD/python/omma/_omma*.so and BUILD/omma, built with
# OMMA_PYTHON=ON for the same interpreter): no compiler run, e.g. to package a CI build.
import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def _install_binary(binary, out_dir):
    """Copies the omma binary into the package: omma/bin/omma (executable)."""
    if not Path(binary).is_file():
        raise RuntimeError(f"omma: the omma binary {binary} was not built")
    (out_dir / "bin").mkdir(parents=True, exist_ok=True)
    dest = out_dir / "bin" / "omma"
    shutil.copy2(binary, dest)
    dest.chmod(0o755)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        out_dir = Path(self.get_ext_fullpath(ext.name)).resolve().parent
        prebuilt = os.environ.get("OMMA_PREBUILT_DIR")
        if prebuilt:
            pre = Path(prebuilt).resolve()
            modules = sorted((pre / "python" / "omma").glob("_omma*.so"))
            if not modules:
                raise RuntimeError(f"omma: OMMA_PREBUILT_DIR={pre} holds no python/omma/_omma*.so")
            out_dir.mkdir(parents=True, exist_ok=True)
            shutil.copy2(modules[0], Path(self.get_ext_fullpath(ext.name)))
            _install_binary(pre / "omma", out_dir)
            return
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
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "_omma", "omma", "-j", jobs], check=True)
        _install_binary(build_dir / "omma", out_dir)


setup(ext_modules=[Extension("omma._omma", sources=[])], cmdclass={"build_ext": CMakeBuild})
