"""The declarative validator: each constraint kind accepts what it declares and refuses the
rest in one line naming the parameter, the value, what to give and its unit; every parameter
class declares only fields it has, and every numeric field it has."""

from __future__ import annotations

import dataclasses
import importlib
import math
from dataclasses import dataclass
from numbers import Integral, Real
from typing import ClassVar

import numpy as np
import pytest

from skinhil.errors import ConfigError
from skinhil.validation import (
    PROBABILITY,
    Constraints,
    InstanceOf,
    Interval,
    Options,
    Predicate,
    StrOptions,
    check_param,
    finite,
    non_negative,
    positive,
    validate_params,
)

PARAMETER_CLASSES = [
    ("skinhil.model.skin", "SkinParams"),
    ("skinhil.model.neurons", "NoiseParams"),
    ("skinhil.model.neurons", "IzhikevichParams"),
    ("skinhil.model.psp", "PSPParams"),
    ("skinhil.model.stimuli", "Stimulus"),
    ("skinhil.world.contact", "ContactParams"),
    ("skinhil.world.indenters", "Indenter"),
    ("skinhil.world.trajectory", "Trajectory"),
    ("skinhil.world.scene", "Contact"),
    ("skinhil.plant.lifts", "GraspParams"),
    ("skinhil.receiver.params", "OnsetParams"),
    ("skinhil.receiver.params", "ReceiverParams"),
    ("skinhil.receiver.grip_reflex", "ReflexParams"),
    ("skinhil.transports.faults", "FaultParams"),
    ("skinhil.decoding.features", "FeatureSpec"),
    ("skinhil.analysis.phases", "PhaseWindows"),
    ("skinhil.analysis.sweep", "SweepSpec"),
    ("skinhil.analysis.decoding_snr", "DecodingSetup"),
    ("skinhil.campaign.rig", "RigBounds"),
    ("firmware_sim.config", "BoardConfig"),
]
"""The classes whose fields are declared through the validator."""


def _refusal(declared: object, value: object) -> str:
    with pytest.raises(ConfigError) as info:
        check_param("x_s", value, declared, where="Thing.")  # type: ignore[arg-type]
    message = str(info.value)
    shown = repr(value) if len(repr(value)) <= 60 else repr(value)[:57] + "..."
    assert "\n" not in message and message.startswith(f"Thing.x_s = {shown} — give ")
    return message


@pytest.mark.parametrize("closed, inside, outside", [
    ("neither", [0.5, 1e-300], [0, 0.0, 1.0, 1, -1]),
    ("left", [0, 0.5], [1, -1e-300]),
    ("right", [1, 0.5], [0, 1.5]),
    ("both", [0, 1, 0.25], [-0.1, 1.1]),
])
def test_interval_ends(closed: str, inside: list[float], outside: list[float]) -> None:
    c = Interval(Real, 0, 1, closed=closed, unit="s")  # type: ignore[arg-type]
    for v in inside:
        check_param("x_s", v, c)
    lo, hi = "[" if closed in ("left", "both") else "(", "]" if closed in ("right", "both") \
        else ")"
    for v in outside:
        assert _refusal(c, v).endswith(f"give a finite number in {lo}0, 1{hi} (s)")


def test_interval_refuses_nan_infinities_bools_and_text_unless_inf_is_a_bound() -> None:
    c = positive("kg")
    for v in (math.nan, math.inf, -math.inf, True, "1", None, np.array([1.0])):
        assert _refusal(c, v).endswith("give a finite number > 0 (kg)")
    for v in (1, 2.5, np.float32(3), np.int64(4)):
        check_param("x_s", v, c)
    to_inf = Interval(Real, 0, math.inf, closed="right", unit="s", hint="inf: constant")
    check_param("x_s", math.inf, to_inf)
    assert _refusal(to_inf, 0).endswith("give a finite number > 0 (s), or inf; inf: constant")
    assert _refusal(to_inf, math.nan)
    open_top = Interval(Real, 0, math.inf, closed="left")
    assert _refusal(open_top, math.inf).endswith("give a finite number >= 0")


def test_interval_kinds_bounds_and_finite_numbers() -> None:
    whole = Interval(Integral, 1, None, closed="left", unit="channels")
    check_param("x_s", np.int32(3), whole)
    assert _refusal(whole, 2.0).endswith("give a whole number >= 1 (channels)")
    assert _refusal(whole, 0).endswith("give a whole number >= 1 (channels)")
    check_param("x_s", 10**400, whole)  # beyond a float's range, compared exactly
    assert _refusal(Interval(Integral, 0, 10, closed="both"), 10**400)
    below = Interval(Real, None, 0, closed="neither")
    assert _refusal(below, 0).endswith("give a finite number < 0")
    assert _refusal(finite("mV"), math.inf).endswith("give a finite number (mV)")
    check_param("x_s", -1e300, finite("mV"))
    assert _refusal(non_negative("N"), -0.5).endswith("give a finite number >= 0 (N)")
    assert _refusal(PROBABILITY, 1.5).endswith("give a finite number in [0, 1] (probability)")
    with pytest.raises(TypeError):
        Interval(float, 0, 1, closed="both")
    with pytest.raises(TypeError):
        Interval(Real, 0, 1, closed="open")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        Interval(Real, 2, 1, closed="both")


