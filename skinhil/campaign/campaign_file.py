"""Campaign files: scenarios × parameters × repetitions × pass criteria, in TOML, checked
before any case runs (the format: ``docs/campaigns.md``)::

    name = "smoke"
    repetitions = 2                       # each case this many times (seed + 0, 1, ...)
    criteria = ["decisions >= 1"]         # every case: numbers of the score file

    [parameters]                          # a value or a list of values each: the cases are
    snr_db = [10.0, 30.0]                 # their product
    duration_s = 3.0

    [[scenario]]
    builtin = "random"                    # the board's seeded random schedule

    [[scenario]]
    file = "../scenarios/press.toml"      # a schedule or scenario file (relative to this one)
    criteria = ["onsets >= 1"]            # more criteria for this scenario's cases

    [rig]                                 # what counts as a fault of the rig, not the decoder
    max_lateness_ms = 50.0

Every table is checked with the schedule file's own helpers
(:func:`~skinhil.model.schedule_file.checked_table`,
:func:`~skinhil.model.schedule_file.table_list`): an unknown key or a value out of range is
refused with one line naming the entry and the key.
"""

from __future__ import annotations

import hashlib
import itertools
import math
import re
from dataclasses import dataclass, field
from numbers import Integral, Real
from pathlib import Path

from protocols.versions import MAX_CHANNELS
from skinhil.campaign.criteria import Criterion, parse_criterion
from skinhil.campaign.rig import RigBounds, rig_bounds_from_table
from skinhil.errors import ConfigError
from skinhil.model.geometry import PAPER_SIZE, format_size, parse_size, spring_count
from skinhil.model.neurons import MAX_SNR_DB, MIN_SNR_DB
from skinhil.model.schedule_file import (
    checked_table,
    parse_toml,
    read_schedule_text,
    table_list,
)
from skinhil.suites import case_ref, suite_trials
from skinhil.validation import Declaration, InstanceOf, Interval, Options, check_param
from skinhil.world.scenario_file import load_scenario

TOP_KEYS = ("name", "repetitions", "criteria", "parameters", "scenario", "rig")
SCENARIO_KEYS = ("name", "file", "builtin", "criteria")
BUILTINS = ("random",)
"""Schedules the board has built in (``builtin = "random"``: ``serve`` without
``--schedule``)."""
MAX_SCENARIOS = 100
MAX_CRITERIA = 100
MAX_VALUES = 100
"""Most values one parameter lists."""
MAX_REPETITIONS = 1000
MAX_CASES = 10_000
"""Most cases (scenarios × parameter combinations × repetitions) a campaign holds."""
MAX_NAME_CHARS = 64
SEED_MAX = 2**63 - 1
"""Largest board seed (``serve --seed``): a case's seed is its ``seed`` plus its repetition."""

PARAMETERS: dict[str, tuple[str, Declaration]] = {
    "snr_db": ("--snr-db", [Interval(Real, MIN_SNR_DB, MAX_SNR_DB, closed="both", unit="dB",
                                     hint="as serve --snr-db"), Options([math.inf])]),
    "seed": ("--seed", Interval(Integral, 0, SEED_MAX, closed="both", hint="as serve --seed")),
    "duration_s": ("--duration", Interval(Real, 0.0, 86400.0, closed="right", unit="s",
                                          hint="as serve --duration")),
    "response_window_s": ("--response-window",
                          Interval(Real, 0.0, 3600.0, closed="right", unit="s",
                                   hint="as serve --response-window")),
    "rest_s": ("--rest", Interval(Real, 0.0, 3600.0, closed="both", unit="s",
                                  hint="as serve --rest")),
    "size": ("--size", InstanceOf(str, 'the skin size as a string such as "6x6"')),
}
"""Parameter name: (``serve`` option it sets, what it takes). ``snr_db`` takes ``inf`` too
(no noise); ``size`` is a string such as ``"6x6"``."""
DEFAULTS: dict[str, float | int | str] = {"duration_s": 10.0, "seed": 1}
"""Values of the parameters a campaign does not give that a case needs (others: serve's
defaults)."""

_NAME = re.compile(r"^[A-Za-z0-9_.+-]{1,64}$")


@dataclass(frozen=True)
class Scenario:
    """One scenario: a schedule/scenario file (``file``), a built-in schedule
    (``builtin``) or a suite's case (``suite``, ``SUITE:CASE``: ``serve --suite``, its
    trials drawn from the case's seed), with the criteria its cases add to the campaign's."""

    name: str
    file: Path | None = None
    builtin: str | None = None
    criteria: tuple[Criterion, ...] = ()
    suite: str | None = None


