/* The default river through the C API: 120 frames at 1/60 s, then its numbers and the
 * water at the middle vertex of its surface. */
#include <metariver/metariver.h>

#include <stdio.h>

/* The failed call's message names the function and the argument. */
static int fail(mr_world* world) {
    fprintf(stderr, "%s\n", mr_world_last_error(world));
    mr_world_destroy(world);
    return 1;
}

int main(void) {
    mr_world_desc desc = mr_world_desc_default();
    mr_world* world = NULL;
    mr_error error;
    mr_stats stats;
    mr_surface_view surface;
    mr_water_sample sample;
    float xz[2];
    int frame;

    if (mr_world_create(&desc, &world, &error) != MR_OK) {
        fprintf(stderr, "mr_world_create: %s\n", error.message);
        return 1;
    }
    for (frame = 0; frame < 120; ++frame)
        if (mr_world_step(world, 1.0f / 60.0f) != MR_OK) return fail(world);
    if (mr_world_stats(world, &stats) != MR_OK) return fail(world);
    printf("%s\nframe %lu: %lu active particles, surface %lu vertices, %lu triangles\n", mr_version_string(),
           (unsigned long)stats.frame, (unsigned long)stats.active_particles, (unsigned long)stats.surface_vertices,
           (unsigned long)stats.surface_triangles);

    if (mr_world_surface(world, &surface) != MR_OK) return fail(world);
    if (surface.vertex_count == 0) {
        fprintf(stderr, "no water surface yet\n");
        mr_world_destroy(world);
        return 1;
    }
    xz[0] = surface.positions[3 * (surface.vertex_count / 2)];
    xz[1] = surface.positions[3 * (surface.vertex_count / 2) + 2];
    if (mr_world_sample_water(world, xz, 1, &sample) != MR_OK) return fail(world);
    printf("water at (%.2f, %.2f): wet %d, surface y %.3f m, depth %.3f m, velocity (%.3f, %.3f, %.3f) m/s\n", xz[0],
           xz[1], (int)sample.wet, sample.surface_y, sample.depth, sample.velocity[0], sample.velocity[1],
           sample.velocity[2]);
    mr_world_destroy(world);
    return 0;
}
