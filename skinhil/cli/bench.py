"""``skinhil bench CAMPAIGN``: play a test campaign against a decoder under test and report
each case as passed, failed (the decoder's) or error (the rig's) in a JSON summary and JUnit
XML (docs: Test campaigns). ``skinhil bench --suite SUITE``: play every case of a task suite
at seeds drawn at run time and write a report card (docs: Suites, "Scoring your decoder on
the suite")."""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path
from typing import Any

from skinhil.cli import signals
from skinhil.cli.conventions import MODEL_HELP, add_json_option, print_json
from skinhil.cli.transport_args import (
    add_transport_args,
    check_transport_args,
    describe_transport,
    serial_baud,
    transport_argv,
)
from skinhil.cli.values import integer, real
from skinhil.errors import ConfigError
from skinhil.output_files import check_output_folder
from skinhil.transports.faults import FaultParams

DEFAULT_SEEDS = 3
"""Seeds per case ``bench --suite`` draws unless ``--seeds`` says."""
MAX_SEEDS = 1000
FAULT_KEYS = ("drop_p", "corrupt_byte_p", "duplicate_p", "delay_p", "delay_s", "seed")
"""What ``--faults`` sets (:class:`~skinhil.transports.faults.FaultParams`)."""


def faults_value(text: str) -> FaultParams:
    """argparse type of ``--faults``: ``KEY=VALUE[,KEY=VALUE...]`` of :data:`FAULT_KEYS`."""
    values: dict[str, Any] = {}
    for item in text.split(","):
        key, _, raw = item.partition("=")
        key = key.strip()
        if key not in FAULT_KEYS or not raw:
            raise argparse.ArgumentTypeError(
                f"{item!r}: give KEY=VALUE pairs, KEY one of {', '.join(FAULT_KEYS)} "
                "(e.g. drop_p=0.01,corrupt_byte_p=1e-4)")
        try:
            values[key] = int(raw) if key == "seed" else float(raw)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{item!r}: {raw!r} is not a number") from None
    try:
        return FaultParams(**values)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


class _Once(argparse.Action):
    """Store an option's value, refusing the option a second time (one would be lost)."""

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        if getattr(namespace, self.dest, None) is not None:
            raise argparse.ArgumentError(self, "given twice — give it once, with every "
                                               "KEY=VALUE in it")
        setattr(namespace, self.dest, values)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "bench", help="play a test campaign against a decoder: JSON summary and JUnit XML",
        description="Play each case of a campaign file (scenarios x parameters x "
                    "repetitions, docs: Test campaigns) on a board started for it, against "
                    "the decoder under test on the link given, or, with no link, against "
                    "the reference receiver (skinhil listen --answer) on a pty pair of the "
                    "bench's own. Each case passes, fails (a criterion on the board's score "
                    "does not hold: the decoder's failure) or is an error (a fault of the "
                    "rig: late ticks, dropped events, link loss or damage, a process "
                    "crashing, a timeout). Writes OUT/summary.json and OUT/junit.xml after "
                    "every case. Exit status 0 when every case passed, 1 otherwise.")
    p.add_argument("campaign", type=Path, metavar="CAMPAIGN", nargs="?",
                   help="the campaign file (TOML); or --suite instead")
    suite = p.add_argument_group(
        "a task suite instead of a campaign (docs/suites.md): every case at seeds drawn from "
        "the suite's evaluation range; writes OUT/report-card.json and .md beside the "
        "summary and JUnit XML")
    suite.add_argument("--suite", metavar="SUITE",
                       help="the suite to play, e.g. tactile-v1 (skinhil suites lists them)")
    suite.add_argument("--seeds", type=integer(1, MAX_SEEDS, "count"), default=DEFAULT_SEEDS,
                       metavar="K", help=f"seeds per case (default {DEFAULT_SEEDS})")
    suite.add_argument("--seed", type=integer(0, 2**63 - 1, "seed"), metavar="N",
                       help="draw the seeds with this seed (the card records it; default: "
                            "drawn now)")
    suite.add_argument("--case", dest="cases", action="append", metavar="NAME",
                       help="play only this case (repeatable; default: every case)")
    suite.add_argument("--max-lateness-ms", type=real(0, 3.6e6, "ms", lo_open=True),
                       metavar="MS",
                       help="a tick later than this is the rig's error (default: a "
                            "campaign's [rig] max_lateness_ms default, docs/campaigns.md)")
    suite.add_argument("--baselines", action="store_true",
                       help="also play the reference, random and oracle answerers (listen "
                            "--answer --answer-with ...; the grasp's reference controller) "
                            "at the same seeds on the bench's own link, beside the decoder "
                            "on the card")
    add_transport_args(p, required=False,
                       title="link to the decoder under test (default: the reference "
                             "receiver on the bench's own pty pair)")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="folder of the summary, the JUnit XML and each case's files "
                        "(default: bench-NAME, NAME the campaign's)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run whose summary is in --out: cases already played "
                        "are not played again")
    p.add_argument("--model", type=Path, metavar="NPZ", help=MODEL_HELP)
    add_json_option(p)
    p.add_argument("--faults", type=faults_value, metavar="KEY=VALUE[,...]", action=_Once,
                   help="damage the bench's own link on purpose, to check the rig reports "
                        f"it: {', '.join(FAULT_KEYS)} (skinhil.transports.faults)")


