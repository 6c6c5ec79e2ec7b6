"""Builds the metariver package: the Python modules plus the shared library libmetariver.so.

The library comes from METARIVER_LIBRARY when that names a built libmetariver.so (copied,
so a test that already built it does not build it twice), else from a CMake build of the
repository this folder sits in (only the shared library target, without render, export,
tests and bench; METARIVER_BUILD_TYPE, default RelWithDebInfo), in build/python-wheel of
the repository. Offline:
    /usr/bin/python3 -m pip install --no-build-isolation --no-deps .
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py as _build_py

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
LIBRARY = "libmetariver.so"
# The CMake target of the shared library (CMakeLists.txt of the repository).
TARGET = os.environ.get("METARIVER_CMAKE_TARGET", "metariver_lib")


def project_version() -> str:
    """The project's version: project(metariver VERSION x.y.z) in the top CMakeLists.txt."""
    text = (ROOT / "CMakeLists.txt").read_text()
    match = re.search(r"project\(\s*metariver\s+VERSION\s+([0-9.]+)", text)
    if not match:
        raise RuntimeError(f"{ROOT / 'CMakeLists.txt'}: no `project(metariver VERSION ...)`")
    return match.group(1)


def built_library() -> Path:
    """METARIVER_LIBRARY's file, or the library CMake builds from the repository."""
    given = os.environ.get("METARIVER_LIBRARY")
    if given:
        path = Path(given)
        if not path.is_file():
            raise RuntimeError(f"METARIVER_LIBRARY={given}: no such file (unset it to build the library with CMake)")
        return path
    build = ROOT / "build" / "python-wheel"
    # the project's default build type (its compile lines, so a shared ccache serves them)
    build_type = os.environ.get("METARIVER_BUILD_TYPE", "RelWithDebInfo")
    configure = ["cmake", "-S", str(ROOT), "-B", str(build), f"-DCMAKE_BUILD_TYPE={build_type}",
                 "-DMETARIVER_WITH_RENDER=OFF", "-DMETARIVER_WITH_EXPORT=OFF",
                 "-DMETARIVER_BUILD_TESTS=OFF", "-DMETARIVER_BUILD_BENCH=OFF"]
    if shutil.which("ninja"):
        configure += ["-G", "Ninja"]
    subprocess.run(configure, check=True)
    subprocess.run(["cmake", "--build", str(build), "--target", TARGET, "-j", str(os.cpu_count() or 2)], check=True)
    found = sorted(p for p in build.rglob(LIBRARY + "*") if p.is_file() and not p.is_symlink())
    if not found:
        raise RuntimeError(f"the CMake build in {build} made no {LIBRARY} (target {TARGET})")
    return found[0]


class build_py(_build_py):
    """The modules, then the library and _version.py beside them."""

    def run(self) -> None:
        super().run()
        package = Path(self.build_lib) / "metariver"
        package.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built_library(), package / LIBRARY)
        (package / "_version.py").write_text(f'__version__ = "{project_version()}"\n')


class BinaryDistribution(Distribution):
    """The wheel carries a native library: tag it for this platform."""

    def has_ext_modules(self) -> bool:
        return True


setup(version=project_version(), cmdclass={"build_py": build_py}, distclass=BinaryDistribution)
