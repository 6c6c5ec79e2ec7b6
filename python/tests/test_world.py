"""World creation, stepping, particles and surface (copies and views), the scene dict, edits."""
from __future__ import annotations

import re
import struct

import numpy as np
import pytest
from conftest import REPO, SMALL, valley

import metariver


def test_version_is_the_projects():
    text = (REPO / "CMakeLists.txt").read_text()
    assert metariver.__version__ == re.search(r"project\(metariver VERSION ([0-9.]+)", text).group(1)
    assert metariver.api_version()[0] == 1
    assert metariver.version_string().startswith("metariver")


def test_default_world_is_the_valley_and_steps():
    with metariver.World(threads=2) as w:
        t = w.terrain
        assert (t.columns, t.rows) == (65, 97)  # terrain.width, terrain.height of the default scene
        assert w.stats.frame == 0
        w.step(frames=2)
        s = w.stats
        assert s.frame == 2
        assert s.time_s == pytest.approx(2 / 60, rel=1e-4)
        assert s.active_particles > 0


@pytest.mark.parametrize("how", ["text", "dict", "file"])
def test_scene_from_toml_text_dict_or_file(how, tmp_path):
    text = 'solver = "springs"\n[particles]\ncount = 700\n'
    if how == "text":
        w = metariver.World(toml=text)
    elif how == "dict":
        w = metariver.World(toml={"solver": "springs", "particles": {"count": 700}})
    else:
        path = tmp_path / "scene.toml"
        path.write_text(text)
        w = metariver.World(scene=path)
    with w:
        assert w.scene["solver"] == "springs"
        assert w.scene["particles"]["count"] == 700


def test_preset():
    with metariver.World(preset="paper-bowl") as w:
        assert w.scene["terrain"]["source"] == "bowl"


def test_heightmap_file_sets_the_terrain_size():
    png = REPO / "assets" / "heightmaps" / "real" / "alps.png"
    width, height = struct.unpack(">II", png.read_bytes()[16:24])  # IHDR
    with metariver.World(heightmap=png, toml=SMALL) as w:
        assert (w.terrain.columns, w.terrain.rows) == (width, height)


def test_numpy_heights_round_trip():
    h = valley(50, 30)
    with metariver.World(heights=h, area_scale=2.0, height_scale=10.0, toml={"terrain": {"condition": "none"}}) as w:
        t = w.terrain
        assert (t.columns, t.rows, t.area_scale) == (30, 50, 2.0)
        back = w.terrain_heights()
        assert back.shape == (50, 30) and back.dtype == np.float32
        np.testing.assert_allclose(back, h * 10.0, atol=1e-4)
        assert t.min_y == pytest.approx(h.min() * 10.0, abs=1e-4)
        assert t.max_y == pytest.approx(h.max() * 10.0, abs=1e-4)


def test_heights_rows_run_along_z():
    """heights[row, column] is the ground at x = column * area_scale, z = row * area_scale."""
    h = valley(50, 30)
    with metariver.World(heights=h, area_scale=2.0, height_scale=10.0, toml={"terrain": {"condition": "none"}},
                         threads=1) as w:
        pts = np.array([[0.0, 0.0], [58.0, 0.0], [0.0, 98.0], [20.0, 40.0]])  # (x, z) on samples
        s = w.sample(pts)
        assert not s["wet"].any()  # no step yet: no surface
        cols, rows = (pts[:, 0] / 2).astype(int), (pts[:, 1] / 2).astype(int)
        np.testing.assert_allclose(s["surface_y"], h[rows, cols] * 10.0, atol=1e-3)


def bad_heights():
    return [
        (np.zeros((10, 10), np.int32), "dtype"),
        (np.zeros(10), "shape"),
        (np.zeros((1, 10)), "shape"),
        (np.zeros((4098, 2)), "shape"),
        (np.full((8, 8), np.nan), "NaN"),
        (np.full((8, 8), 1.5), "1.5"),
        (np.full((8, 8), -0.25), "-0.25"),
    ]


