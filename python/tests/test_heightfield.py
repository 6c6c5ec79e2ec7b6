"""The shallow-water grid through World.heightfield() (the C API's mr_world_heightfield)."""
from __future__ import annotations

import numpy as np
import pytest

import metariver

from conftest import valley


def test_a_still_lake_reads_back_as_depth_over_the_bed():
    h = valley(50, 30)
    # open edges: the lake reaches the map's edge, where an outfall (the default) would drain it
    toml = {"solver": "swe", "swe": {"initial_level": 4.0, "edges": "open"}, "terrain": {"condition": "none"}}
    with metariver.World(heights=h, area_scale=2.0, height_scale=10.0, toml=toml, threads=2) as w:
        w.step(frames=5)
        g = w.heightfield()
        assert g.depth.shape == (50, 30) and g.depth.dtype == np.float32
        assert g.velocity.shape == (50, 30, 2)
        assert g.spacing == 2.0
        np.testing.assert_allclose(g.bed, w.terrain_heights())
        np.testing.assert_allclose(g.depth, np.maximum(4.0 - g.bed, 0.0), atol=1e-4)  # at rest: flat at 4 m
        np.testing.assert_allclose(g.velocity, 0.0, atol=1e-3)
        assert (g.depth > 0).sum() > 50


def test_a_particle_world_has_no_grid(world):
    with pytest.raises(metariver.Error, match="has no water grid"):
        world.heightfield()