def _model(args: argparse.Namespace, sizes: tuple[str, ...]) -> Path:
    """The reference receiver's model, checked for every skin size of the campaign (a file
    the receiver would refuse is refused here, once, not as every case's error)."""
    from skinhil.model.geometry import parse_size, spring_count
    from skinhil.receiver.model_file import load_window_decoder

    if args.model is None:
        from skinhil.cli.demo_cache import demo_decoder

        path = demo_decoder(None, args.quiet, serial_baud(args))
    else:
        path = args.model
    for size in sizes:
        load_window_decoder(path, n_channels=spring_count(parse_size(size)))
    return path


def _grip_readout(args: argparse.Namespace) -> Path:
    """The reference grip controller's load readout (the grasp demo's, fitted and cached on
    first use)."""
    from skinhil.cli.demo_grasp import cached_readout
    from skinhil.cli.options import DECODE_SNR_DB

    return cached_readout(DECODE_SNR_DB, serial_baud(args), 1)


def run_suite_bench(args: argparse.Namespace) -> int:
    """``bench --suite``: the suite's cases at drawn seeds, the baselines, the card."""
    import secrets

    from tqdm.auto import tqdm

    from skinhil.campaign import JUNIT_NAME, SUMMARY_NAME, BenchLink, RigBounds
    from skinhil.campaign.report_card import build_card, write_card
    from skinhil.campaign.suite_run import draw_seeds, run_suite, suite_campaign
    from skinhil.suites import suite as find_suite

    check_transport_args(args)
    if args.resume:
        raise ConfigError("--resume continues a campaign: a suite run draws its seeds anew — "
                          "give --seed N to play the same seeds again")
    the_suite = find_suite(args.suite)
    draw = args.seed if args.seed is not None else secrets.randbelow(2**63)
    seeds = draw_seeds(the_suite, draw, args.seeds)
    rig = RigBounds() if args.max_lateness_ms is None else \
        RigBounds(max_lateness_ms=args.max_lateness_ms)
    campaign = suite_campaign(the_suite, seeds, tuple(args.cases or ()), rig=rig)
    link_args = transport_argv(args)
    if link_args and args.faults is not None:
        raise ConfigError("--faults damages the bench's own link: drop it, or drop the link "
                          "option")
    out = args.out if args.out is not None else Path(f"bench-{the_suite.id}-{draw}")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out '{out}' is not a folder — give a folder")
    if (out / SUMMARY_NAME).exists():
        raise ConfigError(f"'{out / SUMMARY_NAME}' holds an earlier run — give another --out")
    check_output_folder(out, "--out")  # before a model is trained
    own = not link_args
    model = _model(args, ("6x6",)) if own or args.baselines else None
    holds = any(c.holds_object for c in campaign.cases())
    readout = _grip_readout(args) if holds and (own or args.baselines) else None
    base = BenchLink(model=model, baud=serial_baud(args), faults=args.faults,
                     grip_readout=readout)
    if link_args:
        link = BenchLink(link_args=tuple(link_args))
        link_text = describe_transport(args)
    else:
        link = base
        link_text = (f"bench pty pair @ {serial_baud(args)} baud, reference receiver (listen "
                     f"--answer, model {model})")
    n_cases = len(campaign.cases()) * (1 + (3 if args.baselines else 0))
    bar = tqdm(total=n_cases, desc=the_suite.id, unit="case", disable=args.quiet,
               file=sys.stderr)

    def on_case(who: str, record: dict[str, Any] | None) -> None:
        bar.update()
        if record is not None and record["outcome"] != "passed" and not (args.quiet or args.json):
            bar.write(f"{record['outcome'].upper():6} {who} {record['id']}: "
                      f"{record['message']}")

    if not args.quiet and not args.json:
        print(f"bench {the_suite.id}: seeds {', '.join(map(str, seeds))} (--seed {draw})",
              flush=True)
    try:
        with signals.stop_event(lambda: "stopping: the case under way is ended and not "
                                        "recorded") as stop:
            result = run_suite(campaign, out, link, link_text, stop,
                               base if args.baselines else None, on_case)
    finally:
        bar.close()
    card = build_card(the_suite, result, draw, seeds, link_text)
    js, md = write_card(out, card)
    t = result.decoder["totals"]
    if args.json:
        print_json({"suite": the_suite.id, "seeds": list(seeds), "totals": dict(t),
                    "complete": card["complete"], "card": str(js), "card_markdown": str(md),
                    "junit": str(out / JUNIT_NAME)})
        return 0 if card["complete"] and t["passed"] == t["cases"] else 1
    if not args.quiet:
        print(md.read_text(encoding="utf-8"), end="", flush=True)
    print(f"bench {the_suite.id}: {t['played']} of {t['cases']} cases played: {t['passed']} "
          f"passed, {t['failed']} failed (decoder), {t['errors']} errors (rig); {js}, {md}, "
          f"{out / JUNIT_NAME}", flush=True)
    return 0 if card["complete"] and t["passed"] == t["cases"] else 1


