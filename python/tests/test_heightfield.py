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


# The grid's rain per cell (World.set_rain) and volumes (World.water_balance).
RAIN = {"solver": "swe", "swe": {"discharge": 0.0, "rain": 36.0}, "terrain": {"condition": "none"}}


@pytest.fixture
def rainy():
    """A dry 50 x 30 valley at 2 m a cell under the scene's 36 mm/h, no source."""
    with metariver.World(heights=valley(50, 30), area_scale=2.0, height_scale=10.0, toml=RAIN, threads=2) as w:
        yield w


def rained(rate: np.ndarray, spacing: float, seconds: float) -> float:
    """m^3 that `rate` (mm/h per cell, as the library reads it: float32) rains in `seconds`."""
    return float(rate.astype(np.float32).astype(np.float64).sum()) * 1e-3 / 3600.0 * spacing ** 2 * seconds


def test_rain_from_a_mask_rains_its_integral_times_the_rate(rainy):
    g = rainy.heightfield()
    mask = np.broadcast_to(np.linspace(0.0, 1.0, g.depth.shape[1]), g.depth.shape)  # 0 at column 0 .. 1
    rainy.set_rain(mask * 3600.0)  # 1 mm/s where the mask is 1
    rainy.step(frames=30)
    b = rainy.water_balance()
    assert b.rain_set and b.substeps > 0
    assert b.simulated_s == pytest.approx(0.5, abs=1e-6)
    expected = rained(mask * 3600.0, g.spacing, b.simulated_s)
    assert expected > 1.0
    assert b.rain == pytest.approx(expected, rel=1e-9)  # round-off of the grid's double sums
    assert abs(b.error) < 1e-9 * expected


def test_zero_rain_rains_nothing_and_none_brings_the_scenes_rain_back(rainy):
    shape = rainy.heightfield().depth.shape
    rainy.set_rain(np.zeros(shape, np.float32))
    rainy.step(frames=10)
    b = rainy.water_balance()
    assert b.rain == 0.0 and b.stored == 0.0 and (rainy.heightfield().depth == 0).all()
    rainy.set_rain(None)
    assert not rainy.water_balance().rain_set
    rainy.step(frames=10)
    after = rainy.water_balance()
    assert after.rain == pytest.approx(rained(np.full(shape, 36.0), 2.0, after.simulated_s - b.simulated_s), rel=1e-9)


@pytest.mark.parametrize("bad, message", [
    (lambda s: np.ones((s[1], s[0])), r"mm_per_h: expected shape \(50, 30\)"),
    (lambda s: np.ones(s[0] * s[1]), r"mm_per_h: expected shape \(50, 30\)"),
    (lambda s: np.ones(s, np.complex64), "mm_per_h: expected an array of real numbers"),
    (lambda s: np.full(s, "1"), "mm_per_h: expected an array of real numbers"),
    (lambda s: np.ones(s, bool), "mm_per_h: expected an array of real numbers"),
    (lambda s: np.where(np.arange(s[0] * s[1]).reshape(s) == 37, np.nan, 1.0), r"mm_per_h\[1, 7\]: must be finite"),
    (lambda s: np.full(s, -1.0), r"mm_per_h\[0, 0\]: must be finite in \[0, 10000\] mm/h, got -1.0 \(1500 such"),
    (lambda s: np.full(s, np.inf), r"mm_per_h\[0, 0\]"),
    (lambda s: np.full(s, 2e4), r"mm_per_h\[0, 0\]"),
])
def test_bad_rain_is_refused_naming_the_argument(rainy, bad, message):
    with pytest.raises(ValueError, match=message):
        rainy.set_rain(bad((50, 30)))
    rainy.step(frames=3)
    b = rainy.water_balance()  # nothing changed: the scene's 36 mm/h still falls
    assert not b.rain_set
    assert b.rain == pytest.approx(rained(np.full((50, 30), 36.0), 2.0, b.simulated_s), rel=1e-9)


def test_a_particle_world_has_no_rain_grid(world):
    with pytest.raises(metariver.Error, match="mr_world_set_rain: solver = \"pbf\" has no water grid"):
        world.set_rain(None)
    with pytest.raises(metariver.Error, match="has no water grid"):
        world.water_balance()


def test_sources_given_as_a_list_of_dicts_pour_their_discharge(rainy):
    rainy.set_rain(np.zeros((50, 30)))
    assert rainy.apply({"swe": {"sources": [{"start": [30.0, 0.0, 10.0], "discharge": 2.0},
                                            {"shape": "line", "start": [20.0, 0.0, 40.0], "end": [40.0, 0.0, 40.0],
                                             "discharge": 0.5}]}})
    rainy.step(frames=20)
    b = rainy.water_balance()
    assert b.inflow == pytest.approx(2.5 * b.simulated_s, rel=1e-6)  # float32 discharges summed in doubles
    assert b.stored == pytest.approx(b.inflow, rel=1e-9)  # nothing has reached an edge yet


def test_warnings_name_a_source_off_the_map(rainy):
    assert not any("swe.sources" in w for w in rainy.warnings)
    rainy.apply({"swe": {"sources": [{"start": [-500.0, 0.0, 10.0], "discharge": 1.0}]}})
    assert any(w.startswith("swe.sources[1]: lies outside the terrain") for w in rainy.warnings), rainy.warnings
