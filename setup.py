"""Builds the Python package atmo with CMake (pyproject.toml; docs/python.md).

`pip install --no-build-isolation .` configures a CMake build of the library and its bindings
(tests, benchmarks, viewer and install rules off) under build/python-package and copies the
compiled module beside atmo/__init__.py. ATMO_BUILD_DIR=DIR builds the target atmo_python in an
existing, configured CMake build instead (what the test of the package does). CMAKE_ARGS adds
arguments to the configure step (e.g. -DATMO_GL=OFF); CMAKE_BUILD_PARALLEL_LEVEL sets the jobs.
"""
import os
import re
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))


def version() -> str:
    with open(os.path.join(HERE, "CMakeLists.txt"), encoding="utf-8") as f:
        match = re.search(r"project\(atmo VERSION ([0-9.]+)", f.read())
    if not match:
        raise RuntimeError("no `project(atmo VERSION ...)` in CMakeLists.txt")
    return match.group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext: Extension) -> None:
        build_dir = os.environ.get("ATMO_BUILD_DIR")
        if not build_dir:
            build_dir = os.path.join(HERE, "build", "python-package")
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []
            subprocess.run(
                ["cmake", "-S", HERE, "-B", build_dir, *generator, "-DCMAKE_BUILD_TYPE=Release",
                 "-DATMO_BUILD_TESTS=OFF", "-DATMO_BUILD_BENCHMARKS=OFF", "-DATMO_BUILD_VIEWER=OFF",
                 "-DATMO_INSTALL=OFF", "-DATMO_PYTHON=ON", f"-DPython_EXECUTABLE={sys.executable}",
                 *shlex.split(os.environ.get("CMAKE_ARGS", ""))],
                check=True)
        subprocess.run(["cmake", "--build", build_dir, "--target", "atmo_python"], check=True)
        package = os.path.join(build_dir, "python", "atmo")
        built = [name for name in os.listdir(package) if name.startswith("_atmo") and name.endswith(".so")]
        if len(built) != 1:
            raise RuntimeError(f"expected one compiled module _atmo*.so in {package}, found {built}")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(package, built[0]), target)


setup(
    version=version(),
    packages=["atmo"],
    package_dir={"atmo": "python/atmo"},
    package_data={"atmo": ["py.typed", "_atmo.pyi"]},
    ext_modules=[Extension("atmo._atmo", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": os.path.join("build", "setuptools")},
             "egg_info": {"egg_base": os.path.join("build", "setuptools")}},
    zip_safe=False,
)
