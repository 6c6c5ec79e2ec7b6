/* metariver C API (C99): a river simulation behind an opaque handle, read through flat
 * arrays. For engines, plugins and other languages (Python's metariver package binds it
 * with ctypes). docs/embedding.md is the guide; this header is the reference.
 *
 * Rules:
 * - Every function returns an mr_status (MR_OK = 0) unless it says otherwise. On failure
 *   nothing changed, and mr_world_last_error(world) (or the mr_error a create function
 *   filled) says why, naming the argument, the scene key or the file.
 * - A NULL handle or a NULL pointer where one is required is MR_ERROR_NULL_ARGUMENT.
 * - Borrowed pointers (mr_world_particles, mr_world_surface) stay valid until the next
 *   call that changes the world (step, an edit, destroy); copy functions write into
 *   buffers the caller owns.
 * - One world is used by one thread at a time; different worlds are independent (no
 *   global state). A world's own work runs on at most mr_world_desc.threads threads.
 * - Units: metres, seconds, m/s; y is up; the terrain spans x in [0, (columns-1) *
 *   area_scale] and z in [0, (rows-1) * area_scale].
 */
#ifndef METARIVER_H
#define METARIVER_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32)
#define MR_API __declspec(dllexport)
#else
#define MR_API __attribute__((visibility("default")))
#endif

/* The API this header describes; mr_api_version() is the library's (same major: compatible). */
#define MR_API_VERSION_MAJOR 1
#define MR_API_VERSION_MINOR 3 /* 1: bodies (mr_world_add_body & co); 2: the shallow-water grid (mr_world_heightfield);
                                 3: the grid's rain per cell and volumes (mr_world_set_rain, mr_world_water_balance),
                                 mr_world_warnings */
#define MR_API_VERSION ((MR_API_VERSION_MAJOR << 16) | MR_API_VERSION_MINOR)

typedef enum mr_status {
    MR_OK = 0,
    MR_ERROR_NULL_ARGUMENT = 1,    /* a handle or pointer argument is NULL */
    MR_ERROR_INVALID_ARGUMENT = 2, /* a value out of its range (the message names it and the range) */
    MR_ERROR_SCENE = 3,            /* the scene (file, TOML text, key, value) was refused */
    MR_ERROR_IO = 4,               /* a file could not be read */
    MR_ERROR_UNSUPPORTED = 5,      /* the scene's solver does not do this (e.g. push with bullet) */
    MR_ERROR_BUFFER_TOO_SMALL = 6, /* a caller's buffer is smaller than the data; the count says how much is needed */
    MR_ERROR_INTERNAL = 7          /* a bug or out of memory; the message says what */
} mr_status;

/* Creation's error: the code and a message naming the culprit. */
typedef struct mr_error {
    mr_status code;
    char message[512];
} mr_error;

typedef struct mr_world mr_world; /* opaque */

/* How to create a world. Start from mr_world_desc_default(), then set at most one of
 * scene_file, scene_toml and preset (none: the built-in default scene, a river on the
 * procedural valley) and optionally a terrain: heightmap_file, or heights. */
typedef struct mr_world_desc {
    const char* scene_file;     /* a scene TOML file (docs/scene-format.md), or NULL */
    const char* scene_toml;     /* scene TOML text (keys over the default scene), or NULL */
    const char* preset;         /* a built-in preset ("default", "paper-bowl", ...), or NULL */
    const char* heightmap_file; /* a PNG replacing the scene's terrain, or NULL */
    /* The caller's terrain instead: heights[row * columns + column], row along +z,
     * column along +x, each in [0, 1] and scaled by height_scale; NULL: none. */
    const float* heights;
    int32_t columns, rows;     /* samples along x and z, [2, 4097], when heights is set */
    float area_scale;          /* metres between samples; 0: the scene's */
    float height_scale;        /* metres for a height of 1; 0: the scene's */
    int32_t threads;           /* the most threads the world's work uses, [0, 1024]; 0: every core */
} mr_world_desc;

MR_API mr_world_desc mr_world_desc_default(void);

/* Library version: MR_API_VERSION of the library built (major << 16 | minor). */
MR_API uint32_t mr_api_version(void);
/* "metariver 0.1.0 (commit ...)"; static storage. */
MR_API const char* mr_version_string(void);
/* "MR_OK", "MR_ERROR_NULL_ARGUMENT", ...; static storage. */
MR_API const char* mr_status_name(mr_status status);

/* Creates a world (loads or generates the terrain, builds the solver). error may be NULL;
 * on failure *out_world is NULL. */
MR_API mr_status mr_world_create(const mr_world_desc* desc, mr_world** out_world, mr_error* error);
/* Destroys a world; NULL is ignored. */
MR_API void mr_world_destroy(mr_world* world);
/* The message of the latest failed call on this world ("" when none); valid until the
 * next call on it. Returns "world is NULL" for a NULL world. */
