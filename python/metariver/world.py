"""metariver.World: one river simulation (a handle to the C API's mr_world)."""
from __future__ import annotations

import ctypes
import math
import os
import tomllib
from dataclasses import dataclass
from typing import Any, Mapping, NamedTuple

import numpy as np

from . import _capi, _toml
from ._capi import Error, StaleViewError, f32p

_BRUSH_MODES = {"raise": 0, "lower": 1, "smooth": 2, "flatten": 3}


@dataclass(frozen=True)
class Stats:
    """Counters and timings of the latest frame (mr_stats)."""
    frame: int                 #: frames stepped
    time_s: float              #: simulated seconds
    particle_slots: int        #: particle array length (active or not)
    active_particles: int      #: live particles
    tunneled: int              #: particles that crossed the terrain (before any correction)
    surface_vertices: int      #: vertices of the water surface mesh
    surface_triangles: int     #: triangles of the water surface mesh
    simulate_ms: float         #: the latest frame's solver time
    field_ms: float            #: the latest frame's field time
    surface_ms: float          #: the latest frame's surface time


@dataclass(frozen=True)
class TerrainInfo:
    """The terrain as built: samples, spacing and the ground's height range (metres)."""
    columns: int
    rows: int
    area_scale: float
    min_y: float
    max_y: float


class Heightfield(NamedTuple):
    """The water as a grid (solver = "swe"), copies: depth (rows, columns) in metres (0: dry),
    velocity (rows, columns, 2) x and z in m/s, bed (rows, columns) the ground in metres;
    spacing (m) between cells, origin (x, z) of cell [0, 0]."""
    depth: np.ndarray
    velocity: np.ndarray
    bed: np.ndarray
    spacing: float
    origin: tuple[float, float]


@dataclass(frozen=True)
class WaterBalance:
    """The shallow-water grid's volumes in m^3 since frame 0 (mr_water_balance)."""
    initial: float      #: in the grid at frame 0 (a lake, the steady river)
    inflow: float       #: the sources' discharge and what pour() poured
    rain: float         #: rained
    outflow: float      #: left over the map's edges
    sunk: float         #: taken by [[swe.sinks]] and the sea (swe.sea_level)
    exchanged: float    #: net volume the hybrid's particles gave the grid (negative: took)
    stored: float       #: in the grid now
    error: float        #: initial + inflow + rain + exchanged - outflow - sunk - stored: round-off
    simulated_s: float  #: the grid's simulated seconds since frame 0 (dt x swe.time_scale, summed)
    substeps: int       #: time steps taken under the CFL limit since frame 0
    rain_set: bool      #: whether set_rain()'s rates replace the scene's rain


class Particles(NamedTuple):
    """Copies of the active particles: positions and velocities, (N, 3) float32."""
    positions: np.ndarray
    velocities: np.ndarray


class Surface(NamedTuple):
    """Copies of the water surface: vertices, unit normals (V, 3) float32 and triangles (T, 3) uint32,
    counter-clockwise seen from outside the water."""
    vertices: np.ndarray
    normals: np.ndarray
    indices: np.ndarray


class ParticlesView:
    """Read-only numpy views of the world's own particle arrays (no copy), every slot.

    Valid until the world next changes (step, apply, sculpt, pour, push, move_source,
    set_sink_boxes, a body's add, remove or motion, close): reading a property after that raises StaleViewError. Arrays
    taken out of the view are not checked; copy them (np.array(view.positions)) to keep them.
    """

    def __init__(self, world: "World", raw: _capi.mr_particles_view) -> None:
        self._world = world
        self._generation = world._generation
        n = int(raw.count)
        self._arrays = {
            "positions": _borrow(raw.positions, (n, 3)),
            "velocities": _borrow(raw.velocities, (n, 3)),
            "active": _borrow(raw.active, (n,)).view(np.bool_),
        }

    def _get(self, name: str) -> np.ndarray:
        if self._world._generation != self._generation:
            raise StaleViewError(f"particles_view().{name}: the world changed since the view was taken "
                                 "(views are valid until the next step or edit); take a new view")
        return self._arrays[name]

    @property
    def valid(self) -> bool:
        """Whether the view still shows the world's current arrays."""
        return self._world._generation == self._generation

    @property
    def positions(self) -> np.ndarray:
        """(slots, 3) float32, read-only; inactive slots hold stale values."""
        return self._get("positions")

    @property
    def velocities(self) -> np.ndarray:
        """(slots, 3) float32, read-only."""
        return self._get("velocities")

    @property
    def active(self) -> np.ndarray:
        """(slots,) bool, read-only: True for a live particle."""
        return self._get("active")


