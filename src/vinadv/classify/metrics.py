"""Evaluation figures of an FP/DP classifier (FP is the positive class: a successful attack)."""

from __future__ import annotations

import numpy as np
from sklearn.metrics import (
    accuracy_score,
    average_precision_score,
    confusion_matrix,
    precision_recall_fscore_support,
    roc_auc_score,
)

from vinadv.vocabulary import FORK_OR_DETOUR


def binary_metrics(y_true, y_pred, scores=None) -> dict:
    """Accuracy, per-class precision/recall/F1/support, ROC AUC and average precision, confusion matrix.

    `y_true`, `y_pred`: `(n,)` 'DP'/'FP'. `scores`: `(n,)` FP scores (higher = more FP), for ROC AUC and AP;
    those two are None without scores or when the truth holds one class only. The confusion matrix has rows
    = true class, columns = predicted class, both in the order `classes`.
    """
    y_true = np.asarray(y_true)
    y_pred = np.asarray(y_pred)
    classes = list(FORK_OR_DETOUR)
    precision, recall, f1, support = precision_recall_fscore_support(y_true, y_pred, labels=classes, zero_division=0)
    both = len(np.unique(y_true)) == 2
    result = {
        "n": int(len(y_true)),
        "accuracy": float(accuracy_score(y_true, y_pred)) if len(y_true) else None,
        "per_class": {
            c: {"precision": float(p), "recall": float(r), "f1": float(f), "support": int(s)}
            for c, p, r, f, s in zip(classes, precision, recall, f1, support)
        },
        "roc_auc": None,
        "average_precision": None,
        "classes": classes,
        "confusion_matrix": confusion_matrix(y_true, y_pred, labels=classes).tolist(),
    }
    if scores is not None and both:
        positive = y_true == "FP"
        result["roc_auc"] = float(roc_auc_score(positive, scores))
        result["average_precision"] = float(average_precision_score(positive, scores))
    return result
