"""World's bodies (mr_world_add_body & co): added, read back, thrown, removed, and the
refusals that name the field."""
from __future__ import annotations

import numpy as np
import pytest

import metariver


def _above_middle(world) -> tuple[float, float, float]:
    t = world.terrain
    return (0.5 * (t.columns - 1) * t.area_scale, t.max_y + 3.0, 0.5 * (t.rows - 1) * t.area_scale)


def test_a_body_is_added_read_thrown_and_removed(world):
    p = _above_middle(world)
    log = world.add_body("box", (2.0, 0.5, 0.5), density=500.0, position=p)
    ball = world.add_body("sphere", (0.4, 0.0, 0.0), density=800.0, position=(p[0] + 4.0, p[1], p[2]))
    assert log != ball
    b = world.bodies()
    assert b.dtype == metariver.BODY_STATE_DTYPE
    assert list(b["id"]) == [log, ball]
    assert [metariver.BODY_SHAPES[s] for s in b["shape"]] == ["box", "sphere"]
    np.testing.assert_allclose(b["position"][0], p, rtol=1e-6)
    np.testing.assert_allclose(b["orientation"][0], (0.0, 0.0, 0.0, 1.0), atol=1e-6)
    assert b["mass"][0] == pytest.approx(500.0 * 2.0 * 0.5 * 0.5, rel=1e-4)

    to = (p[0] - 2.0, p[1] + 1.0, p[2])
    world.set_body_motion(log, to, velocity=(3.0, 0.0, 0.0))
    assert world.bodies()["velocity"][0][0] == pytest.approx(3.0)
    world.step(frames=6)
    b = world.bodies()
    assert b["position"][0][0] > to[0] + 0.2, "thrown along +x"
    assert b["position"][0][1] < to[1], "falling"

    world.remove_body(log)
    assert list(world.bodies()["id"]) == [ball]
    with pytest.raises(metariver.Error) as e:
        world.remove_body(log)
    assert "id" in e.value.message and e.value.status == "MR_ERROR_INVALID_ARGUMENT"


def test_bad_values_name_the_field(world):
    p = _above_middle(world)
    with pytest.raises(metariver.Error, match="bodies.density"):
        world.add_body(density=-1.0, position=p)
    with pytest.raises(ValueError, match="shape"):
        world.add_body("cone", position=p)
    with pytest.raises(ValueError, match="position"):
        world.add_body(position=(0.0, float("nan"), 0.0))
    with pytest.raises(metariver.Error) as e:
        world.add_body("convex_mesh", (1.0, 0.0, 0.0), mesh="/nonexistent/rock.obj", position=p)
    assert e.value.status == "MR_ERROR_IO" and "/nonexistent/rock.obj" in e.value.message
    with pytest.raises(ValueError, match="id"):
        world.remove_body(-1)
    log = world.add_body(position=p)
    with pytest.raises(ValueError, match="orientation"):
        world.set_body_motion(log, p, orientation=(0.0, 0.0, 1.0))
    with pytest.raises(metariver.Error, match="orientation"):
        world.set_body_motion(log, p, orientation=(0.0, 0.0, 0.0, 0.0))
    assert len(world.bodies()) == 1
    assert world.bodies()["position"][0][1] == pytest.approx(p[1]), "a refused motion moved nothing"


def test_a_solver_without_bodies_refuses_them():
    with metariver.World(preset="paper-bowl", threads=2) as w:
        with pytest.raises(metariver.Error) as e:
            w.add_body(position=(1.0, 30.0, 1.0))
        assert e.value.status == "MR_ERROR_UNSUPPORTED"
        assert len(w.bodies()) == 0


def test_a_box_floats_on_the_grids_lake():
    """solver = "swe": the grid's water floats the body one way (docs/bodies.md)."""
    toml = 'solver = "swe"\n[swe]\ninitial_level = 13.0\nedges = "open"\n'
    with metariver.World(toml=toml, threads=2) as w:
        w.step()
        g = w.heightfield()
        inner = np.zeros_like(g.depth)
        inner[5:-5, 5:-5] = g.depth[5:-5, 5:-5]  # the deepest cell away from the map's edges
        row, col = np.unravel_index(int(np.argmax(inner)), g.depth.shape)
        assert g.depth[row, col] > 2.0
        p = (g.origin[0] + col * g.spacing, 13.5, g.origin[1] + row * g.spacing)
        box = w.add_body("box", (1.0, 1.0, 1.0), density=500.0, position=p)
        w.step(frames=300)
        b = w.bodies()
        assert len(b) == 1 and b["id"][0] == box
        assert b["submerged_fraction"][0] == pytest.approx(0.5, abs=0.02)
        assert b["position"][0][1] == pytest.approx(13.0, abs=0.02), "half of it under the level"
        w.remove_body(box)
        assert len(w.bodies()) == 0