@pytest.mark.parametrize("h,culprit", bad_heights())
def test_bad_heights_raise_naming_heights_and_the_range(h, culprit):
    with pytest.raises(ValueError) as err:
        metariver.World(heights=h)
    message = str(err.value)
    assert message.startswith("heights:") and culprit in message
    assert "[0, 1]" in message or "[2, 4097]" in message


def test_bad_arguments_name_the_culprit(tmp_path):
    with pytest.raises(ValueError, match="scene, toml, preset"):
        metariver.World(preset="default", toml="")
    with pytest.raises(ValueError, match="threads"):
        metariver.World(threads=-1)
    with pytest.raises(ValueError, match="area_scale"):
        metariver.World(area_scale=float("nan"))
    with pytest.raises(metariver.Error) as err:
        metariver.World(preset="no-such-preset")
    assert isinstance(err.value, RuntimeError)
    assert err.value.status in ("MR_ERROR_SCENE", "MR_ERROR_INVALID_ARGUMENT") and "no-such-preset" in err.value.message
    missing = tmp_path / "missing.png"
    with pytest.raises(metariver.Error) as err:
        metariver.World(heightmap=missing)
    assert err.value.status in ("MR_ERROR_IO", "MR_ERROR_SCENE") and "missing.png" in err.value.message
    with pytest.raises(metariver.Error) as err:
        metariver.World(toml="[particles]\ncount = -5\n")
    assert err.value.status == "MR_ERROR_SCENE" and "particles.count" in err.value.message


def test_bad_calls_on_a_world(world):
    with pytest.raises(metariver.Error) as err:
        world.step(dt=0.0)
    assert err.value.status == "MR_ERROR_INVALID_ARGUMENT"
    with pytest.raises(metariver.Error) as err:
        world.sculpt(10.0, 10.0, radius=-1.0, strength=1.0)
    assert err.value.status == "MR_ERROR_INVALID_ARGUMENT" and "radius" in err.value.message
    with pytest.raises(ValueError, match="mode"):
        world.sculpt(10.0, 10.0, 3.0, 1.0, mode="dig")
    with pytest.raises(ValueError, match="center"):
        world.pour([1.0, 2.0], 10)
    with pytest.raises(ValueError, match="boxes"):
        world.set_sink_boxes(np.zeros((2, 5)))
    with pytest.raises(metariver.Error) as err:
        world.set_sink_boxes(np.tile([0, 0, 0, 1, 1, 1], (17, 1)))
    assert err.value.status == "MR_ERROR_INVALID_ARGUMENT"


def test_step_changes_the_state(world):
    before = world.particles()
    frame = world.stats.frame
    world.step(frames=3)
    after = world.particles()
    assert world.stats.frame == frame + 3
    assert len(after.positions) > 0
    n = min(len(before.positions), len(after.positions))
    assert not np.array_equal(before.positions[:n], after.positions[:n])


def test_particles_are_copies_and_views_are_the_worlds_memory(world):
    copy = world.particles()
    stats = world.stats
    assert copy.positions.shape == (stats.active_particles, 3) and copy.positions.dtype == np.float32
    assert copy.velocities.shape == copy.positions.shape
    view = world.particles_view()
    assert view.positions.shape == (stats.particle_slots, 3)
    assert int(view.active.sum()) == stats.active_particles
    np.testing.assert_array_equal(view.positions[view.active], copy.positions)
    np.testing.assert_array_equal(view.velocities[view.active], copy.velocities)
    with pytest.raises(ValueError):
        view.positions[0, 0] = 1.0  # read-only
    kept = copy.positions.copy()
    world.step()
    assert not view.valid
    with pytest.raises(metariver.StaleViewError):
        view.positions
    np.testing.assert_array_equal(copy.positions, kept)  # the copy did not follow the world
    assert world.particles_view().valid


def test_surface_is_a_closed_form_mesh(world):
    v, n, i = world.surface()
    s = world.stats
    assert v.shape == (s.surface_vertices, 3) and n.shape == v.shape
    assert i.shape == (s.surface_triangles, 3) and i.dtype == np.uint32
    assert s.surface_triangles > 0
    assert i.max() < len(v)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-3)


