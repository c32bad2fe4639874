"""The evaluation report: every table and figure of the paper, regenerated from a stored run and what the
evaluation stage (`vinadv.evaluation`, `vinadv evaluate`) stored of it. The report reads; it computes no evaluation."""

from vinadv.report.build import build_report, write_report

__all__ = ["build_report", "write_report"]
