"""Path pair classification: path features, the exact FP/DP rule, path images, classifiers, baselines.

Input everywhere: path pairs (`PathPairBatch`, or two `vinadv.grid.paths.PackedPaths`). Label names come from
`vinadv.vocabulary`, flips and rotations from `vinadv.grid.dihedral`.

The names below are imported from their modules when first used, so that importing one module of the package (the
rule labeller, harm) does not load scikit-learn and PyTorch with the classifiers (`vinadv run` with the rule labeller
needs neither of them for labelling).
"""

import importlib

#: every public name of the package and the module that defines it
_EXPORTS = {
    **dict.fromkeys(("MODEL_FORMAT", "PairClassifier", "load_model", "save_model"), "base"),
    **dict.fromkeys(("PathPairBatch",), "batch"),
    **dict.fromkeys(("FEATURES", "cooccurrence", "image_features", "offset_cooccurrence"), "cooccurrence"),
    **dict.fromkeys(("PathFeatures", "path_features", "reaches_goal"), "features"),
    **dict.fromkeys(("FP_DP_KINDS", "HybridClassifier", "RuleClassifier", "make_fp_classifier"), "hybrid"),
    **dict.fromkeys(
        (
            "AUGMENT_TRANSFORMS",
            "augmentation_plan",
            "balance_batch",
            "balance_images",
            "render_batch",
            "render_path_images",
        ),
        "images",
    ),
    **dict.fromkeys(("binary_metrics",), "metrics"),
    **dict.fromkeys(("CNNImageClassifier", "MLPImageClassifier", "SVMImageClassifier"), "models"),
    **dict.fromkeys(
        ("PairLabels", "default_threshold", "is_fork", "label_batch", "label_pairs", "path_distances"), "rule"
    ),
    **dict.fromkeys(
        ("DistanceThresholdClassifier", "dtw_distances", "frechet_distances", "hausdorff_distances"), "similarity"
    ),
}
__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'vinadv.classify' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"vinadv.classify.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