def _borrow(ptr, shape: tuple[int, ...]) -> np.ndarray:
    """A read-only numpy view of C memory (an empty array for a NULL pointer or no elements)."""
    ctype = ptr._type_
    dtype = np.dtype(ctype)
    if not ptr or math.prod(shape) == 0:
        return np.zeros(shape, dtype)
    array = np.ctypeslib.as_array(ptr, shape=shape)
    array.flags.writeable = False
    return array


def _vec3(name: str, value: Any) -> np.ndarray:
    v = np.asarray(value, dtype=np.float64)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: expected 3 finite numbers (x, y, z), got {value!r}")
    return np.ascontiguousarray(v, dtype=np.float32)


def _points(name: str, value: Any, width: int) -> np.ndarray:
    """A (..., width) array of real numbers as C-contiguous float32. NaN and infinity pass:
    the queries answer such a point alone as dry / zero velocity / no hit (as C and C++ do)."""
    v = np.asarray(value)
    if v.dtype.kind not in "fiu" or v.ndim < 1 or v.shape[-1] != width:
        raise ValueError(f"{name}: expected an array of shape (..., {width}) of real numbers, "
                         f"got shape {v.shape} dtype {v.dtype}")
    return np.ascontiguousarray(v, dtype=np.float32)


def check_heights(heights: Any) -> np.ndarray:
    """heights as C-contiguous float32 rows x columns, or ValueError naming `heights` and the ranges."""
    h = np.asarray(heights)
    if h.dtype.kind != "f":
        raise ValueError(f"heights: expected a 2D array of floats in [0, 1], got dtype {h.dtype}")
    if h.ndim != 2 or not (2 <= h.shape[0] <= 4097 and 2 <= h.shape[1] <= 4097):
        raise ValueError(f"heights: expected a 2D array rows x columns, each in [2, 4097], got shape {h.shape}")
    if not np.all(np.isfinite(h)):
        raise ValueError("heights: contains NaN or infinity; every height must be in [0, 1]")
    lo, hi = float(h.min()), float(h.max())
    if lo < 0.0 or hi > 1.0:
        raise ValueError(f"heights: values span [{lo:g}, {hi:g}]; every height must be in [0, 1]")
    return np.ascontiguousarray(h, dtype=np.float32)


def _rain_rates(mm_per_h: Any, shape: tuple[int, int]) -> np.ndarray:
    """mm_per_h as C-contiguous float32 of the grid's shape, or ValueError naming it and the ranges."""
    r = np.asarray(mm_per_h)
    if r.dtype.kind not in "fiu":
        raise ValueError(f"mm_per_h: expected an array of real numbers (mm/h), got dtype {r.dtype}")
    if r.shape != shape:
        raise ValueError(f"mm_per_h: expected shape {shape} (the grid's rows, columns), got {r.shape}")
    bad = ~((r >= 0) & (r <= 1e4))  # NaN compares false: caught too
    if bad.any():
        row, column = (int(x) for x in np.argwhere(bad)[0])
        raise ValueError(f"mm_per_h[{row}, {column}]: must be finite in [0, 10000] mm/h, got {r[row, column]!r} "
                         f"({int(bad.sum())} such cells)")
    return np.ascontiguousarray(r, dtype=np.float32)


def _body_id(id: Any) -> None:
    if not isinstance(id, (int, np.integer)) or not 0 <= id <= 2**32 - 1:
        raise ValueError(f"id: expected an integer in [0, 4294967295], got {id!r}")


