"""The paper's numbers (Wang et al., tables 4-7 and section 5.2), shown beside ours in the report."""

from __future__ import annotations

#: table 4: pairs per category out of 5,000
TABLE4 = {"UrP": 1632, "FP": 204, "DP": 1076, "UcP": 2088}
#: table 5: training time in seconds (70% of 5,000 pairs, balanced, 10 epochs for the networks)
TRAINING_S = {"svm": 46.0, "cnn": 474.0, "mlp": 105.0}
#: table 6: test accuracy (balanced training)
ACCURACY = {"svm": 0.97, "cnn": 0.76, "mlp": 0.68}
#: fig. 9: the SVM's accuracy by training set
SVM_ACCURACY = {"imbalanced": 0.91, "balanced": 0.97}
#: table 7: seconds to identify 100 pairs
PROCESSING_S = {"training": 0.22, "manual": 300.0}
#: the epochs the paper trains its CNN and MLP for
EPOCHS = 10
ENV = "Intel i7-4510U, 8 GB, Windows 10, Python 2.7"
