"""Sweeps: the modal path equals the full simulation; local, in-process and Dask runs agree."""

from dataclasses import replace

import numpy as np
import pytest

from skinhil import SkinModel, SkinParams, paper_stimuli
from skinhil.analysis import SweepSpec, information_measures, run_sweep
from skinhil.analysis.modal_response import reduced_responses, supports
from skinhil.errors import ConfigError


@pytest.mark.parametrize("k, c", [(50.0, 0.05), (7.0, 0.3)])
def test_modal_responses_equal_skin_model(k: float, c: float) -> None:
    params = SkinParams(stiffness_n_per_m=k, damping_n_s_per_m=c, readout="axial",
                        mechanics="linear")
    stimuli = paper_stimuli()
    fast = reduced_responses(params, stimuli, 0.5, 5e-4)
    full = SkinModel(params).simulate_many(stimuli, 0.5, 5e-4)
    np.testing.assert_allclose(fast.full_forces(), full, rtol=0, atol=1e-10 * np.abs(full).max())
    a = information_measures(fast.reduced, 5e-4)
    b = information_measures(full, 5e-4)
    for name, value in a.as_dict().items():
        assert value == pytest.approx(getattr(b, name), rel=1e-6), name


def test_modal_path_refuses_tension_and_the_length_readout() -> None:
    with pytest.raises(ConfigError, match="tension"):
        reduced_responses(SkinParams(tension_n=0.1, readout="axial", mechanics="linear"),
                          paper_stimuli(), 0.5, 5e-4)
    # the length change is not linear in the displacements: no reduced basis is exact
    length = SkinParams(mechanics="linear")
    assert not supports(length) and supports(replace(length, readout="axial"))
    with pytest.raises(ConfigError, match="readout"):
        reduced_responses(length, paper_stimuli(), 0.5, 5e-4)


def test_local_processes_and_dask_give_identical_results() -> None:
    distributed = pytest.importorskip("distributed")
    spec = SweepSpec.log_grid(3, 2, tension_n=(0.0, 0.05))
    inline = run_sweep(spec, workers=1, progress=False)
    local = run_sweep(spec, workers=2, progress=False)
    with distributed.LocalCluster(n_workers=2, processes=False, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        remote = run_sweep(spec, scheduler=cluster.scheduler_address, progress=False)
    for name, values in inline.values.items():
        assert values.shape == (2, 3, 2)
        assert np.array_equal(values, local.values[name], equal_nan=True), name
        assert np.array_equal(values, remote.values[name], equal_nan=True), name
    assert np.all(np.isfinite(inline.values["area"]))
    # tension changes the mechanics, so it must change the measures somewhere
    assert not np.array_equal(inline.values["area"][0], inline.values["area"][1])


def test_unreachable_scheduler_is_a_config_error() -> None:
    pytest.importorskip("distributed")
    spec = SweepSpec.log_grid(1, 1)
    with pytest.raises(ConfigError, match="Dask scheduler"):
        run_sweep(spec, scheduler="tcp://127.0.0.1:9", progress=False, connect_timeout_s=1.0)