def _path_bytes(name: str, value: Any) -> bytes | None:
    if value is None:
        return None
    if not isinstance(value, (str, os.PathLike)):
        raise ValueError(f"{name}: expected a file path, got {type(value).__name__}")
    return os.fsencode(value)


class World:
    """A river simulation: terrain, water particles and the water surface.

    Create it from at most one of `scene` (a scene TOML file), `toml` (TOML text or a
    dict of keys over the default scene) and `preset` (a built-in preset name); none
    gives the default river on the procedural valley. The terrain can be replaced by a
    PNG (`heightmap`) or a numpy array (`heights`: rows x columns, each in [0, 1], row
    along +z, column along +x), scaled by `area_scale` (metres between samples) and
    `height_scale` (metres for a height of 1); 0 keeps the scene's. `threads` bounds the
    threads the world's work uses (0: every core).

    A World is used by one thread at a time. Close it (or use `with World() as w:`) to
    free its memory at once; the garbage collector does it otherwise.
    """

    def __init__(self, scene: str | os.PathLike | None = None, toml: str | Mapping[str, Any] | None = None,
                 preset: str | None = None, heightmap: str | os.PathLike | None = None,
                 heights: Any = None, area_scale: float = 0.0, height_scale: float = 0.0,
                 threads: int = 0) -> None:
        self._handle: ctypes.c_void_p | None = None
        self._generation = 0
        lib = _capi.lib()
        if sum(x is not None for x in (scene, toml, preset)) > 1:
            raise ValueError("scene, toml, preset: give at most one of them")
        if heightmap is not None and heights is not None:
            raise ValueError("heightmap, heights: give at most one of them")
        for name, value in (("area_scale", area_scale), ("height_scale", height_scale)):
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a finite number >= 0 (0: the scene's), got {value!r}")
        if not isinstance(threads, (int, np.integer)) or not 0 <= threads <= 2**31 - 1:
            raise ValueError(f"threads: expected an integer >= 0 (0: every core), got {threads!r}")
        desc = lib.mr_world_desc_default()
        desc.scene_file = _path_bytes("scene", scene)
        if isinstance(toml, Mapping):
            toml = _toml.dumps(toml)
        if toml is not None and not isinstance(toml, str):
            raise ValueError(f"toml: expected TOML text or a dict, got {type(toml).__name__}")
        desc.scene_toml = toml.encode() if toml is not None else None
        desc.preset = preset.encode() if preset is not None else None
        desc.heightmap_file = _path_bytes("heightmap", heightmap)
        if heights is not None:
            self._heights = check_heights(heights)  # kept alive during create
            desc.heights = f32p(self._heights)
            desc.rows, desc.columns = self._heights.shape
        desc.area_scale = float(area_scale)
        desc.height_scale = float(height_scale)
        desc.threads = int(threads)
        handle = ctypes.c_void_p()
        err = _capi.mr_error()
        status = lib.mr_world_create(ctypes.byref(desc), ctypes.byref(handle), ctypes.byref(err))
        self._heights = None
        if status != 0:
            raise Error(err.message.decode(errors="replace"), _capi.status_name(status), status)
        self._handle = handle

    # -- lifetime -------------------------------------------------------------------------
    def close(self) -> None:
        """Destroys the world (frees its memory); later calls raise metariver.Error. Idempotent."""
        if self._handle is not None:
            _capi.lib().mr_world_destroy(self._handle)
            self._handle = None
            self._generation += 1

    def __enter__(self) -> "World":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # interpreter shutdown: the library may be gone
            pass

    @property
    def closed(self) -> bool:
        """Whether close() was called."""
        return self._handle is None

    def _h(self) -> ctypes.c_void_p:
        if self._handle is None:
            raise Error("the world is closed", "MR_ERROR_NULL_ARGUMENT", 1)
        return self._handle

    def _check(self, status: int) -> None:
        if status != 0:
            message = _capi.lib().mr_world_last_error(self._handle).decode(errors="replace")
            raise Error(message, _capi.status_name(status), status)

    def _changed(self) -> None:
        self._generation += 1

    # -- stepping and reading -------------------------------------------------------------
    def step(self, dt: float = 1.0 / 60.0, frames: int = 1) -> None:
        """Advances `frames` frames of `dt` seconds each (dt in (0, 1]): the solver's substeps,
        then the surface. Invalidates views."""
        if not isinstance(frames, int) or frames < 0:
            raise ValueError(f"frames: expected an integer >= 0, got {frames!r}")
        h, lib = self._h(), _capi.lib()
        for _ in range(frames):
            self._changed()
            self._check(lib.mr_world_step(h, float(dt)))

    @property
    def stats(self) -> Stats:
        """Counters and stage times of the latest frame (a Stats dataclass)."""
        s = _capi.mr_stats()
        self._check(_capi.lib().mr_world_stats(self._h(), ctypes.byref(s)))
        return Stats(*(getattr(s, name) for name, _ in _capi.mr_stats._fields_))

    def particles(self) -> Particles:
        """Copies of the ACTIVE particles in index order: (positions, velocities), each (N, 3) float32."""
        h, lib = self._h(), _capi.lib()
        n = self.stats.active_particles
        while True:
            pos = np.empty((n, 3), np.float32)
            vel = np.empty((n, 3), np.float32)
            count = ctypes.c_size_t()
            status = lib.mr_world_copy_particles(h, f32p(pos), f32p(vel), n, ctypes.byref(count))
            if status == 6 and count.value > n:  # MR_ERROR_BUFFER_TOO_SMALL: grow and retry
                n = count.value
                continue
            self._check(status)
            return Particles(pos[:count.value], vel[:count.value])

    def particles_view(self) -> ParticlesView:
        """Borrowed, read-only views of every particle slot (positions, velocities, active), no
        copy: valid until the world next changes; using it after that raises StaleViewError."""
        raw = _capi.mr_particles_view()
        self._check(_capi.lib().mr_world_particles(self._h(), ctypes.byref(raw)))
        return ParticlesView(self, raw)

    def surface(self) -> Surface:
        """Copies of the latest frame's water surface: (vertices, normals, indices)."""
        h, lib = self._h(), _capi.lib()
        nv, ni = ctypes.c_size_t(), ctypes.c_size_t()
        self._check(lib.mr_world_copy_surface(h, None, None, 0, None, 0, ctypes.byref(nv), ctypes.byref(ni)))
        v = np.empty((nv.value, 3), np.float32)
        n = np.empty((nv.value, 3), np.float32)
        i = np.empty((ni.value // 3, 3), np.uint32)
        self._check(lib.mr_world_copy_surface(h, f32p(v), f32p(n), nv.value, i.ctypes.data_as(
            ctypes.POINTER(ctypes.c_uint32)), ni.value, ctypes.byref(nv), ctypes.byref(ni)))
        return Surface(v, n, i)

    @property
    def terrain(self) -> TerrainInfo:
        """The terrain as built: columns, rows, area_scale (m), min_y and max_y (m)."""
        t = _capi.mr_terrain_info()
        self._check(_capi.lib().mr_world_terrain(self._h(), ctypes.byref(t)))
        return TerrainInfo(t.columns, t.rows, t.area_scale, t.min_y, t.max_y)

    def terrain_heights(self) -> np.ndarray:
        """Ground heights in metres, a (rows, columns) float32 copy (after conditioning and sculpting)."""
        t = self.terrain
        out = np.empty((t.rows, t.columns), np.float32)
        self._check(_capi.lib().mr_world_copy_terrain_heights(self._h(), f32p(out), out.size))
        return out

    def heightfield(self) -> Heightfield:
        """The shallow-water grid of the latest frame (copies); Error for a world whose water
        is particles (the C API's MR_ERROR_UNSUPPORTED)."""
        h, lib = self._h(), _capi.lib()
        info = _capi.mr_heightfield_info()
        self._check(lib.mr_world_heightfield(h, ctypes.byref(info)))
        depth = np.empty((info.rows, info.columns), np.float32)
        velocity = np.empty((info.rows, info.columns, 2), np.float32)
        bed = np.empty((info.rows, info.columns), np.float32)
        self._check(lib.mr_world_copy_heightfield(h, f32p(depth), f32p(velocity), f32p(bed), depth.size))
        return Heightfield(depth, velocity, bed, info.spacing, (info.origin[0], info.origin[1]))

    def water_balance(self) -> WaterBalance:
        """The grid's volumes since frame 0 (a WaterBalance); Error for a world whose water is particles."""
        b = _capi.mr_water_balance()
        self._check(_capi.lib().mr_world_water_balance(self._h(), ctypes.byref(b)))
        return WaterBalance(*(getattr(b, name) for name, _ in _capi.mr_water_balance._fields_[:-1]), bool(b.rain_set))

    def set_rain(self, mm_per_h: Any) -> None:
        """Rain per cell on the grid (solver "swe" or "hybrid"), in mm/h: an array of shape
        (rows, columns) like heightfield().depth, each finite in [0, 10000]; a 0..1 mask times
        a rate is `mask * rate`. It replaces the scene's swe.rain, rain_center, rain_radius
        and rain_mask until set_rain(None) (the scene's rain again), and outlives apply().
        Copied; costs O(cells). A wrong shape or dtype, NaN, infinity or a value out of range
        raises ValueError naming `mm_per_h`; a particle world raises metariver.Error."""
        h, lib = self._h(), _capi.lib()
        if mm_per_h is None:
            self._check(lib.mr_world_set_rain(h, None, 0))
            return
        info = _capi.mr_heightfield_info()
        self._check(lib.mr_world_heightfield(h, ctypes.byref(info)))
        self._check(lib.mr_world_set_rain(h, f32p(_rain_rates(mm_per_h, (info.rows, info.columns))), info.rows * info.columns))

    def _text(self, fn) -> str:
        """The text a (world, buffer, capacity, length) C function writes."""
        h = self._h()
        length = ctypes.c_size_t()
        buf = ctypes.create_string_buffer(1 << 16)  # one call for a usual scene (~33 KB)
        status = fn(h, buf, len(buf), ctypes.byref(length))
        if status == 6:  # MR_ERROR_BUFFER_TOO_SMALL: length says how much
            buf = ctypes.create_string_buffer(length.value + 1)
            status = fn(h, buf, len(buf), ctypes.byref(length))
        self._check(status)
        return buf.value.decode()

    @property
    def scene_toml(self) -> str:
        """The resolved scene as TOML text (what `metariver scene` prints)."""
        return self._text(_capi.lib().mr_world_scene_toml)

    @property
    def warnings(self) -> list[str]:
        """Non-fatal advice about the running scene, one line each naming the key (a swe source
        off the map, a steady spin-up stopped at its cap, a flow rate capped, ...)."""
        text = self._text(_capi.lib().mr_world_warnings)
        return text.split("\n") if text else []

    @property
    def scene(self) -> dict[str, Any]:
        """The resolved scene as a dict (scene_toml parsed with tomllib)."""
        return tomllib.loads(self.scene_toml)

    # -- edits ----------------------------------------------------------------------------
    def apply(self, edit: str | Mapping[str, Any]) -> bool:
        """Live edit: TOML text or a dict of scene keys over the world's scene. Returns True when
        applied in place; False when a key needs a new world (nothing changed then; the
        reason is in last_error). An invalid scene raises metariver.Error."""
        text = _toml.dumps(edit) if isinstance(edit, Mapping) else edit
        if not isinstance(text, str):
            raise ValueError(f"edit: expected TOML text or a dict, got {type(edit).__name__}")
        applied = ctypes.c_int32()
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_apply_toml(h, text.encode(), ctypes.byref(applied)))
        return bool(applied.value)

    @property
    def last_error(self) -> str:
        """The message of the latest failed or refused call on this world ("" when none)."""
        return _capi.lib().mr_world_last_error(self._h()).decode(errors="replace")

    def sculpt(self, x: float, z: float, radius: float, strength: float, mode: str = "raise",
               target: float = 0.0) -> None:
        """One sculpt stroke under the running water, centred at (x, z) metres. mode: "raise" or
        "lower" (strength: metres at the centre, >= 0), "smooth" or "flatten" (strength in
        [0, 1]; flatten moves towards `target` metres)."""
        if mode not in _BRUSH_MODES:
            raise ValueError(f"mode: {mode!r} is not one of {', '.join(_BRUSH_MODES)}")
        brush = _capi.mr_brush(float(x), float(z), float(radius), float(strength), _BRUSH_MODES[mode], float(target))
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_sculpt(h, ctypes.byref(brush)))

    def pour(self, center: Any, count: int) -> None:
        """Pours `count` (>= 1) particles at center (x, y, z); the source moves there."""
        c = _vec3("center", center)
        if not isinstance(count, (int, np.integer)) or not 1 <= count <= 2**31 - 1:
            raise ValueError(f"count: expected an integer in [1, 2147483647], got {count!r}")
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_pour(h, f32p(c), int(count)))

    def push(self, center: Any, radius: float, velocity: Any) -> int:
        """Pushes the water within `radius` metres of center with `velocity` (m/s at the centre,
        falling to 0 at the rim). Returns how many particles it pushed."""
        c, v = _vec3("center", center), _vec3("velocity", velocity)
        pushed = ctypes.c_size_t()
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_push(h, f32p(c), float(radius), f32p(v), ctypes.byref(pushed)))
        return pushed.value

    def move_source(self, center: Any) -> None:
        """Moves the source's volume centre to center (x, y, z); on a grid (solver "swe", "hybrid")
        its main source moves there while swe.source_center is "auto"."""
        c = _vec3("center", center)
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_move_source(h, f32p(c)))

    def set_sink_boxes(self, boxes: Any) -> None:
        """Replaces the box sinks with `boxes`: (K, 6) or (K, 2, 3) as min xyz then max xyz,
        K in [0, 16]. The edge sink of a river stays."""
        b = np.asarray(boxes, dtype=np.float64)
        if b.size == 0:
            b = b.reshape(0, 6)
        if b.ndim == 3 and b.shape[1:] == (2, 3):
            b = b.reshape(-1, 6)
        if b.ndim != 2 or b.shape[1] != 6 or not np.all(np.isfinite(b)):
            raise ValueError(f"boxes: expected (K, 6) or (K, 2, 3) finite numbers, got shape {b.shape}")
        b = np.ascontiguousarray(b, dtype=np.float32)
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_set_sink_boxes(h, f32p(b), b.shape[0]))

    # -- bodies (solver "pbf", "swe", "hybrid"; docs/bodies.md) ----------------------------
    def add_body(self, shape: str = "box", size: Any = (2.0, 0.5, 0.5), *, mesh: str | os.PathLike | None = None,
                 density: float = 500.0, position: Any = (0.0, 0.0, 0.0), rotation: Any = (0.0, 0.0, 0.0),
                 velocity: Any = (0.0, 0.0, 0.0), angular_velocity: Any = (0.0, 0.0, 0.0),
                 friction: float = 0.5) -> int:
        """Adds a rigid body (the scene's [[bodies]] keys) and returns its id. shape: "box"
        (size: extents x, y, z), "sphere" (radius size[0]), "capsule" (radius size[0], length
        size[1]), "convex_mesh" or "triangle_mesh" (the OBJ `mesh`, scaled by size[0]);
        density in kg/m^3 (water 1000); position: the centre of mass (m); rotation: degrees
        about x, then y, then z; velocity (m/s), angular_velocity (rad/s). A bad value raises
        metariver.Error naming its key (e.g. "bodies.density")."""
        if shape not in _capi.BODY_SHAPES:
            raise ValueError(f"shape: {shape!r} is not one of {', '.join(_capi.BODY_SHAPES)}")
        d = _capi.lib().mr_body_desc_default()
        d.shape = _capi.BODY_SHAPES.index(shape)
        for name, value in (("size", size), ("position", position), ("rotation", rotation),
                            ("velocity", velocity), ("angular_velocity", angular_velocity)):
            getattr(d, name)[:] = [float(x) for x in _vec3(name, value)]
        mesh_bytes = _path_bytes("mesh", mesh)
        d.mesh = mesh_bytes
        d.density = float(density)
        d.friction = float(friction)
        out = ctypes.c_uint32()
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_add_body(h, ctypes.byref(d), ctypes.byref(out)))
        return out.value

    def remove_body(self, id: int) -> None:
        """Removes the body `id`; an unknown id raises metariver.Error naming `id`."""
        _body_id(id)
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_remove_body(h, int(id)))

    def set_body_motion(self, id: int, position: Any, orientation: Any = (0.0, 0.0, 0.0, 1.0),
                        velocity: Any = (0.0, 0.0, 0.0), angular_velocity: Any = (0.0, 0.0, 0.0)) -> None:
        """Moves body `id` (a drag, a throw): its centre of mass to `position`, its orientation
        (a quaternion x, y, z, w; normalised by the library), velocity (m/s) and angular
        velocity (rad/s, world axes)."""
        _body_id(id)
        q = np.ascontiguousarray(np.asarray(orientation, dtype=np.float32).reshape(-1))
        if q.shape != (4,):
            raise ValueError(f"orientation: expected 4 numbers (x, y, z, w), got shape {np.shape(orientation)}")
        p, v, w = _vec3("position", position), _vec3("velocity", velocity), _vec3("angular_velocity", angular_velocity)
        h = self._h()
        self._changed()
        self._check(_capi.lib().mr_world_set_body_motion(h, int(id), f32p(p), f32p(q), f32p(v), f32p(w)))

    def bodies(self) -> np.ndarray:
        """The bodies after the latest frame, in the order they were added: a record array with
        fields id, shape (an index into metariver.BODY_SHAPES), size (3,), position (3,),
        orientation (4,: x, y, z, w), velocity (3,), angular_velocity (3,), mass (kg) and
        submerged_fraction ([0, 1])."""
        h, lib = self._h(), _capi.lib()
        n = ctypes.c_size_t()
        self._check(lib.mr_world_bodies(h, None, 0, ctypes.byref(n)))
        out = np.zeros(n.value, _capi.BODY_STATE_DTYPE)
        if n.value:
            self._check(lib.mr_world_bodies(h, out.ctypes.data, out.size, ctypes.byref(n)))
        return out

    # -- queries --------------------------------------------------------------------------
    def sample(self, xz: Any) -> np.ndarray:
        """Water at points (x, z): xz of shape (..., 2) -> a record array of shape (...) with
        fields surface_y (m; the ground where dry), depth (m), velocity (3,) m/s and wet (0/1).
        A point with a NaN or infinite coordinate is answered as dry (all 0); the others as usual."""
        p = _points("xz", xz, 2)
        out = np.zeros(p.shape[:-1], _capi.WATER_SAMPLE_DTYPE)
        self._check(_capi.lib().mr_world_sample_water(self._h(), f32p(p), out.size, out.ctypes.data))
        return out

    def velocity_at(self, points: Any) -> np.ndarray:
        """The water's velocity (m/s) at 3D points: (..., 3) -> (..., 3) float32 (0 away from
        water, and at a point with a NaN or infinite coordinate)."""
        p = _points("points", points, 3)
        out = np.zeros(p.shape, np.float32)
        self._check(_capi.lib().mr_world_water_velocity(self._h(), f32p(p), p.size // 3, f32p(out)))
        return out

    def raycast(self, origins: Any, directions: Any, max_distance: float = 1.0e6) -> np.ndarray:
        """First hits of rays on the water surface: origins, directions (..., 3) (broadcast
        together) -> a record array of shape (...) with fields t (distance along the
        normalised direction), point (3,), normal (3,) facing the origin, and hit (0/1). A ray
        with a NaN or infinite origin or direction does not hit; max_distance must be >= 0."""
        o, d = np.broadcast_arrays(_points("origins", origins, 3), _points("directions", directions, 3))
        o, d = np.ascontiguousarray(o), np.ascontiguousarray(d)
        out = np.zeros(o.shape[:-1], _capi.RAY_HIT_DTYPE)
        self._check(_capi.lib().mr_world_raycast_water(self._h(), f32p(o), f32p(d), out.size,
                                                       float(max_distance), out.ctypes.data))
        return out
