"""JSON Schemas (draft 2020-12) of every file skinhil writes or reads as JSON or TOML, and
their validation.

Each ``NAME.schema.json`` in this package describes one format; its fields carry
descriptions with units, and the field reference (``docs/reference/files.md``) is rendered
from them by ``python -m skinhil.schemas.render``. A TOML file is validated as the document
``tomllib`` parses it into. Where a format is closed (``additionalProperties: false``) a
renamed or unknown key is refused; where it is open the schema says so in its description.

- :func:`names` — the schemas shipped;
- :func:`schema` — one schema as a dict;
- :func:`validate` — a document against one schema: :class:`~skinhil.errors.ConfigError` in
  one line naming the place in the document and what to give.

Schemas refer to each other by their ``$id`` (``urn:skinhil:schema:NAME``).
"""

from __future__ import annotations

import functools
import itertools
import json
import re
from importlib import resources
from typing import Any

from skinhil.errors import ConfigError

ID_PREFIX = "urn:skinhil:schema:"
"""The ``$id`` of schema NAME is this prefix and NAME."""
SUFFIX = ".schema.json"
MAX_SHOWN_CHARS = 80
"""Longest value quoted in an error line."""
MAX_ERRORS = 100
"""Errors looked at to choose the one reported (a hostile document may hold millions)."""
_UNKNOWN_KEYS = ("additionalProperties", "unevaluatedProperties")
_NO_VALUE = ("required", "additionalProperties", "unevaluatedProperties", "anyOf", "oneOf")
"""Failing keywords whose message does not quote the value (an object, named by its path)."""


def names() -> list[str]:
    """The names of the shipped schemas (``score``, ``campaign-summary``, ...), sorted."""
    files = resources.files(__package__)
    return sorted(f.name[:-len(SUFFIX)] for f in files.iterdir() if f.name.endswith(SUFFIX))


@functools.cache
def _load(name: str) -> str:
    if name not in names():
        raise ConfigError(f"no schema named {name!r} — give one of {', '.join(names())}")
    return (resources.files(__package__) / f"{name}{SUFFIX}").read_text(encoding="utf-8")


def schema(name: str) -> dict[str, Any]:
    """The schema ``name`` (a fresh dict: changing it changes nothing here)."""
    out: dict[str, Any] = json.loads(_load(name))
    return out


@functools.cache
def _validator(name: str) -> Any:
    from jsonschema import Draft202012Validator
    from referencing import Registry, Resource

    base, _, pointer = name.partition("#")
    registry: Registry[Any] = Registry().with_resources(
        (ID_PREFIX + n, Resource.from_contents(schema(n))) for n in names())
    root = schema(base)
    if pointer:  # a part of a document: a schema that refers to it
        root = {"$schema": root["$schema"], "$ref": f"{ID_PREFIX}{base}#{pointer}"}
    return Draft202012Validator(root, registry=registry)


def _short(value: object) -> str:
    text = json.dumps(value, default=str) if not isinstance(value, str) else repr(value)
    return text if len(text) <= MAX_SHOWN_CHARS else text[:MAX_SHOWN_CHARS - 3] + "..."


def _give(error: Any) -> str:
    """What to give instead, from the failing keyword of the schema."""
    kind, want, s = error.validator, error.validator_value, error.schema
    if kind == "type":
        return f"a value of type {' or '.join(want) if isinstance(want, list) else want}"
    if kind == "enum":
        return f"one of {', '.join(_short(v) for v in want)}"
    if kind == "const":
        return _short(want)
    if kind == "required":
        missing = [k for k in want if isinstance(error.instance, dict) and k not in error.instance]
        return f"the key(s) {', '.join(missing)}"
    if kind in ("additionalProperties", "unevaluatedProperties"):
        return "only the keys the format defines (docs/reference/files.md)"
    if kind in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        lo, hi = s.get("minimum", s.get("exclusiveMinimum")), s.get("maximum",
                                                                     s.get("exclusiveMaximum"))
        return f"a number in [{'-inf' if lo is None else lo}, {'inf' if hi is None else hi}]"
    if kind in ("minItems", "maxItems"):
        return f"a list of {s.get('minItems', 0)}..{s.get('maxItems', 'any number of')} items"
    if kind in ("minLength", "maxLength", "pattern"):
        return f"a string matching {s.get('pattern', 'the length bounds')}"
    description = s.get("description")
    return f"{description.split('.')[0]}" if isinstance(description, str) else \
        f"what the schema {_short(want)} takes"


def validate(name: str, document: object, where: str | None = None) -> None:
    """Check ``document`` (parsed JSON, or TOML as ``tomllib`` gives it) against schema
    ``name`` (or a part of one: ``score#/$defs/grasp``, the score file's ``grasp``);
    :class:`ConfigError` with one line naming the place in the document (a JSON path such as
    ``$.cases[0].outcome``) and what to give. ``where`` names the document in the message
    (default: the schema's name)."""
    from jsonschema.exceptions import best_match

    try:
        errors = list(itertools.islice(_validator(name).iter_errors(document), MAX_ERRORS))
        error = best_match(errors)
    except RecursionError:
        raise ConfigError(f"{where or name}: nested too deeply to be a {name} document — "
                          "give the file skinhil wrote") from None
    if error is None:
        return
    got = "" if error.validator in _NO_VALUE else f" = {_short(error.instance)}"
    extra = ""
    if error.validator in _UNKNOWN_KEYS:
        unknown = re.findall(r"'([^']*)'", error.message.split("(")[-1])
        extra = f" has unknown key(s) {', '.join(repr(k) for k in unknown[:5])}"
    elif error.validator == "required":
        extra = " lacks a key"
        for other in errors:  # a renamed key: say the name it has too
            if other.json_path == error.json_path and other.validator in _UNKNOWN_KEYS:
                unknown = re.findall(r"'([^']*)'", other.message.split("(")[-1])
                extra += f" and has unknown key(s) {', '.join(repr(k) for k in unknown[:5])}"
    raise ConfigError(f"{where or name}: {error.json_path}{got}{extra} — give {_give(error)}"
                      f" (schema {name})")
