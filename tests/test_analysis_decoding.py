"""Figure 4's decoding: feature sets select exactly the columns FeatureSpec(channels) gives,
and the figure's longer single-sensor trials are the decoding's own trials."""

import math

import numpy as np

from skinhil.analysis.decoding_snr import (
    DecodingSetup,
    FeatureSet,
    decode_feature_sets,
    split_standard_error,
    trial_features,
    trial_standard_error,
)
from skinhil.decoding import FeatureSpec
from skinhil.model.stimuli import direction_conditions
from skinhil.model.trials import simulate_trials


def test_feature_set_columns_equal_a_channel_subset_spec() -> None:
    rng = np.random.default_rng(5)
    base = FeatureSpec(dt_s=1e-4, window_s=0.02, bin_s=0.005, n_channels=9)
    raster = rng.random((4, 200, 9)) < 0.05
    full = base.raster_features(raster)
    for chans in ((3,), (0, 4, 8)):
        fs = FeatureSet("x", chans)
        np.testing.assert_allclose(full[:, fs.columns(base)],
                                   fs.spec(base).raster_features(raster), rtol=1e-12)
    np.testing.assert_array_equal(FeatureSet("all").columns(base), np.arange(full.shape[1]))


def test_kept_channels_and_longer_trials_are_the_same_trials() -> None:
    setup = DecodingSetup(reps=3, repeats=2)
    x, y = trial_features(10.0, setup, seed=7)
    longer = simulate_trials(direction_conditions(), 3, duration_s=0.08, snr_db=10.0, seed=7,
                             channels=[67, 201])
    assert longer.shape == (9, 3, 800, 2)
    # the first 50 ms of the kept sensors give the decoding's features of those sensors
    base = setup.spec
    sub = FeatureSet("two", (67, 201))
    own = replace_channels(base, 2).raster_features(longer[:, :, :base.n_steps])
    np.testing.assert_allclose(own.reshape(len(y), -1), x[:, sub.columns(base)], rtol=1e-12)
    assert own.any()


def replace_channels(spec: FeatureSpec, n: int) -> FeatureSpec:
    return FeatureSpec(dt_s=spec.dt_s, window_s=spec.window_s, bin_s=spec.bin_s, n_channels=n)


def test_feature_sets_share_trials_and_report_their_errors() -> None:
    setup = DecodingSetup(reps=6, repeats=3)
    out = decode_feature_sets([FeatureSet("s67", (67,)), FeatureSet("all")], (math.inf,),
                              setup)
    assert set(out) == {"s67", "all"} and all(len(v) == 1 for v in out.values())
    cv = out["all"][0]
    assert cv.accuracy > 3 / 9  # noise-free forces on all sensors
    assert cv.confusion.sum() == 3 * 9 * 6
    p = cv.accuracy
    assert trial_standard_error(cv) == math.sqrt(p * (1 - p) / 54)
    assert split_standard_error(cv) >= 0.0