def test_str_options_and_options() -> None:
    c = StrOptions(("auto", "linear", "geometric"))
    check_param("x_s", "linear", c)
    for v in ("Linear", 1, None, b"auto"):
        assert _refusal(c, v).endswith("give 'auto', 'linear' or 'geometric'")
    assert StrOptions({"b", "a"}).describe() == "'a' or 'b'"
    o = Options([math.inf, 0])
    check_param("x_s", math.inf, o)
    check_param("x_s", 0, o)
    assert _refusal(o, False).endswith("give inf or 0")
    assert _refusal(o, np.array([0, 0])).endswith("give inf or 0")


def test_instance_of_predicate_and_alternatives() -> None:
    i = InstanceOf(str, "a name")
    check_param("x_s", "ok", i)
    assert _refusal(i, 3).endswith("give a name")
    p = Predicate(lambda v: v[0] < v[1], "(start, stop) with start < stop")
    check_param("x_s", (0, 1), p)
    assert _refusal(p, (1, 0)).endswith("give (start, stop) with start < stop")
    assert _refusal(p, 5).endswith("give (start, stop) with start < stop")  # TypeError inside
    either = [Interval(Integral, 0, None, closed="left", unit="count"), None]
    check_param("x_s", None, either)
    check_param("x_s", 3, either)
    assert _refusal(either, -1).endswith("give a whole number >= 0 (count) or None")


def test_a_long_value_is_cut_in_the_message() -> None:
    with pytest.raises(ConfigError) as info:
        check_param("x_s", "z" * 1000, positive("s"))
    assert len(str(info.value)) < 120


@dataclass(frozen=True)
class _Example:
    rate_hz: float = 1.0
    mode: str = "a"

    _parameter_constraints: ClassVar[Constraints] = {
        "rate_hz": positive("Hz"),
        "mode": StrOptions(("a", "b")),
    }

    def __post_init__(self) -> None:
        validate_params(self)


def test_validate_params_names_the_class_and_checks_in_order() -> None:
    assert _Example(2.0, "b").rate_hz == 2.0
    assert "_parameter_constraints" not in {f.name for f in dataclasses.fields(_Example)}
    with pytest.raises(ConfigError, match=r"^_Example\.rate_hz = -1 — give a finite number "
                                          r"> 0 \(Hz\)$"):
        _Example(-1, "c")
    with pytest.raises(ConfigError, match=r"^_Example\.mode = 'c' — give 'a' or 'b'$"):
        _Example(1, "c")
    with pytest.raises(ConfigError, match=r"^thing 'p': mode = 'c'"):
        validate_params(_Bare(), where="thing 'p': ")


class _Bare:
    rate_hz = 1.0
    mode = "c"
    _parameter_constraints = _Example._parameter_constraints


@pytest.mark.parametrize("module, name", PARAMETER_CLASSES)
def test_every_parameter_class_declares_its_fields(module: str, name: str) -> None:
    cls = getattr(importlib.import_module(module), name)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    declared = cls._parameter_constraints
    assert set(declared) <= set(fields), set(declared) - set(fields)
    numeric = {n for n, f in fields.items()
               if f.init and isinstance(f.default, int | float) and not isinstance(f.default, bool)}
    assert numeric <= set(declared), f"{name} leaves {numeric - set(declared)} unchecked"
    for field_name, f in fields.items():  # every default passes its own declaration
        if field_name in declared and f.default is not dataclasses.MISSING:
            check_param(field_name, f.default, declared[field_name])


@pytest.mark.parametrize("build, says", [
    (lambda: __import__("skinhil").SkinParams(mass_kg=-1.0),
     "SkinParams.mass_kg = -1.0 — give a finite number > 0 (kg)"),
    (lambda: __import__("skinhil").SkinParams(linear_stepper="rk4"),
     "SkinParams.linear_stepper = 'rk4' — give 'auto', 'exact' or 'leapfrog'"),
    (lambda: __import__("skinhil").Stimulus("s", {15: (0, 0, -1)}, decay_tau_s=0.0),
     "stimulus 's': decay_tau_s = 0.0 — give a finite number > 0 (s), or inf"),
    (lambda: importlib.import_module("skinhil.transports.faults").FaultParams(drop_p=2),
     "FaultParams.drop_p = 2 — give a finite number in [0, 1] (probability)"),
    (lambda: importlib.import_module("skinhil.world.indenters").Indenter(radius_m=1.0),
     "indenter radius_m = 1.0 — give a finite number in (0, 0.1] (m)"),
    (lambda: importlib.import_module("skinhil.receiver.params").OnsetParams(z=-1),
     "OnsetParams.z = -1 — give a finite number >= 0 (baseline standard deviations)"),
])
def test_parameter_classes_refuse_in_one_line(build, says: str) -> None:
    with pytest.raises(ConfigError) as info:
        build()
    assert str(info.value).startswith(says), str(info.value)
