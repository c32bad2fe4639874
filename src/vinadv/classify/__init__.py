"""Path pair classification: path features, the exact FP/DP rule, path images, classifiers, baselines.

Input everywhere: path pairs (`PathPairBatch`, or two `vinadv.grid.paths.PackedPaths`). Label names come from
`vinadv.vocabulary`, flips and rotations from `vinadv.grid.dihedral`.
"""

from vinadv.classify.base import MODEL_FORMAT, PairClassifier, load_model, save_model
from vinadv.classify.batch import PathPairBatch
from vinadv.classify.cooccurrence import FEATURES, cooccurrence, image_features, offset_cooccurrence
from vinadv.classify.features import PathFeatures, path_features, reaches_goal
from vinadv.classify.hybrid import (
    FP_DP_KINDS,
    HybridClassifier,
    RuleClassifier,
    make_fp_classifier,
)
from vinadv.classify.images import (
    AUGMENT_TRANSFORMS,
    augmentation_plan,
    balance_batch,
    balance_images,
    render_batch,
    render_path_images,
)
from vinadv.classify.metrics import binary_metrics
from vinadv.classify.models import CNNImageClassifier, MLPImageClassifier, SVMImageClassifier
from vinadv.classify.rule import PairLabels, default_threshold, is_fork, label_batch, label_pairs, path_distances
from vinadv.classify.similarity import (
    DistanceThresholdClassifier,
    dtw_distances,
    frechet_distances,
    hausdorff_distances,
)

__all__ = [
    "AUGMENT_TRANSFORMS",
    "CNNImageClassifier",
    "DistanceThresholdClassifier",
    "FEATURES",
    "FP_DP_KINDS",
    "HybridClassifier",
    "MLPImageClassifier",
    "MODEL_FORMAT",
    "PairClassifier",
    "PairLabels",
    "PathFeatures",
    "PathPairBatch",
    "RuleClassifier",
    "SVMImageClassifier",
    "augmentation_plan",
    "balance_batch",
    "balance_images",
    "binary_metrics",
    "cooccurrence",
    "default_threshold",
    "dtw_distances",
    "frechet_distances",
    "hausdorff_distances",
    "image_features",
    "is_fork",
    "label_batch",
    "label_pairs",
    "load_model",
    "make_fp_classifier",
    "offset_cooccurrence",
    "path_distances",
    "path_features",
    "reaches_goal",
    "render_batch",
    "render_path_images",
    "save_model",
]
