"""ctypes declarations of the C API (include/metariver/metariver.h) and the library loader.

Private: the public interface is metariver.World. Every struct here mirrors the header's
field for field; numpy dtypes mirror mr_water_sample and mr_ray_hit so batches are
written straight into numpy arrays.
"""
from __future__ import annotations

import ctypes
import os
from ctypes import POINTER, c_char, c_char_p, c_double, c_float, c_int, c_int32, c_size_t, c_uint8, c_uint32, c_uint64, c_void_p
from pathlib import Path

import numpy as np

LIBRARY_NAME = "libmetariver.so"
API_VERSION_MAJOR = 1


class Error(RuntimeError):
    """A call into the metariver library failed.

    Attributes:
        status: the C status name, e.g. "MR_ERROR_SCENE".
        code: the C status code (an int, MR_OK = 0 never appears here).
        message: the library's message, naming the argument, scene key or file.
    """

    def __init__(self, message: str, status: str = "MR_ERROR_INTERNAL", code: int = 7) -> None:
        super().__init__(f"{message} [{status}]")
        self.message = message
        self.status = status
        self.code = code


class StaleViewError(Error):
    """A borrowed view (World.particles_view()) was used after the world changed."""

    def __init__(self, message: str) -> None:
        super().__init__(message, "STALE_VIEW", -1)


class mr_error(ctypes.Structure):
    _fields_ = [("code", c_int), ("message", c_char * 512)]


class mr_world_desc(ctypes.Structure):
    _fields_ = [("scene_file", c_char_p), ("scene_toml", c_char_p), ("preset", c_char_p),
                ("heightmap_file", c_char_p), ("heights", POINTER(c_float)),
                ("columns", c_int32), ("rows", c_int32), ("area_scale", c_float),
                ("height_scale", c_float), ("threads", c_int32)]


class mr_stats(ctypes.Structure):
    _fields_ = [("frame", c_uint64), ("time_s", c_double), ("particle_slots", c_uint64),
                ("active_particles", c_uint64), ("tunneled", c_uint64), ("surface_vertices", c_uint64),
                ("surface_triangles", c_uint64), ("simulate_ms", c_double), ("field_ms", c_double),
                ("surface_ms", c_double)]


class mr_particles_view(ctypes.Structure):
    _fields_ = [("positions", POINTER(c_float)), ("velocities", POINTER(c_float)),
                ("active", POINTER(c_uint8)), ("count", c_size_t)]


class mr_surface_view(ctypes.Structure):
    _fields_ = [("positions", POINTER(c_float)), ("normals", POINTER(c_float)), ("vertex_count", c_size_t),
                ("indices", POINTER(c_uint32)), ("index_count", c_size_t)]


class mr_terrain_info(ctypes.Structure):
    _fields_ = [("columns", c_int32), ("rows", c_int32), ("area_scale", c_float), ("min_y", c_float),
                ("max_y", c_float)]


class mr_heightfield_info(ctypes.Structure):
    _fields_ = [("columns", c_int32), ("rows", c_int32), ("spacing", c_float), ("origin", c_float * 2)]


class mr_water_balance(ctypes.Structure):
    _fields_ = [("initial", c_double), ("inflow", c_double), ("rain", c_double), ("outflow", c_double),
                ("sunk", c_double), ("exchanged", c_double), ("stored", c_double), ("error", c_double),
                ("simulated_s", c_double), ("substeps", c_uint64), ("rain_set", c_int32)]


class mr_brush(ctypes.Structure):
    _fields_ = [("x", c_float), ("z", c_float), ("radius", c_float), ("strength", c_float), ("mode", c_int),
                ("target", c_float)]


class mr_body_desc(ctypes.Structure):
    _fields_ = [("shape", c_int32), ("size", c_float * 3), ("mesh", c_char_p), ("density", c_float),
                ("position", c_float * 3), ("rotation", c_float * 3), ("velocity", c_float * 3),
                ("angular_velocity", c_float * 3), ("friction", c_float)]


# mr_body_shape, in its order: the scene file's names of [[bodies]] shape.
BODY_SHAPES = ("box", "sphere", "capsule", "convex_mesh", "triangle_mesh")
# mr_body_state as a numpy record (4-byte fields, no padding).
BODY_STATE_DTYPE = np.dtype([("id", "<u4"), ("shape", "<i4"), ("size", "<f4", (3,)), ("position", "<f4", (3,)),
                             ("orientation", "<f4", (4,)), ("velocity", "<f4", (3,)),
                             ("angular_velocity", "<f4", (3,)), ("mass", "<f4"), ("submerged_fraction", "<f4")])

# mr_water_sample and mr_ray_hit as numpy records (same layout, 4-byte fields, no padding).
WATER_SAMPLE_DTYPE = np.dtype([("surface_y", "<f4"), ("depth", "<f4"), ("velocity", "<f4", (3,)), ("wet", "<i4")])
RAY_HIT_DTYPE = np.dtype([("t", "<f4"), ("point", "<f4", (3,)), ("normal", "<f4", (3,)), ("hit", "<i4")])

_world_p = c_void_p
_f32p = POINTER(c_float)