MR_API const char* mr_world_last_error(const mr_world* world);

/* One frame of frame_dt seconds, (0, 1]: the solver's substeps, then the surface. */
MR_API mr_status mr_world_step(mr_world* world, float frame_dt);

typedef struct mr_stats {
    uint64_t frame;           /* frames stepped */
    double time_s;            /* simulated seconds */
    uint64_t particle_slots;  /* particle array length (active or not) */
    uint64_t active_particles;
    uint64_t tunneled;        /* particles that crossed the terrain (counted before any correction) */
    uint64_t surface_vertices, surface_triangles;
    double simulate_ms, field_ms, surface_ms; /* the latest frame's stage times */
} mr_stats;
MR_API mr_status mr_world_stats(const mr_world* world, mr_stats* out);

/* Borrowed views of the particles: count slots, xyz per slot, active[i] = 1 for a live
 * particle (inactive slots hold stale values). Valid until the world changes. */
typedef struct mr_particles_view {
    const float* positions;  /* 3 * count */
    const float* velocities; /* 3 * count */
    const uint8_t* active;   /* count */
    size_t count;
} mr_particles_view;
MR_API mr_status mr_world_particles(const mr_world* world, mr_particles_view* out);
/* Copies the ACTIVE particles, in index order, into positions / velocities (3 floats
 * each; either may be NULL). *count: the active particles; MR_ERROR_BUFFER_TOO_SMALL
 * (nothing written) when capacity is smaller. */
MR_API mr_status mr_world_copy_particles(const mr_world* world, float* positions, float* velocities,
                                         size_t capacity, size_t* count);

/* The water surface mesh of the latest frame (triangles, counter-clockwise seen from
 * outside the water, unit vertex normals). Borrowed until the world changes. */
typedef struct mr_surface_view {
    const float* positions; /* 3 * vertex_count */
    const float* normals;   /* 3 * vertex_count */
    size_t vertex_count;
    const uint32_t* indices; /* index_count, 3 per triangle */
    size_t index_count;
} mr_surface_view;
MR_API mr_status mr_world_surface(const mr_world* world, mr_surface_view* out);
/* Copies the surface; either of positions/normals and indices may be NULL (counts only).
 * MR_ERROR_BUFFER_TOO_SMALL (nothing written) when a capacity is smaller than its count. */
MR_API mr_status mr_world_copy_surface(const mr_world* world, float* positions, float* normals,
                                       size_t vertex_capacity, uint32_t* indices, size_t index_capacity,
                                       size_t* vertex_count, size_t* index_count);

/* The terrain as built (after any conditioning and sculpting). */
typedef struct mr_terrain_info {
    int32_t columns, rows; /* samples along x and z */
    float area_scale;      /* metres between samples */
    float min_y, max_y;    /* lowest and highest ground, metres */
} mr_terrain_info;
MR_API mr_status mr_world_terrain(const mr_world* world, mr_terrain_info* out);
/* Ground heights in metres, heights[row * columns + column] (capacity >= rows * columns). */
MR_API mr_status mr_world_copy_terrain_heights(const mr_world* world, float* heights, size_t capacity);

/* The water as a grid (solver = "swe": one cell per terrain sample). MR_ERROR_UNSUPPORTED
 * for a solver whose water is not a grid (particles). */
typedef struct mr_heightfield_info {
    int32_t columns, rows; /* cells along x and z */
    float spacing;         /* metres between neighbouring cells */
    float origin[2];       /* x and z of cell (row 0, column 0), metres */
} mr_heightfield_info;
MR_API mr_status mr_world_heightfield(const mr_world* world, mr_heightfield_info* out);
/* Copies the grid of the latest frame, cell row * columns + column: depth (m, 0: dry),
 * velocity (2 floats a cell: x and z, m/s) and bed (the ground, m); any of the three may
 * be NULL (not copied). capacity: cells each non-NULL buffer holds (>= rows * columns, else
 * MR_ERROR_BUFFER_TOO_SMALL, nothing written). */
MR_API mr_status mr_world_copy_heightfield(const mr_world* world, float* depth, float* velocity, float* bed,
                                           size_t capacity);

/* Rain per cell on the grid (solver = "swe" or "hybrid"), in mm/h: mm_per_h[row * columns +
 * column] as mr_world_copy_heightfield, count = rows * columns values, each in [0, 10000]
 * (NaN refused). It replaces the scene's swe.rain, rain_center, rain_radius and rain_mask
 * until cleared (mm_per_h NULL, count 0: the scene's rain again) and outlives live edits
 * (mr_world_apply_toml); it is not part of the scene (mr_world_scene_toml). A 0..1 mask
 * times a rate is mask[k] * rate; a storm moved every frame is one call a frame. Copied;
 * O(cells). Refused (nothing
 * changed): a wrong count (MR_ERROR_INVALID_ARGUMENT naming count and the grid's size), a
 * bad value (naming mm_per_h[k], its row and column), a particle solver (UNSUPPORTED). */