@dataclass(frozen=True)
class Case:
    """One case: a scenario, one value of each parameter, one repetition (0-based)."""

    scenario: Scenario
    parameters: dict[str, float | int | str]
    repetition: int
    criteria: tuple[Criterion, ...]

    @property
    def id(self) -> str:
        """A stable name, unique in its campaign: ``scenario[k=v,...]#repetition``
        (1-based), each value as it is written shortest with its exact value (``1``,
        ``1.0000001``)."""
        params = ",".join(f"{k}={_text(v)}" for k, v in sorted(self.parameters.items()))
        return f"{self.scenario.name}[{params}]#{self.repetition + 1}"

    @property
    def seed(self) -> int:
        """The board's seed: the ``seed`` parameter plus the repetition, so repetitions
        differ in noise and in the random schedule."""
        return int(self.parameters.get("seed", DEFAULTS["seed"])) + self.repetition

    @property
    def holds_object(self) -> bool:
        """Whether the case's board holds an object (a suite case with a grasp)."""
        return self.scenario.suite is not None and case_ref(self.scenario.suite)[1].held_object

    @property
    def duration_s(self) -> float:
        """Board time (s) the case plays: a suite case's own length (its trials and tail)
        unless ``duration_s`` is given."""
        if self.scenario.suite is not None and "duration_s" not in self.parameters:
            size = parse_size(str(self.parameters.get("size", format_size(PAPER_SIZE))))
            return suite_trials(self.scenario.suite, self.seed, size).duration_s
        return float(self.parameters.get("duration_s", DEFAULTS["duration_s"]))


@dataclass(frozen=True)
class Campaign:
    """A checked campaign file: its cases in the order they run."""

    name: str
    path: Path
    digest: str
    """SHA-256 of the file's text (a resumed run refuses a changed campaign)."""
    scenarios: tuple[Scenario, ...]
    parameters: dict[str, tuple[float | int | str, ...]]
    repetitions: int
    criteria: tuple[Criterion, ...]
    rig: RigBounds = field(default_factory=RigBounds)

    def cases(self) -> list[Case]:
        """Every case: scenario-major, then the parameters' product, then repetitions."""
        names = sorted(self.parameters)
        out = []
        for scenario in self.scenarios:
            for values in itertools.product(*(self.parameters[n] for n in names)):
                for rep in range(self.repetitions):
                    out.append(Case(scenario, dict(zip(names, values, strict=True)), rep,
                                    self.criteria + scenario.criteria))
        return out


def _text(value: float | int | str) -> str:
    """``value`` in a case id: a float as ``:g`` gives it where that is its exact value,
    else as ``repr`` (the shortest text that reads back as the same float)."""
    if not isinstance(value, float):
        return str(value)
    short = f"{value:g}"
    return short if float(short) == value else repr(value)


def _criteria(value: object, where: str) -> tuple[Criterion, ...]:
    if not isinstance(value, list) or len(value) > MAX_CRITERIA:
        raise ConfigError(f"{where}: criteria = {value!r} — give a list of at most "
                          f"{MAX_CRITERIA} strings such as [\"accuracy >= 0.8\"]")
    return tuple(parse_criterion(c, where) for c in value)


def _value(name: str, value: object, where: str) -> float | int | str:
    check_param(name, value, PARAMETERS[name][1], where=f"{where}: ")
    if name == "size":
        try:
            size = parse_size(str(value))
        except ConfigError as exc:
            raise ConfigError(f"{where}: size = {value!r}: {exc}") from None
        if spring_count(size) > MAX_CHANNELS:  # as serve --size refuses it
            raise ConfigError(f"{where}: size = {value!r}: a {format_size(size)} skin has "
                              f"{spring_count(size)} sensors; the wire addresses at most "
                              f"{MAX_CHANNELS} — give a smaller size")
        return format_size(size)
    if name == "seed":
        return int(value)  # type: ignore[call-overload]
    return float(value)  # type: ignore[arg-type]


def _parameters(table: object, where: str) -> dict[str, tuple[float | int | str, ...]]:
    t = checked_table(table, tuple(PARAMETERS), where)
    out: dict[str, tuple[float | int | str, ...]] = {}
    for name, raw in t.items():
        values = raw if isinstance(raw, list) else [raw]
        if not 1 <= len(values) <= MAX_VALUES:
            raise ConfigError(f"{where}: {name} lists {len(values)} values — give 1.."
                              f"{MAX_VALUES}")
        out[name] = tuple(_value(name, v, where) for v in values)
        if len(set(out[name])) != len(out[name]):
            raise ConfigError(f"{where}: {name} lists a value twice — list each once (use "
                              "repetitions to run a case again)")
    return out


