"""Builds the dsreg Python package (pyproject.toml): the module dsreg._dsreg is the CMake target
_dsreg of CMakeLists.txt (option DSREG_BUILD_PYTHON), built for the interpreter running pip.

Environment:
  DSREG_CMAKE_BUILD_DIR  an existing CMake build tree of this source, configured with
                         -DDSREG_BUILD_PYTHON=ON for the same Python: its module is built there
                         (usually nothing to do) instead of configuring a new tree. The test
                         suite's install test uses it.
  DSREG_CMAKE_ARGS       extra arguments for the configure step, e.g.
                         "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache".
  CMAKE_BUILD_PARALLEL_LEVEL  parallel jobs (default: every core).
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version() -> str:
    """The version of CMakeLists.txt's project(), the one source of it."""
    match = re.search(r"project\(dsreg VERSION ([0-9.]+)", (ROOT / "CMakeLists.txt").read_text())
    return match.group(1)


def run(command):
    print(" ".join(str(c) for c in command), flush=True)
    subprocess.run([str(c) for c in command], check=True)


class CMakeBuild(build_ext):
    """Builds the extension with CMake instead of setuptools' compiler calls."""

    def build_extension(self, ext):
        build_dir = os.environ.get("DSREG_CMAKE_BUILD_DIR")
        if build_dir:
            build_dir = Path(build_dir).resolve()
        else:
            build_dir = Path(self.build_temp).resolve() / "cmake"
            run(["cmake", "-S", ROOT, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release", "-DDSREG_BUILD_PYTHON=ON",
                 "-DDSREG_BUILD_TESTS=OFF", "-DDSREG_BUILD_BENCHMARKS=OFF", f"-DPython_EXECUTABLE={sys.executable}",
                 *shlex.split(os.environ.get("DSREG_CMAKE_ARGS", ""))])
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL") or str(os.cpu_count() or 1)
        run(["cmake", "--build", build_dir, "--target", "_dsreg", "--parallel", jobs])
        built = build_dir / "python" / "dsreg" / ("_dsreg" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.exists():
            raise RuntimeError(f"{built} was not built: is {build_dir} configured with -DDSREG_BUILD_PYTHON=ON "
                               f"and -DPython_EXECUTABLE for this Python ({sys.executable})?")
        destination = Path(self.get_ext_fullpath(ext.name))
        destination.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built, destination)


setup(
    version=project_version(),
    ext_modules=[Extension("dsreg._dsreg", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
)
