"""``skinhil bench CAMPAIGN``: play a test campaign against a decoder under test and report
each case as passed, failed (the decoder's) or error (the rig's) in a JSON summary and JUnit
XML (docs: Test campaigns)."""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
from pathlib import Path
from typing import Any

from skinhil.cli import signals
from skinhil.cli.transport_args import (
    add_transport_args,
    check_transport_args,
    describe_transport,
    serial_baud,
    transport_argv,
)
from skinhil.errors import ConfigError
from skinhil.transports.faults import FaultParams

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
    p.add_argument("campaign", type=Path, metavar="CAMPAIGN", help="the campaign file (TOML)")
    add_transport_args(p, required=False,
                       title="link to the decoder under test (default: the reference "
                             "receiver on the bench's own pty pair)")
    p.add_argument("--out", type=Path, metavar="DIR",
                   help="folder of the summary, the JUnit XML and each case's files "
                        "(default: bench-NAME, NAME the campaign's)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run whose summary is in --out: cases already played "
                        "are not played again")
    p.add_argument("--model", type=Path, metavar="NPZ",
                   help="the reference receiver's model (default: the demo's, trained and "
                        "cached on first use)")
    p.add_argument("--faults", type=faults_value, metavar="KEY=VALUE[,...]", action=_Once,
                   help="damage the bench's own link on purpose, to check the rig reports "
                        f"it: {', '.join(FAULT_KEYS)} (skinhil.transports.faults)")
    p.add_argument("--quiet", action="store_true", help="no progress bar, only the totals")


def _model(args: argparse.Namespace, sizes: tuple[str, ...]) -> Path:
    """The reference receiver's model, checked for every skin size of the campaign (a file
    the receiver would refuse is refused here, once, not as every case's error)."""
    from skinhil.model.geometry import parse_size, spring_count
    from skinhil.receiver.model_file import load_window_decoder

    if args.model is None:
        from skinhil.cli.demo import cached_model
        from skinhil.cli.options import DECODE_SNR_DB

        path = cached_model(DECODE_SNR_DB, args.quiet, serial_baud(args), 1)
    else:
        path = args.model
    for size in sizes:
        load_window_decoder(path, n_channels=spring_count(parse_size(size)))
    return path


def run(args: argparse.Namespace) -> int:
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
        if record is not None and record["outcome"] != "passed" and not args.quiet:
            bar.write(f"{record['outcome'].upper():6} {record['id']}: {record['message']}")

    try:
        with signals.stop_event(lambda: "stopping: the case under way is ended and not "
                                        "recorded; --resume plays it later") as stop:
            summary = run_campaign(campaign, out, link, link_text, stop, args.resume, on_case)
    finally:
        bar.close()
    t = summary["totals"]
    earlier = f" ({counts['skipped']} in the earlier run)" if counts["skipped"] else ""
    print(f"bench {campaign.name}: {t['played']} of {t['cases']} cases played{earlier}"
          f": {t['passed']} passed, {t['failed']} failed (decoder), {t['errors']} errors "
          f"(rig); {out / SUMMARY_NAME}, {out / JUNIT_NAME}"
          f"{'' if summary['complete'] else '; incomplete: --resume continues it'}",
          flush=True)
    return 0 if summary["complete"] and t["passed"] == t["cases"] else 1