# name: (restype, argtypes); restype c_int is an mr_status.
_SIGNATURES = {
    "mr_world_desc_default": (mr_world_desc, []),
    "mr_api_version": (c_uint32, []),
    "mr_version_string": (c_char_p, []),
    "mr_status_name": (c_char_p, [c_int]),
    "mr_world_create": (c_int, [POINTER(mr_world_desc), POINTER(_world_p), POINTER(mr_error)]),
    "mr_world_destroy": (None, [_world_p]),
    "mr_world_last_error": (c_char_p, [_world_p]),
    "mr_world_step": (c_int, [_world_p, c_float]),
    "mr_world_stats": (c_int, [_world_p, POINTER(mr_stats)]),
    "mr_world_particles": (c_int, [_world_p, POINTER(mr_particles_view)]),
    "mr_world_copy_particles": (c_int, [_world_p, _f32p, _f32p, c_size_t, POINTER(c_size_t)]),
    "mr_world_surface": (c_int, [_world_p, POINTER(mr_surface_view)]),
    "mr_world_copy_surface": (c_int, [_world_p, _f32p, _f32p, c_size_t, POINTER(c_uint32), c_size_t,
                                      POINTER(c_size_t), POINTER(c_size_t)]),
    "mr_world_terrain": (c_int, [_world_p, POINTER(mr_terrain_info)]),
    "mr_world_copy_terrain_heights": (c_int, [_world_p, _f32p, c_size_t]),
    "mr_world_heightfield": (c_int, [_world_p, POINTER(mr_heightfield_info)]),
    "mr_world_copy_heightfield": (c_int, [_world_p, _f32p, _f32p, _f32p, c_size_t]),
    "mr_world_set_rain": (c_int, [_world_p, _f32p, c_size_t]),
    "mr_world_water_balance": (c_int, [_world_p, POINTER(mr_water_balance)]),
    "mr_world_scene_toml": (c_int, [_world_p, c_char_p, c_size_t, POINTER(c_size_t)]),
    "mr_world_warnings": (c_int, [_world_p, c_char_p, c_size_t, POINTER(c_size_t)]),
    "mr_world_apply_toml": (c_int, [_world_p, c_char_p, POINTER(c_int32)]),
    "mr_world_sculpt": (c_int, [_world_p, POINTER(mr_brush)]),
    "mr_world_pour": (c_int, [_world_p, _f32p, c_int32]),
    "mr_world_push": (c_int, [_world_p, _f32p, c_float, _f32p, POINTER(c_size_t)]),
    "mr_world_move_source": (c_int, [_world_p, _f32p]),
    "mr_world_set_sink_boxes": (c_int, [_world_p, _f32p, c_size_t]),
    "mr_body_desc_default": (mr_body_desc, []),
    "mr_world_add_body": (c_int, [_world_p, POINTER(mr_body_desc), POINTER(c_uint32)]),
    "mr_world_remove_body": (c_int, [_world_p, c_uint32]),
    "mr_world_set_body_motion": (c_int, [_world_p, c_uint32, _f32p, _f32p, _f32p, _f32p]),
    "mr_world_bodies": (c_int, [_world_p, c_void_p, c_size_t, POINTER(c_size_t)]),
    "mr_world_sample_water": (c_int, [_world_p, _f32p, c_size_t, c_void_p]),
    "mr_world_water_velocity": (c_int, [_world_p, _f32p, c_size_t, _f32p]),
    "mr_world_raycast_water": (c_int, [_world_p, _f32p, _f32p, c_size_t, c_float, c_void_p]),
}

_lib: ctypes.CDLL | None = None


def library_path() -> Path:
    """Where the shared library is: the copy next to this package (pip installs one),
    else the file METARIVER_LIBRARY names. Raises Error saying what to do when neither."""
    bundled = Path(__file__).resolve().parent / LIBRARY_NAME
    if bundled.is_file():
        return bundled
    env = os.environ.get("METARIVER_LIBRARY")
    if env:
        path = Path(env)
        if path.is_file():
            return path
        raise Error(f"METARIVER_LIBRARY={env}: no such file (set it to a built libmetariver.so)", "MR_ERROR_IO", 4)
    raise Error(f"{LIBRARY_NAME} not found next to the package ({bundled.parent}) and METARIVER_LIBRARY is "
                "not set: install the package with `pip install python/` from the repository (it builds the "
                "library), or build it (cmake) and set METARIVER_LIBRARY to the built libmetariver.so",
                "MR_ERROR_IO", 4)


def lib() -> ctypes.CDLL:
    """The loaded library with every function's signature declared (loaded once)."""
    global _lib
    if _lib is None:
        path = library_path()
        try:
            handle = ctypes.CDLL(str(path))
        except OSError as exc:
            raise Error(f"{path}: cannot load the library ({exc})", "MR_ERROR_IO", 4) from exc
        for name, (restype, argtypes) in _SIGNATURES.items():
            try:
                fn = getattr(handle, name)
            except AttributeError as exc:
                raise Error(f"{path}: does not export {name} (an older library?)", "MR_ERROR_INTERNAL", 7) from exc
            fn.restype = restype
            fn.argtypes = argtypes
        major = handle.mr_api_version() >> 16
        if major != API_VERSION_MAJOR:
            raise Error(f"{path}: C API major version {major}, this package needs {API_VERSION_MAJOR}",
                        "MR_ERROR_UNSUPPORTED", 5)
        _lib = handle
    return _lib


def status_name(code: int) -> str:
    """The C name of a status code ("MR_ERROR_SCENE", ...)."""
    return lib().mr_status_name(code).decode()


def f32p(array: np.ndarray):
    """A float* to a C-contiguous float32 array (None stays NULL)."""
    if array is None:
        return None
    return array.ctypes.data_as(_f32p)
