"""Test campaigns as hardware-in-the-loop rigs run them: a campaign file (scenarios ×
parameters × repetitions × pass criteria, :mod:`.campaign_file`) played case by case against
a decoder on any link (:mod:`.runner`, :mod:`.case_run`), each case judged by criteria on the
board's score file (:mod:`.criteria`) and by the rig's health (:mod:`.rig`), reported as a
JSON summary (:mod:`.summary_file`, resumable) and JUnit XML (:mod:`.junit_report`): the
decoder's failures apart from the rig's errors. ``skinhil bench`` is its command line."""

from skinhil.campaign.campaign_file import Campaign, Case, Scenario, load_campaign
from skinhil.campaign.case_run import BenchLink
from skinhil.campaign.criteria import Criterion, parse_criterion
from skinhil.campaign.rig import RigBounds
from skinhil.campaign.runner import JUNIT_NAME, SUMMARY_NAME, run_campaign

__all__ = ["JUNIT_NAME", "SUMMARY_NAME", "BenchLink", "Campaign", "Case", "Criterion",
           "RigBounds", "Scenario", "load_campaign", "parse_criterion", "run_campaign"]
