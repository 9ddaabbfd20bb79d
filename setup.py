"""Builds the extension tetcut._tetcut with the project's CMake, for `pip install .`.

The metadata is in pyproject.toml. The module is CMake's target _tetcut (python/CMakeLists.txt),
built in build/pip (kept, so that reinstalling is incremental), or in the configured build tree
that TETCUT_BUILD_DIR names (e.g. build/release, whose library is already built).
"""

import os
import pathlib
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = pathlib.Path(__file__).resolve().parent


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = pathlib.Path(os.environ.get("TETCUT_BUILD_DIR") or SOURCE / "build" / "pip").resolve()
        if not (build_dir / "CMakeCache.txt").exists():
            subprocess.run(["cmake", "-S", SOURCE, "-B", build_dir, "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                            "-DTETCUT_PYTHON=ON", "-DTETCUT_BUILD_TESTS=OFF", "-DTETCUT_BUILD_BENCH=OFF",
                            "-DTETCUT_WITH_VIEWER=OFF", f"-DPython_EXECUTABLE={sys.executable}"], check=True)
        subprocess.run(["cmake", "--build", build_dir, "--target", "_tetcut", "-j", str(os.cpu_count() or 2)], check=True)
        built = sorted((build_dir / "python" / "tetcut").glob("_tetcut*.so"))
        if not built:
            raise RuntimeError(f"CMake built no _tetcut module in {build_dir}/python/tetcut")
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[-1], target)


setup(ext_modules=[Extension("tetcut._tetcut", sources=[])], cmdclass={"build_ext": CMakeBuild})
