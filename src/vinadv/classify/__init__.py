"""Path pair classification: path features, the exact FP/DP rule, path images, classifiers, baselines.

Input everywhere: path pairs (`PathPairBatch`, or two `vinadv.grid.paths.PackedPaths`). Label names come from
`vinadv.vocabulary`, flips and rotations from `vinadv.grid.dihedral`.

The names below are imported from their modules when first used, so that importing one module of the package (the
rule labeller, harm) does not load scikit-learn and PyTorch with the classifiers (`vinadv run` with the rule labeller
needs neither of them for labelling).
"""

from vinadv import lazy_names

#: the package's public names, by the module that defines them
_MODULES = {
    "base": ("MODEL_FORMAT", "PairClassifier", "load_model", "save_model"),
    "batch": ("PathPairBatch",),
    "cooccurrence": ("FEATURES", "cooccurrence", "image_features", "offset_cooccurrence"),
    "features": ("PathFeatures", "path_features", "reaches_goal"),
    "hybrid": ("FP_DP_KINDS", "HybridClassifier", "RuleClassifier", "make_fp_classifier"),
    "images": (
        "AUGMENT_TRANSFORMS",
        "augmentation_plan",
        "balance_batch",
        "balance_images",
        "render_batch",
        "render_path_images",
    ),
    "metrics": ("binary_metrics",),
    "models": ("CNNImageClassifier", "MLPImageClassifier", "SVMImageClassifier"),
    "rule": ("PairLabels", "default_threshold", "is_fork", "label_batch", "label_pairs", "path_distances"),
    "similarity": ("DistanceThresholdClassifier", "dtw_distances", "frechet_distances", "hausdorff_distances"),
}
__all__, __getattr__, __dir__ = lazy_names(__name__, _MODULES)
