"""`auv report CAMPAIGN_DIR [--against OTHER_DIR] [--out FILE]`: a campaign's HTML page (`mission.campaign_report`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any


def _report(args: argparse.Namespace) -> int:
    from mission.campaign_report import load_campaign, render
    from mission.extras import require

    require("matplotlib", "the campaign report's figures (`auv report`)")
    campaign = load_campaign(Path(args.campaign))
    against = load_campaign(Path(args.against)) if args.against else None
    out = render(campaign, against, Path(args.out) if args.out else Path(args.campaign) / "report.html")
    print(f"report: {out}")
    return 0


def add_report_command(sub: Any) -> None:
    p = sub.add_parser("report", help="an HTML report of a campaign of seeded runs (`auv simulate --seeds`)")
    p.add_argument("campaign", help="campaign folder (with campaign.json)")
    p.add_argument("--against", metavar="OTHER_DIR", help="a second campaign to compare with")
    p.add_argument("--out", help="the page (default CAMPAIGN_DIR/report.html)")
    p.set_defaults(func=_report)
