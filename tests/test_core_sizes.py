"""Skins of any size: the pyramid mesh, its numbering, stimuli and schedules per size."""

import numpy as np
import pytest

from skinhil import SkinModel, SkinParams, Stimulus
from skinhil.errors import ConfigError
from skinhil.model.geometry import (
    build_mesh,
    layer_shapes,
    mass_count,
    mass_index,
    mass_position,
    parse_size,
    spring_count,
)
from skinhil.model.sensor import SkinSensor
from skinhil.model.stimuli import at_size, builtin_catalog, paper_stimuli
from skinhil.model.timeline import Timeline


@pytest.mark.parametrize("size", [(3, 3), (6, 6), (4, 7), (16, 16), (26, 26)])
def test_pyramid_counts_and_structure(size: tuple[int, int]) -> None:
    mesh = build_mesh(1e-3, 1e-3, size)
    rows, cols = size
    assert layer_shapes(size) == ((rows, cols), (rows - 1, cols - 1), (rows - 2, cols - 2))
    assert mesh.positions.shape == (mass_count(size), 3)
    assert mesh.springs.shape == (spring_count(size), 2)
    assert len({tuple(sorted(s)) for s in mesh.springs.tolist()}) == spring_count(size)
    # every lower mass lies under the centre of its cell, one layer gap down
    for layer in (1, 2):
        r, c = layer_shapes(size)[layer]
        for row, col in ((0, 0), (r - 1, c - 1)):
            low = mesh.positions[mass_index(layer, row, col, size)]
            cell = [mesh.positions[mass_index(layer - 1, row + dr, col + dc, size)]
                    for dr in (0, 1) for dc in (0, 1)]
            np.testing.assert_allclose(low, np.mean(cell, axis=0) - [0, 0, 1e-3], atol=1e-15)
    # free: the inner masses of layers 1 and 2; layer 3 is fixed
    free = (rows - 2) * (cols - 2) + (rows - 3) * (cols - 3)
    assert mesh.free.size == free


def test_paper_size_is_the_paper_mesh() -> None:
    assert (mass_count(), spring_count()) == (77, 338)
    mesh = build_mesh(1e-3, 1e-3)
    assert [5, 10] in mesh.springs.tolist()  # the diagonal M6-M11 of Figure 1B
    assert mass_position(14) == (0, 2, 2)  # M15: layer 1, row 3, column 3
    assert spring_count((26, 26)) == 10138


@pytest.mark.parametrize("text", ["2x6", "6x", "abc", "0", "6x2"])
def test_bad_sizes_are_refused(text: str) -> None:
    with pytest.raises(ConfigError, match="mesh size"):
        parse_size(text)
    assert parse_size("16x12") == (16, 12) and parse_size("9") == (9, 9)


def test_mass_numbers_are_checked_against_the_size() -> None:
    with pytest.raises(ConfigError, match="unknown mass number 78; use mass numbers 1..77"):
        Stimulus("s", {78: (0, 0, 1)})
    big = Stimulus("s", {600: (0, 0, -0.1)}, size=(16, 16))
    assert big.peak_forces_n.shape == (mass_count((16, 16)), 3)
    with pytest.raises(ConfigError, match="defined on a 16x16 skin, this one is 6x6"):
        SkinModel().simulate(big, 0.01)
    with pytest.raises(ConfigError, match="unknown mass number 2000"):
        Stimulus("s", {2000: (0, 0, 1)}, size=(16, 16))


def test_builtins_keep_their_place_relative_to_the_centre() -> None:
    a = paper_stimuli()[0]
    assert at_size(a, (6, 6)) is a
    assert list(at_size(a, (16, 16)).forces) == [mass_index(0, 7, 7, (16, 16)) + 1]
    assert list(at_size(a, (3, 3)).forces) == [5]
    b = builtin_catalog((3, 3))["B"][1]  # M15's neighbour: on the fixed edge of a 3x3 skin
    with pytest.raises(ConfigError, match="fixed mass"):
        SkinModel(SkinParams(size=(3, 3))).simulate(b, 0.01)
    # the moved press deflects the 16x16 skin as the 6x6 one, near its centre
    f16, f6 = (SkinModel(SkinParams(size=size, mechanics="linear")).simulate(at_size(a, size),
                                                                             0.05)
               for size in ((16, 16), (6, 6)))
    assert 0.5 < np.abs(f16).max() / np.abs(f6).max() < 2.0


@pytest.mark.parametrize("size, mechanics", [((3, 3), "linear"), ((5, 8), "linear"),
                                             ((10, 10), "linear"), ((10, 10), "geometric")])
def test_any_size_senses_a_press(size: tuple[int, int], mechanics: str) -> None:
    model = SkinModel(SkinParams(size=size, mechanics=mechanics))  # type: ignore[arg-type]
    timeline = Timeline(1e-4, size=size)
    sensor = SkinSensor(model, 1e-4, seed=1)
    springs, spikes = sensor.advance_schedule(timeline.schedule, 4000)
    assert springs.shape == spikes.shape == (4000, spring_count(size))
    assert np.abs(springs).max() > 1e-3 and spikes.any()


def test_schedule_of_another_size_is_refused() -> None:
    timeline = Timeline(1e-4, size=(8, 8))
    with pytest.raises(ConfigError, match="8x8 skin, this one is 6x6"):
        SkinSensor().advance_schedule(timeline.schedule, 10)


def test_trial_events_are_the_raster_s_spikes() -> None:
    from skinhil.model.neurons import raster_to_events
    from skinhil.model.stimuli import direction_conditions
    from skinhil.model.trials import simulate_trial_events, simulate_trials

    stims = direction_conditions()[7:9]
    raster = simulate_trials(stims, 3, duration_s=0.12, snr_db=10.0, seed=4)
    events = simulate_trial_events(stims, 3, duration_s=0.12, snr_db=10.0, seed=4)
    assert raster.any()
    for i in range(2):
        for r in range(3):
            assert np.array_equal(events[i][r], raster_to_events(raster[i, r], 1e-4))


def test_sweep_point_at_another_size() -> None:
    # the information measures of one K x C point on a 7x7 skin (exact modal path)
    from dataclasses import replace

    from skinhil.analysis.sweep import evaluate_point

    measures = evaluate_point(replace(SkinParams(), size=(7, 7)))
    assert all(np.isfinite(v) for v in vars(measures).values())


def test_a_skin_beyond_16_bit_addresses_is_refused() -> None:
    with pytest.raises(ConfigError, match="66226 sensors; event addresses are 16-bit"):
        SkinSensor(SkinModel(SkinParams(size=(64, 64))))
