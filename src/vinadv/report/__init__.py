"""The evaluation report (every table and figure of the paper, regenerated from a stored run) and the classifier
comparison behind it (`vinadv evaluate`)."""

from vinadv.report.evaluate import CLASSIFIERS, evaluate_run
from vinadv.report.html import write_report

__all__ = ["CLASSIFIERS", "evaluate_run", "write_report"]
