"""metariver: a real-time river simulation (PBF particles, metaball surface) for Python.

ctypes over the library's C API (include/metariver/metariver.h). Start with::

    import metariver
    with metariver.World() as world:          # the default river on the procedural valley
        world.step(frames=60)
        positions, velocities = world.particles()   # copies, (N, 3) float32
        vertices, normals, indices = world.surface()
        log = world.add_body("box", (3.0, 0.4, 0.4), density=600.0, position=(30.0, 20.0, 80.0))
        world.step(frames=60)
        world.bodies()["position"]               # a record array, one row per body

What is a copy and what is a view: particles(), surface(), terrain_heights() and the
query results are copies the caller owns; particles_view() gives read-only numpy views
of the world's own arrays, valid until the next step or edit (using a stale view raises
StaleViewError). The shared library is the copy installed next to this package, or the
file the METARIVER_LIBRARY environment variable names.
"""
from __future__ import annotations

from ._capi import BODY_SHAPES, BODY_STATE_DTYPE, RAY_HIT_DTYPE, WATER_SAMPLE_DTYPE, Error, StaleViewError, library_path
from ._capi import lib as _lib
from .world import Heightfield, Particles, ParticlesView, Stats, Surface, TerrainInfo, WaterBalance, World

try:  # written by setup.py when installed
    from ._version import __version__
except ImportError:  # the source tree: the project's version from CMakeLists.txt
    import re as _re
    from pathlib import Path as _Path

    _cm = (_Path(__file__).resolve().parents[2] / "CMakeLists.txt")
    _m = _re.search(r"project\(\s*metariver\s+VERSION\s+([0-9.]+)", _cm.read_text()) if _cm.is_file() else None
    __version__ = _m.group(1) if _m else "0+unknown"

__all__ = ["World", "Error", "StaleViewError", "Stats", "TerrainInfo", "Heightfield", "WaterBalance", "Particles",
           "ParticlesView", "Surface",
           "WATER_SAMPLE_DTYPE", "RAY_HIT_DTYPE", "BODY_SHAPES", "BODY_STATE_DTYPE", "api_version", "version_string",
           "library_path", "__version__"]


def api_version() -> tuple[int, int]:
    """The loaded library's C API version as (major, minor)."""
    v = _lib().mr_api_version()
    return v >> 16, v & 0xFFFF


def version_string() -> str:
    """The loaded library's version, e.g. "metariver 0.1.0 (commit ...)"."""
    return _lib().mr_version_string().decode()
