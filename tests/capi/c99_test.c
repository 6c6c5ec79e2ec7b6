/* The C API from C99 (compiled with -std=c99 -Wall -Wextra -pedantic -Werror): create the
 * default world, step it, read the particles and the surface, check the errors, destroy;
 * rain per cell on a shallow-water world.
 * Exit status 0 when every check holds; each failed check prints its line. */
#include <metariver/metariver.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int failures = 0;

#define CHECK(cond)                                                      \
    do {                                                                 \
        if (!(cond)) {                                                   \
            fprintf(stderr, "c99_test.c:%d: failed: %s\n", __LINE__, #cond); \
            ++failures;                                                  \
        }                                                                \
    } while (0)

static void check_errors(mr_world* world) {
    mr_world_desc desc = mr_world_desc_default();
    mr_world* other = NULL;
    mr_error error;
    size_t count = 0;
    float small[3];

    desc.preset = "no-such-preset";
    CHECK(mr_world_create(&desc, &other, &error) == MR_ERROR_INVALID_ARGUMENT);
    CHECK(other == NULL);
    CHECK(error.code == MR_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(error.message, "no-such-preset") != NULL);
    CHECK(mr_world_step(NULL, 1.0f / 60.0f) == MR_ERROR_NULL_ARGUMENT);
    CHECK(mr_world_step(world, 2.0f) == MR_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(mr_world_last_error(world), "frame_dt") != NULL);
    CHECK(mr_world_copy_particles(world, small, NULL, 1, &count) == MR_ERROR_BUFFER_TOO_SMALL);
    CHECK(count > 1);
    CHECK(strcmp(mr_status_name(MR_ERROR_BUFFER_TOO_SMALL), "MR_ERROR_BUFFER_TOO_SMALL") == 0);
    CHECK(strcmp(mr_status_name((mr_status)99), "MR_STATUS_UNKNOWN") == 0);
}

/* A body: added, read back, thrown, stepped and removed, in plain C99. */
static void check_bodies(mr_world* world) {
    mr_body_desc body = mr_body_desc_default();
    mr_body_state states[2];
    mr_terrain_info terrain;
    const float q[4] = {0.0f, 0.0f, 0.0f, 1.0f}, v[3] = {1.0f, 0.0f, 0.0f}, w[3] = {0.0f, 0.0f, 0.0f};
    uint32_t id = 0;
    size_t n = 0;
    CHECK(mr_world_terrain(world, &terrain) == MR_OK);
    body.position[0] = 0.5f * (float)(terrain.columns - 1) * terrain.area_scale;
    body.position[1] = terrain.max_y + 2.0f;
    body.position[2] = 0.5f * (float)(terrain.rows - 1) * terrain.area_scale;
    CHECK(mr_world_add_body(world, &body, &id) == MR_OK);
    CHECK(mr_world_bodies(world, NULL, 0, &n) == MR_OK && n == 1);
    CHECK(mr_world_bodies(world, states, 2, &n) == MR_OK && states[0].id == id && states[0].shape == MR_BODY_BOX);
    CHECK(states[0].mass > 0.0f);
    CHECK(mr_world_set_body_motion(world, id, body.position, q, v, w) == MR_OK);
    CHECK(mr_world_step(world, 1.0f / 60.0f) == MR_OK);
    CHECK(mr_world_remove_body(world, id) == MR_OK);
    CHECK(mr_world_remove_body(world, id) == MR_ERROR_INVALID_ARGUMENT);
    CHECK(mr_world_bodies(world, states, 2, &n) == MR_OK && n == 0);
}

/* Rain per cell on a shallow-water world: a uniform 3600 mm/h (1 mm/s) over every cell,
 * its volume after 10 frames the cells' area x 1 mm/s x the grid's simulated time. */
static void check_rain(void) {
    mr_world_desc desc = mr_world_desc_default();
    mr_world* world = NULL;
    mr_error error;
    mr_heightfield_info grid;
    mr_water_balance balance;
    float* rate;
    size_t cells, k;
    double expected;
    int frame;
    desc.scene_toml = "solver = \"swe\"\n[swe]\ndischarge = 0\n";
    desc.threads = 2;
    CHECK(mr_world_create(&desc, &world, &error) == MR_OK);
    if (!world) return;
    CHECK(mr_world_heightfield(world, &grid) == MR_OK);
    cells = (size_t)grid.rows * (size_t)grid.columns;
    rate = (float*)malloc(cells * sizeof(float));
    for (k = 0; k < cells; ++k) rate[k] = 3600.0f;
    CHECK(mr_world_set_rain(world, rate, cells - 1) == MR_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(mr_world_last_error(world), "count") != NULL);
    CHECK(mr_world_set_rain(world, rate, cells) == MR_OK);
    for (frame = 0; frame < 10; ++frame) CHECK(mr_world_step(world, 1.0f / 60.0f) == MR_OK);
    CHECK(mr_world_water_balance(world, &balance) == MR_OK);
    expected = (double)cells * grid.spacing * grid.spacing * 1e-3 * balance.simulated_s;
    CHECK(balance.rain_set == 1);
    CHECK(balance.rain > 0.999999999 * expected && balance.rain < 1.000000001 * expected);
    free(rate);
    mr_world_destroy(world);
}

int main(void) {
    mr_world_desc desc = mr_world_desc_default();
    mr_world* world = NULL;
    mr_error error;
    mr_stats stats;
    mr_particles_view particles;
    mr_surface_view surface;
    float* positions;
    uint32_t* indices;
    size_t count = 0, vertices = 0, index_count = 0, i, active = 0;
    int frame;

    CHECK((mr_api_version() >> 16) == MR_API_VERSION_MAJOR);
    desc.threads = 2;
    if (mr_world_create(&desc, &world, &error) != MR_OK) {
        fprintf(stderr, "mr_world_create: %s: %s\n", mr_status_name(error.code), error.message);
        return 1;
    }
    for (frame = 0; frame < 30; ++frame) CHECK(mr_world_step(world, 1.0f / 60.0f) == MR_OK);
    CHECK(mr_world_stats(world, &stats) == MR_OK);
    CHECK(stats.frame == 30);
    CHECK(stats.active_particles > 0);

    CHECK(mr_world_particles(world, &particles) == MR_OK);
    for (i = 0; i < particles.count; ++i) active += particles.active[i];
    CHECK(active == stats.active_particles);
    positions = (float*)malloc(3 * active * sizeof(float));
    CHECK(mr_world_copy_particles(world, positions, NULL, active, &count) == MR_OK);
    CHECK(count == active);
    free(positions);

    CHECK(mr_world_surface(world, &surface) == MR_OK);
    CHECK(surface.vertex_count == stats.surface_vertices);
    CHECK(surface.index_count == 3 * stats.surface_triangles);
    indices = (uint32_t*)malloc((surface.index_count + 1) * sizeof(uint32_t));
    CHECK(mr_world_copy_surface(world, NULL, NULL, 0, indices, surface.index_count, &vertices, &index_count) == MR_OK);
    CHECK(index_count == surface.index_count);
    CHECK(index_count == 0 || memcmp(indices, surface.indices, index_count * sizeof(uint32_t)) == 0);
    free(indices);

    check_bodies(world);
    check_errors(world);
    check_rain();
    mr_world_destroy(world);
    if (failures == 0) printf("c99_test: all checks passed (%lu active particles)\n", (unsigned long)active);
    return failures == 0 ? 0 : 1;
}
