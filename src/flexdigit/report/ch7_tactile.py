"""Report chapter 7: tactile sensing of the actuated digit (table 7.1 on the twin; builder shared with chapter 6)."""

from __future__ import annotations

from flexdigit.report.ch6_tactile import build_tactile
from flexdigit.report.chapter import Chapter, ReportContext


def build(ctx: ReportContext) -> Chapter:
    return build_tactile(ctx, "actuated")