def test_scene_dict_and_live_edit(world):
    scene = world.scene
    assert scene["solver"] == "pbf" and scene["particles"]["count"] == 1500
    assert world.apply({"pbf": {"xsph": 0.05}}) is True
    assert world.scene["pbf"]["xsph"] == pytest.approx(0.05)
    assert world.apply('[terrain]\nseed = 9\n') is False  # needs a new world
    assert "terrain" in world.last_error
    with pytest.raises(metariver.Error) as err:
        world.apply({"pbf": {"xsph": -1.0}})
    assert err.value.status == "MR_ERROR_SCENE" and "pbf.xsph" in err.value.message


@pytest.mark.parametrize("mode,sign", [("raise", 1), ("lower", -1)])
def test_sculpt_moves_the_ground_under_the_brush_only(world, mode, sign):
    before = world.terrain_heights()
    world.sculpt(x=20.0, z=30.0, radius=4.0, strength=1.5, mode=mode)
    delta = world.terrain_heights() - before
    assert sign * delta[30, 20] > 1.0  # the centre: row z = 30, column x = 20
    assert np.all(delta[:, :10] == 0) and np.all(delta[:20] == 0)  # far from it
    world.step()


def test_pour_push_move_source_and_sinks(world):
    active = world.stats.active_particles
    world.pour([20.0, 12.0, 10.0], 50)
    world.step()
    assert world.stats.active_particles > active
    assert world.push([20.0, 5.0, 30.0], 100.0, [0.0, 0.0, 1.0]) > 0
    world.move_source([20.0, 10.0, 8.0])
    world.set_sink_boxes([[0, -10, 60, 40, 30, 72]])
    world.set_sink_boxes(np.zeros((0, 6)))
    world.step()


def test_close_and_context_manager(heights):
    w = metariver.World(heights=heights, toml=SMALL)
    with w:
        w.step()
    assert w.closed
    with pytest.raises(metariver.Error, match="closed"):
        w.step()
    w.close()  # again: nothing


def test_threads_1_and_2_give_the_same_river(heights):
    runs = []
    for threads in (1, 2):
        with metariver.World(heights=heights, area_scale=1.0, height_scale=12.0, toml=SMALL, threads=threads) as w:
            w.step(frames=15)
            runs.append((w.particles(), w.surface()))
    (p1, s1), (p2, s2) = runs
    np.testing.assert_array_equal(p1.positions, p2.positions)
    np.testing.assert_array_equal(p1.velocities, p2.velocities)
    np.testing.assert_array_equal(s1.vertices, s2.vertices)
    np.testing.assert_array_equal(s1.indices, s2.indices)


def test_float32_heights_and_single_point_queries(world):
    with metariver.World(heights=valley(20, 16).astype(np.float32), toml=SMALL) as w:
        assert (w.terrain.columns, w.terrain.rows) == (16, 20)
    one = world.sample([20.0, 30.0])
    assert one.shape == () and one.dtype == metariver.WATER_SAMPLE_DTYPE
    assert world.velocity_at([20.0, 5.0, 30.0]).shape == (3,)
    with pytest.raises(ValueError, match="count"):
        world.pour([20.0, 12.0, 10.0], 0)


def test_without_a_library_the_error_says_what_to_do(tmp_path):
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "METARIVER_LIBRARY"}
    env["PYTHONPATH"] = str(REPO / "python")
    code = "import metariver\ntry:\n    metariver.World()\nexcept metariver.Error as e:\n    print(e)\n"
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert "METARIVER_LIBRARY" in out.stdout and "pip install" in out.stdout, out.stdout + out.stderr
    env["METARIVER_LIBRARY"] = str(tmp_path / "nope.so")
    out = subprocess.run([sys.executable, "-c", code], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert "nope.so" in out.stdout and "no such file" in out.stdout, out.stdout + out.stderr