def _scenario(table: object, where: str, base: Path, sizes: tuple[str, ...],
              checked: set[tuple[Path, str]]) -> Scenario:
    t = checked_table(table, SCENARIO_KEYS, where)
    file, builtin = t.get("file"), t.get("builtin")
    if (file is None) == (builtin is None):
        raise ConfigError(f"{where}: give exactly one of file = \"PATH\" (a schedule or "
                          f"scenario file) or builtin = \"random\"")
    path: Path | None = None
    if builtin is not None:
        if builtin not in BUILTINS:
            raise ConfigError(f"{where}: builtin = {builtin!r} — the board has "
                              f"{', '.join(repr(b) for b in BUILTINS)}")
        default_name = str(builtin)
    else:
        if not isinstance(file, str) or not file or "\x00" in file:
            raise ConfigError(f"{where}: file = {file!r} — give the path in quotes")
        try:
            path = (base / file).resolve(strict=False)
        except (OSError, RuntimeError) as exc:  # a symlink loop
            raise ConfigError(f"{where}: file = {file!r} cannot be followed ({exc}) — give "
                              "the path of a scenario file") from None
        for size in sizes:  # the board would refuse it later: refuse it now, once a file
            if (path, size) not in checked:
                load_scenario(path, parse_size(size))
                checked.add((path, size))
        default_name = path.stem
    name = t.get("name", default_name)
    if not (isinstance(name, str) and _NAME.match(name)):
        raise ConfigError(f"{where}: name = {name!r} — give 1..{MAX_NAME_CHARS} letters, "
                          "digits or _.+-")
    return Scenario(name, path, builtin if isinstance(builtin, str) else None,
                    _criteria(t.get("criteria", []), where))


def parse_campaign(text: str, where: str, path: Path) -> Campaign:
    """The campaign of TOML ``text`` (named ``where`` in errors; relative scenario paths
    from ``path``'s folder), or a one-line :class:`ConfigError`."""
    doc = checked_table(parse_toml(text, where), TOP_KEYS, where)
    name = doc.get("name")
    if not (isinstance(name, str) and _NAME.match(name)):
        raise ConfigError(f"{where}: name = {name!r} — give the campaign a name of 1.."
                          f"{MAX_NAME_CHARS} letters, digits or _.+-")
    reps = doc.get("repetitions", 1)
    if not (isinstance(reps, int) and not isinstance(reps, bool)
            and 1 <= reps <= MAX_REPETITIONS):
        raise ConfigError(f"{where}: repetitions = {reps!r} — give a whole number 1.."
                          f"{MAX_REPETITIONS}")
    params = _parameters(doc.get("parameters", {}), f"{where}: [parameters]")
    top_seed = max((int(v) for v in params.get("seed", (DEFAULTS["seed"],))), default=1)
    if top_seed + reps - 1 > SEED_MAX:
        raise ConfigError(f"{where}: seed {top_seed} with repetitions = {reps} gives seeds up "
                          f"to {top_seed + reps - 1}, past {SEED_MAX} — give seeds at most "
                          f"{SEED_MAX - reps + 1}")
    sizes = tuple(str(v) for v in params.get("size", (format_size(PAPER_SIZE),)))
    tables = table_list(doc, "scenario", MAX_SCENARIOS, where)
    if not tables:
        raise ConfigError(f"{where} has no [[scenario]] — give at least one (builtin = "
                          "\"random\" or file = \"PATH\")")
    n_cases = len(tables) * reps * math.prod(len(v) for v in params.values())
    if n_cases > MAX_CASES:  # counted before any scenario file is read
        raise ConfigError(f"{where} makes {n_cases} cases — at most {MAX_CASES}; split the "
                          "campaign")
    checked: set[tuple[Path, str]] = set()
    scenarios = tuple(_scenario(t, f"{where}: [[scenario]] #{i + 1}", path.parent, sizes,
                                checked)
                      for i, t in enumerate(tables))
    names = [s.name for s in scenarios]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: two scenarios are named alike — give each a distinct "
                          "name = \"...\"")
    campaign = Campaign(name, path, hashlib.sha256(text.encode()).hexdigest(), scenarios,
                        params, reps, _criteria(doc.get("criteria", []), where),
                        rig_bounds_from_table(doc.get("rig", {}), f"{where}: [rig]"))
    return campaign


def load_campaign(path: str | Path) -> Campaign:
    """Read and check the campaign file ``path``; :class:`ConfigError` for anything off."""
    text, where = read_schedule_text(path, "campaign file")
    return parse_campaign(text, where, Path(path))
