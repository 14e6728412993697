"""``skinhil stimuli``: the stimulus id table (the MARKERs' ``stimulus_id``) of the built-ins
and of a schedule file, as the board's SESSION and STIMULUS records carry it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import protocols
from skinhil.cli.conventions import add_json_option
from skinhil.cli.options import SCHEDULE_HELP, add_size_option, read_scenario
from skinhil.model.stimuli import PAPER_STIMULUS_ID_BASE, USER_STIMULUS_ID_BASE, Stimulus
from skinhil.model.stimulus_table import catalog, stimulus_table


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "stimuli", help="list the stimulus ids (the markers' stimulus_id) and their names",
        description="Print the stimulus table a board publishes (SESSION and STIMULUS "
                    "records, protocols/SPEC.md §3.7): each stimulus id, its name, where it "
                    "comes from and its time profile; with --schedule also the file's "
                    "stimuli and its timeline. The digest equals the SESSION record's.")
    p.add_argument("--schedule", type=Path, metavar="FILE", help=f"add the {SCHEDULE_HELP}")
    add_json_option(p)
    add_size_option(p)


def _source(sid: int) -> str:
    if sid >= USER_STIMULUS_ID_BASE:
        return "schedule file"
    if sid >= PAPER_STIMULUS_ID_BASE:
        return "paper Figure 3 A-E"
    return "Figure 4 direction condition"


def _row(sid: int, s: Stimulus) -> dict[str, Any]:
    return {"id": sid, "name": s.name, "source": _source(sid), "onset_s": s.onset_s,
            "indentation_s": s.indentation_s, "decay_tau_s": s.decay_tau_s,
            "masses": [int(m) + 1 for m in s.pushed_masses]}


def run(args: argparse.Namespace) -> int:
    scenario = read_scenario(args.schedule, args.size) if args.schedule is not None else None
    schedule = scenario.schedule if scenario is not None else None
    contacts = ([c.name for c in scenario.scene.contacts]
                if scenario is not None and scenario.scene is not None else [])
    stimuli = catalog(args.size, schedule)
    table = stimulus_table(stimuli)
    rows = [_row(sid, stimuli[sid]) for sid in sorted(stimuli)]
    timeline = [] if schedule is None else [
        {"start_s": e.start_s, "id": e.stimulus_id, "name": e.stimulus.name}
        for e in schedule.entries]
    digest = protocols.table_digest(table)
    if args.json:
        print(json.dumps({"stimuli": rows, "schedule": timeline, "n_stimuli": len(table),
                          "table_digest": digest, "contacts": contacts}))
        return 0
    print(f"{'id':>5}  {'name':<16} {'source':<29} {'indentation':>11}  masses")
    for r in rows:
        masses = ",".join(f"M{m}" for m in r["masses"])
        print(f"{r['id']:>5}  {r['name']:<16} {r['source']:<29} {r['indentation_s']:>9g} s  "
              f"{masses}")
    if timeline:
        print(f"\nschedule {args.schedule}: {len(timeline)} events")
        for e in timeline:
            print(f"{e['start_s']:>10.3f} s  id {e['id']:>5}  {e['name']}")
    if contacts:
        print(f"\nschedule {args.schedule}: {len(contacts)} contact(s), no stimulus id (the "
              f"board's contact truth, never on the link): {', '.join(contacts)}")
    print(f"\n{len(table)} stimuli; table digest 0x{digest:08X} (the SESSION record's)")
    return 0
