"""Feature definition: binning, channel selection, online = offline, serialisation."""

import numpy as np
import pytest

from skinhil import PSPFilterBank, PSPParams
from skinhil.decoding import FeatureSpec
from skinhil.errors import ConfigError


def test_bin_means_and_order() -> None:
    spec = FeatureSpec(dt_s=1e-3, window_s=0.004, bin_s=0.002, n_channels=3)
    trace = np.arange(6 * 3, dtype=float).reshape(6, 3)  # 6 steps, 2 beyond the window
    feats = spec.transform(trace)
    assert spec.n_bins == 2 and spec.n_features == 6
    expected = np.concatenate([trace[0:2].mean(0), trace[2:4].mean(0)])
    np.testing.assert_allclose(feats, expected)


def test_channel_subset() -> None:
    spec = FeatureSpec(dt_s=1e-3, window_s=0.002, bin_s=0.001, channels=(0, 2), n_channels=3)
    trace = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    np.testing.assert_allclose(spec.transform(trace[None]), [[1.0, 3.0, 4.0, 6.0]])


def test_online_psp_trace_gives_offline_features() -> None:
    rng = np.random.default_rng(3)
    spec = FeatureSpec(dt_s=1e-4, window_s=0.02, bin_s=0.005, n_channels=7)
    raster = rng.random((250, 7)) < 0.02
    bank = PSPFilterBank(7, spec.dt_s, spec.psp)
    online = np.stack([bank.step(row.astype(float)) for row in raster])
    np.testing.assert_allclose(spec.transform(online), spec.raster_features(raster),
                               rtol=1e-9, atol=1e-12)


def test_raster_features_batched_equals_single() -> None:
    rng = np.random.default_rng(4)
    spec = FeatureSpec(dt_s=1e-4, window_s=0.01, bin_s=0.005, n_channels=5)
    raster = rng.random((2, 3, 100, 5)) < 0.05
    many = spec.raster_features(raster, chunk_trials=2)
    assert many.shape == (2, 3, spec.n_features)
    np.testing.assert_allclose(many[1, 2], spec.raster_features(raster[1, 2]))


def test_dict_round_trip() -> None:
    spec = FeatureSpec(dt_s=2e-4, window_s=0.04, bin_s=0.02, channels=(1, 5), n_channels=9,
                       psp=PSPParams(tau_d_ms=3.0))
    assert FeatureSpec.from_dict(spec.to_dict()) == spec


@pytest.mark.parametrize("kwargs", [dict(window_s=0.05, bin_s=0.03), dict(bin_s=0.0),
                                    dict(window_s=0.00015), dict(channels=(3, 1)),
                                    dict(channels=(400,))])
def test_bad_specs_refused(kwargs: dict) -> None:
    with pytest.raises(ConfigError):
        FeatureSpec(**kwargs)


def test_short_trace_refused() -> None:
    spec = FeatureSpec()
    with pytest.raises(ConfigError, match="steps"):
        spec.transform(np.zeros((spec.n_steps - 1, 338)))
    with pytest.raises(ConfigError, match="shape"):
        spec.transform(np.zeros((spec.n_steps, 337)))
