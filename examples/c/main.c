/* The default river through the C API: 120 frames at 1/60 s, then its numbers and the
 * water where it is deepest among samples under the surface's vertices. */
#include <metariver/metariver.h>

#include <stdio.h>
#include <stdlib.h>

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
    mr_water_sample* samples;
    float* xz;
    size_t i, n, best = 0;
    int frame;

    if (mr_world_create(&desc, &world, &error) != MR_OK) {
        fprintf(stderr, "mr_world_create: %s\n", error.message);
        return 1;
    }
    for (frame = 0; frame < 120; ++frame)
        if (mr_world_step(world, 1.0f / 60.0f) != MR_OK) return fail(world);
    if (mr_world_stats(world, &stats) != MR_OK || mr_world_surface(world, &surface) != MR_OK) return fail(world);
    printf("%s\nframe %lu: %lu active particles, surface %lu vertices, %lu triangles\n", mr_version_string(),
           (unsigned long)stats.frame, (unsigned long)stats.active_particles, (unsigned long)surface.vertex_count,
           (unsigned long)(surface.index_count / 3));

    n = surface.vertex_count; /* one sample under every vertex (the surface is borrowed until the next step) */
    xz = malloc(2 * n * sizeof(float) + 1);
    samples = malloc(n * sizeof(mr_water_sample) + 1);
    for (i = 0; i < n; ++i) {
        xz[2 * i] = surface.positions[3 * i];
        xz[2 * i + 1] = surface.positions[3 * i + 2];
    }
    if (mr_world_sample_water(world, xz, n, samples) != MR_OK) return fail(world);
    for (i = 1; i < n; ++i)
        if (samples[i].depth > samples[best].depth) best = i;
    if (n > 0)
        printf("deepest at (%.2f, %.2f): surface y %.3f m, depth %.3f m, velocity (%.3f, %.3f, %.3f) m/s\n",
               xz[2 * best], xz[2 * best + 1], samples[best].surface_y, samples[best].depth,
               samples[best].velocity[0], samples[best].velocity[1], samples[best].velocity[2]);
    free(xz);
    free(samples);
    mr_world_destroy(world);
    return 0;
}