def run(args: argparse.Namespace) -> int:
    if (args.campaign is None) == (args.suite is None):
        raise ConfigError("give a campaign file or --suite SUITE (e.g. --suite tactile-v1), "
                          "not both")
    if args.suite is not None:
        return run_suite_bench(args)
    given = [opt for opt, v in (
        ("--seeds", args.seeds != DEFAULT_SEEDS), ("--seed", args.seed is not None),
        ("--case", args.cases), ("--baselines", args.baselines),
        ("--max-lateness-ms", args.max_lateness_ms is not None)) if v]
    if given:
        raise ConfigError(f"{', '.join(given)} go with --suite: drop them, or play a suite")
    return run_campaign_file(args)


def run_campaign_file(args: argparse.Namespace) -> int:
    from tqdm.auto import tqdm

    from skinhil.campaign import (
        JUNIT_NAME,
        SUMMARY_NAME,
        BenchLink,
        load_campaign,
        run_campaign,
    )
    from skinhil.campaign.summary_file import load_summary

    check_transport_args(args)
    campaign = load_campaign(args.campaign)
    link_args = transport_argv(args)
    if link_args and (args.model is not None or args.faults is not None):
        raise ConfigError("--model and --faults are for the bench's own link and reference "
                          "receiver: drop them, or drop the link option")
    out = args.out if args.out is not None else Path(f"bench-{campaign.name}")
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out '{out}' is not a folder — give a folder")
    if not args.resume and (out / SUMMARY_NAME).exists():
        raise ConfigError(f"'{out / SUMMARY_NAME}' holds an earlier run — add --resume to "
                          "continue it, or give another --out")
    if args.resume:  # a summary that cannot be resumed is refused before any model loads
        load_summary(out / SUMMARY_NAME, campaign)
    check_output_folder(out, "--out")  # before a model is trained
    if link_args:
        link = BenchLink(link_args=tuple(link_args))
        link_text = describe_transport(args)
    else:
        model = _model(args, tuple(str(v) for v in campaign.parameters.get("size", ("6x6",))))
        link = BenchLink(model=model, baud=serial_baud(args), faults=args.faults)
        link_text = (f"bench pty pair @ {serial_baud(args)} baud, reference receiver (listen "
                     f"--answer, model {model})"
                     + ("" if args.faults is None else
                        f", faults {dataclasses.asdict(args.faults)}"))
    try:  # every input checked: the folder is made now, or refused in one line
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"--out '{out}' cannot be created: {exc.strerror or exc} — give "
                          "a folder you can write") from None
    if not os.access(out, os.W_OK | os.X_OK):
        raise ConfigError(f"--out '{out}' is not writable — give a folder you can write")
    n_cases = len(campaign.cases())
    bar = tqdm(total=n_cases, desc=campaign.name, unit="case", disable=args.quiet,
               file=sys.stderr)
    counts = {"passed": 0, "failed": 0, "error": 0, "skipped": 0}

    def on_case(record: dict[str, Any] | None) -> None:
        counts["skipped" if record is None else record["outcome"]] += 1
        bar.set_postfix(passed=counts["passed"], failed=counts["failed"],
                        errors=counts["error"], refresh=False)
        bar.update()
        if record is not None and record["outcome"] != "passed" and not (args.quiet or args.json):
            bar.write(f"{record['outcome'].upper():6} {record['id']}: {record['message']}")

    try:
        with signals.stop_event(lambda: "stopping: the case under way is ended and not "
                                        "recorded; --resume plays it later") as stop:
            summary = run_campaign(campaign, out, link, link_text, stop, args.resume, on_case)
    finally:
        bar.close()
    t = summary["totals"]
    if args.json:
        print_json({"campaign": campaign.name, "totals": dict(t),
                    "skipped_earlier": counts["skipped"], "complete": summary["complete"],
                    "summary": str(out / SUMMARY_NAME), "junit": str(out / JUNIT_NAME)})
        return 0 if summary["complete"] and t["passed"] == t["cases"] else 1
    earlier = f" ({counts['skipped']} in the earlier run)" if counts["skipped"] else ""
    print(f"bench {campaign.name}: {t['played']} of {t['cases']} cases played{earlier}"
          f": {t['passed']} passed, {t['failed']} failed (decoder), {t['errors']} errors "
          f"(rig); {out / SUMMARY_NAME}, {out / JUNIT_NAME}"
          f"{'' if summary['complete'] else '; incomplete: --resume continues it'}",
          flush=True)
    return 0 if summary["complete"] and t["passed"] == t["cases"] else 1
