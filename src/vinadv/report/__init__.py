"""The evaluation report (every table and figure of the paper, regenerated from a stored run) and the classifier
comparison behind it (`vinadv evaluate`)."""

from vinadv.report.build import build_report, report_run, write_report
from vinadv.report.evaluate import CLASSIFIERS, evaluate_run

__all__ = ["CLASSIFIERS", "build_report", "evaluate_run", "report_run", "write_report"]