MR_API mr_status mr_world_set_rain(mr_world* world, const float* mm_per_h, size_t count);
/* The grid's volumes, m^3 since frame 0 (after swe.init's spin-up). */
typedef struct mr_water_balance {
    double initial;     /* in the grid at frame 0 (a lake, the steady river) */
    double inflow;      /* the sources' discharge and what mr_world_pour poured */
    double rain;        /* rained */
    double outflow;     /* left over the map's edges */
    double sunk;        /* taken by [[swe.sinks]] and the sea (swe.sea_level) */
    double exchanged;   /* net volume the hybrid's particles gave the grid (negative: took) */
    double stored;      /* in the grid now */
    double error;       /* initial + inflow + rain + exchanged - outflow - sunk - stored: round-off */
    double simulated_s; /* the grid's simulated seconds since frame 0 (frame_dt x swe.time_scale, summed) */
    uint64_t substeps;  /* time steps taken under the CFL limit since frame 0 */
    int32_t rain_set;   /* 1 while mr_world_set_rain's rates replace the scene's rain */
} mr_water_balance;
MR_API mr_status mr_world_water_balance(const mr_world* world, mr_water_balance* out);

/* The resolved scene as TOML (what `metariver scene` prints): writes at most capacity
 * bytes including the terminating NUL; *length: the text's length without it
 * (MR_ERROR_BUFFER_TOO_SMALL when it does not fit; buffer may then be NULL). */
MR_API mr_status mr_world_scene_toml(const mr_world* world, char* buffer, size_t capacity, size_t* length);
/* Non-fatal advice about the running scene, one line each, naming the key (a swe source
 * off the map, a steady spin-up stopped at its cap, a flow rate capped, ...): the text as
 * mr_world_scene_toml writes it ("" when there is none). */
MR_API mr_status mr_world_warnings(const mr_world* world, char* buffer, size_t capacity, size_t* length);
/* Live edit: TOML keys over the world's scene, applied in place when the solver can take
 * them (*applied = 1); keys that need a new world (terrain, solver, budget, ...) change
 * nothing (MR_OK with *applied = 0; mr_world_last_error names the first such key). A bad
 * key or value is MR_ERROR_SCENE. applied may be NULL. */
MR_API mr_status mr_world_apply_toml(mr_world* world, const char* toml, int32_t* applied);

/* Interaction. */
typedef enum mr_brush_mode { MR_BRUSH_RAISE = 0, MR_BRUSH_LOWER = 1, MR_BRUSH_SMOOTH = 2, MR_BRUSH_FLATTEN = 3 } mr_brush_mode;
typedef struct mr_brush {
    float x, z;        /* centre, metres */
    float radius;      /* metres, > 0 */
    float strength;    /* raise/lower: metres at the centre per stroke, >= 0; smooth/flatten: [0, 1] */
    mr_brush_mode mode;
    float target;      /* flatten: the height, metres */
} mr_brush;
/* One sculpt stroke under the running water. */
MR_API mr_status mr_world_sculpt(mr_world* world, const mr_brush* brush);
/* Pours count (>= 1) particles at center (xyz); the source moves there. */
MR_API mr_status mr_world_pour(mr_world* world, const float center[3], int32_t count);
/* Pushes the water within radius of center with velocity (m/s at the centre). pushed may be NULL. */
MR_API mr_status mr_world_push(mr_world* world, const float center[3], float radius, const float velocity[3],
                               size_t* pushed);
/* Moves the source's volume centre to center (xyz); on a grid (solver = "swe", "hybrid") its
 * main source moves there while swe.source_center is "auto" (the default). */
MR_API mr_status mr_world_move_source(mr_world* world, const float center[3]);
/* Replaces the scene's box sinks (where water leaves) with count boxes, each min xyz then
 * max xyz (6 floats); count 0 removes them. At most 16. The edge sink of a river stays. */
MR_API mr_status mr_world_set_sink_boxes(mr_world* world, const float* boxes, size_t count);

/* Rigid bodies in the water (logs, boats, crates; solver "pbf" only, docs/bodies.md): the
 * scene's [[bodies]] keys as a flat struct. Start from mr_body_desc_default(). */
