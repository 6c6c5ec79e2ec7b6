"""metariver from Python: a river over a numpy terrain (or the default valley), stepped and read.

    pip install python/            (from the repository; offline: --no-build-isolation --no-deps)
    python3 examples/python/example.py [--default]
"""
import sys

import numpy as np

import metariver


def valley(rows=72, columns=40):
    """A V-shaped valley falling along +z: heights in [0, 1], rows along z, columns along x."""
    z = np.linspace(0.0, 1.0, rows)[:, None]
    x = np.linspace(-1.0, 1.0, columns)[None, :]
    return 0.05 + 0.45 * (1.0 - z) + 0.45 * np.abs(x)


def main():
    if "--default" in sys.argv:
        world = metariver.World()  # the default river on the procedural valley
    else:
        world = metariver.World(heights=valley(), area_scale=1.0, height_scale=12.0,
                                toml={"particles": {"count": 1500}})
    with world:
        print(metariver.version_string(), "| library:", metariver.library_path().name)
        t = world.terrain
        print(f"terrain: {t.columns} x {t.rows} samples, {t.area_scale:g} m apart, ground {t.min_y:.1f}..{t.max_y:.1f} m")
        world.step(dt=1 / 60, frames=60)
        s = world.stats
        print(f"after {s.frame} frames ({s.time_s:.2f} s): {s.active_particles} particles, "
              f"{s.surface_triangles} surface triangles")
        positions, velocities = world.particles()  # copies, (N, 3) float32
        speed = np.linalg.norm(velocities, axis=1)
        print(f"particles: {positions.shape}, mean speed {speed.mean():.2f} m/s, "
              f"lowest y {positions[:, 1].min():.2f} m")
        vertices, normals, triangles = world.surface()  # copies
        centre = vertices[triangles[len(triangles) // 2]].mean(axis=0)
        sample = world.sample([centre[[0, 2]]])[0]
        print(f"surface sample at x={centre[0]:.2f} z={centre[2]:.2f}: wet={bool(sample['wet'])} "
              f"surface_y={sample['surface_y']:.2f} m depth={sample['depth']:.2f} m "
              "velocity=({:.2f}, {:.2f}, {:.2f}) m/s".format(*sample["velocity"]))


if __name__ == "__main__":
    main()
