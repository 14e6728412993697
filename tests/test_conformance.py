"""The conformance vectors (protocols/conformance.json, SPEC.md §11): the committed file is
what tests/conformance_cases.py builds, and the reference decoder outputs exactly what each
case says (the C example's check is in tests/test_c_decoder.py)."""

from __future__ import annotations

import json

from conformance_cases import COUNTERS, conformance_json, record_json

import protocols


def test_committed_vectors_are_the_generator_output() -> None:
    assert protocols.CONFORMANCE_PATH.read_text(encoding="utf-8") == conformance_json()


def test_every_vector_decodes_as_the_file_says() -> None:
    doc = json.loads(protocols.CONFORMANCE_PATH.read_text(encoding="utf-8"))
    names = [c["name"] for c in doc["cases"]]
    assert len(names) == len(set(names)) >= 25
    moved = set()
    for case in doc["cases"]:
        dec = protocols.SerialDecoder()
        res = dec.feed(bytes.fromhex(case["input"]))
        got_events = [[int(t), int(a)] for t, a in zip(res.events["t"], res.events["addr"],
                                                       strict=True)]
        assert got_events == case["events"], case["name"]
        assert [record_json(r) for r in res.records] == case["records"], case["name"]
        got = {c: getattr(dec.counters, c) for c in COUNTERS}
        assert got == case["counters"], case["name"]
        moved |= {c for c, v in got.items() if v}
    # the damage the file covers: every counter a serial decoder keeps moves in some case
    assert moved == set(COUNTERS)