typedef enum mr_body_shape {
    MR_BODY_BOX = 0,          /* size: full extents along the body's x, y, z */
    MR_BODY_SPHERE = 1,       /* size[0]: radius */
    MR_BODY_CAPSULE = 2,      /* size[0]: radius, size[1]: the cylinder's length along the body's x */
    MR_BODY_CONVEX_MESH = 3,  /* the convex hull of mesh's vertices, scaled by size[0] */
    MR_BODY_TRIANGLE_MESH = 4 /* the closed triangle mesh of mesh, scaled by size[0] */
} mr_body_shape;
typedef struct mr_body_desc {
    int32_t shape;              /* an mr_body_shape */
    float size[3];              /* metres, see mr_body_shape; the components the shape reads in (0, 1000] */
    const char* mesh;           /* the OBJ file of a mesh shape (NULL or "" otherwise); copied */
    float density;              /* kg/m^3, (0, 100000]; water is 1000 */
    float position[3];          /* the centre of mass, metres */
    float rotation[3];          /* degrees: about the world's x, then y, then z */
    float velocity[3];          /* m/s */
    float angular_velocity[3];  /* rad/s, world axes */
    float friction;             /* Coulomb coefficient against the terrain and other bodies, [0, 2] */
} mr_body_desc;
/* A log: a 2 x 0.5 x 0.5 m box of 500 kg/m^3 at the origin, at rest, friction 0.5. */
MR_API mr_body_desc mr_body_desc_default(void);
/* Adds a body; *out_id: its id (stable, never reused in the world). A bad value is
 * MR_ERROR_INVALID_ARGUMENT naming its scene key ("bodies.density"), an unreadable mesh
 * MR_ERROR_IO, a solver without bodies MR_ERROR_UNSUPPORTED. */
MR_API mr_status mr_world_add_body(mr_world* world, const mr_body_desc* desc, uint32_t* out_id);
/* Removes a body; an id with no body is MR_ERROR_INVALID_ARGUMENT naming `id`. */
MR_API mr_status mr_world_remove_body(mr_world* world, uint32_t id);
/* Moves a body (a drag, a throw): its centre of mass, orientation (a quaternion x, y, z, w;
 * normalised here, not zero), velocity and angular velocity (world axes). */
MR_API mr_status mr_world_set_body_motion(mr_world* world, uint32_t id, const float position[3],
                                          const float orientation[4], const float velocity[3],
                                          const float angular_velocity[3]);
/* A body after the latest frame. */
typedef struct mr_body_state {
    uint32_t id;
    int32_t shape;              /* an mr_body_shape */
    float size[3];
    float position[3];          /* centre of mass, metres */
    float orientation[4];       /* body to world, a unit quaternion x, y, z, w */
    float velocity[3];          /* m/s */
    float angular_velocity[3];  /* rad/s, world axes */
    float mass;                 /* kg */
    float submerged_fraction;   /* share of the volume under the water, [0, 1] */
} mr_body_state;
/* Copies the bodies, in the order they were added, into out; *count: how many there
 * are. out may be NULL (count only); MR_ERROR_BUFFER_TOO_SMALL (nothing written) when
 * capacity is smaller than the count. */
MR_API mr_status mr_world_bodies(const mr_world* world, mr_body_state* out, size_t capacity, size_t* count);

/* Water queries on the latest frame (the first query after a step builds their grids).
 * Batches of count points; outputs are arrays the caller owns. Each point is answered on
 * its own: a point with a NaN or infinite coordinate (in xz, points, origins or
 * directions) is answered as dry (wet 0, surface_y 0, depth 0, velocity 0), zero velocity
 * or no hit, as WaterQuery answers it, and the call still returns MR_OK with every other
 * point answered; check your inputs with isfinite() where a NaN means a bug of yours.
 * Arguments of the whole call (NULL pointers, max_distance) are refused as usual. */
typedef struct mr_water_sample {
    float surface_y;   /* the highest water surface over/under (x, z), metres; the ground when dry */
    float depth;       /* surface_y minus the ground, >= 0 */
    float velocity[3]; /* the flow at the surface, m/s */
    int32_t wet;       /* 1 when the surface covers (x, z) */
} mr_water_sample;
/* xz: 2 floats per point. */
MR_API mr_status mr_world_sample_water(mr_world* world, const float* xz, size_t count, mr_water_sample* out);
/* points, velocities: 3 floats per point. */
MR_API mr_status mr_world_water_velocity(mr_world* world, const float* points, size_t count, float* velocities);
typedef struct mr_ray_hit {
    float t;         /* distance along the normalised direction */
    float point[3];
    float normal[3]; /* facing the ray's origin */
    int32_t hit;     /* 1 when the ray meets the surface within max_distance */
} mr_ray_hit;
/* origins, directions: 3 floats per ray. */
MR_API mr_status mr_world_raycast_water(mr_world* world, const float* origins, const float* directions, size_t count,
                                        float max_distance, mr_ray_hit* out);

#ifdef __cplusplus
}
#endif

#endif /* METARIVER_H */
