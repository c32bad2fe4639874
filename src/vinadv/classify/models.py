"""Path image classifiers for FP vs DP: SVM (scikit-learn SVC), CNN and MLP (PyTorch).

Inputs are path images (`vinadv.classify.images`), rendered from a `PathPairBatch` in chunks or passed in
directly as `(n, N, N, 3)` uint8. Pixel values are scaled to 0/1.

Every classifier has a `features` parameter (`vinadv.classify.cooccurrence`): 'pixels' (the image itself, the
paper's), 'cooccurrence' (red/blue cells of one row or one column, by their two positions) or 'offsets' (the
same by their distance). The features are computed from the image (flipped/rotated first when the networks
augment), so every classifier takes path images.

SVM: fitted with `sklearn.svm.SVC` (RBF kernel) on the sparse features; predictions use the fitted
support vectors, dual coefficients and intercept directly (sparse features x dense support-vector products),
which gives SVC's decision function far faster than libsvm's per-sample loop, and is what is saved.
"""

from __future__ import annotations

import functools
import time

import numpy as np
import scipy.sparse
from sklearn.svm import SVC

from vinadv.classify.base import FP_DP_CLASSES, PairClassifier, register_kind
from vinadv.classify.batch import PathPairBatch
from vinadv.classify.cooccurrence import feature_shape, image_features, offset_matrix, torch_features
from vinadv.classify.images import render_batch
from vinadv.errors import InputError
from vinadv.grid.dihedral import transform_grids

CHUNK = 4096


def _image_chunks(X, chunk: int = CHUNK, encoding: str = "paper"):
    """Yield `(start, images (m, N, N, 3) uint8)` chunks of X (a PathPairBatch, rendered with `encoding`, or
    an image array, used as it is)."""
    if isinstance(X, PathPairBatch):
        for start in range(0, len(X), chunk):
            yield start, render_batch(X.take(np.arange(start, min(start + chunk, len(X)))), encoding)
    else:
        images = np.asarray(X)
        if images.ndim != 4 or images.shape[3] != 3 or images.shape[1] != images.shape[2]:
            raise InputError(f"path images must be (n, N, N, 3), got shape {images.shape}")
        for start in range(0, len(images), chunk):
            yield start, images[start : start + chunk]


def _image_size(X) -> int:
    return X.size if isinstance(X, PathPairBatch) else int(np.asarray(X).shape[1])


def _sparse_features(images: np.ndarray) -> scipy.sparse.csr_matrix:
    """Flattened images as a 0/1 float32 CSR matrix `(m, N * N * 3)`."""
    flat = images.reshape(len(images), -1)
    rows, cols = np.nonzero(flat)
    values = (flat[rows, cols] / 255.0).astype(np.float32)
    return scipy.sparse.csr_matrix((values, (rows, cols)), shape=flat.shape, dtype=np.float32)


def _svm_features(images: np.ndarray, features: str) -> scipy.sparse.csr_matrix:
    """The SVM's 0/1 features of images `(m, N, N, 3)` as a float32 CSR matrix `(m, F)`."""
    if features == "pixels":
        return _sparse_features(images)
    return scipy.sparse.csr_matrix(image_features(images, features))


@register_kind("svm")
class SVMImageClassifier(PairClassifier):
    """RBF-kernel SVM on path images (paper section 4.3: on the flattened pixels). `C`, `gamma` as in
    `sklearn.svm.SVC`; `encoding`: the path image encoding ('paper' or 'split', see `vinadv.classify.images`);
    `features`: 'pixels' (the paper's), 'cooccurrence' or 'offsets' (see `vinadv.classify.cooccurrence`)."""

    kind = "svm"

    def __init__(self, C: float = 1.0, gamma: str | float = "scale", encoding: str = "paper", features: str = "pixels"):
        self.C = C
        self.gamma = gamma
        self.encoding = encoding
        self.features = features

    def fit(self, X, y) -> SVMImageClassifier:
        y = self._check_y(X, y)
        start = time.perf_counter()
        feature_shape(self.features, _image_size(X))  # checks the name before any work
        chunks = _image_chunks(X, CHUNK, self.encoding)
        features = scipy.sparse.vstack([_svm_features(images, self.features) for _, images in chunks]).tocsr()
        svc = SVC(C=self.C, kernel="rbf", gamma=self.gamma, cache_size=500)
        svc.fit(features.astype(np.float64), y)
        # binary SVC: dual_coef_ and intercept_ are signed so that a positive decision means classes_[1] (FP)
        # a sparse fit gives sparse support vectors and dual coefficients
        self.support_vectors_ = np.asarray(svc.support_vectors_.toarray(), dtype=np.float32)
        dual = svc.dual_coef_
        dual = dual.toarray() if scipy.sparse.issparse(dual) else dual
        self.dual_coef_ = np.asarray(dual, dtype=np.float64).reshape(-1)
        self.intercept_ = float(svc.intercept_[0])
        self.gamma_ = float(svc._gamma)
        self.size_ = _image_size(X)
        self.training_time_s_ = time.perf_counter() - start
        self._prepare()
        return self

    def _prepare(self) -> None:
        self._sv_t = np.ascontiguousarray(self.support_vectors_.T)
        self._sv_norms = (self.support_vectors_.astype(np.float64) ** 2).sum(axis=1)

    def decision_function(self, X) -> np.ndarray:
        """SVC decision value per pair, `(n,)` float64 (positive = FP)."""
        self._check_fitted("support_vectors_")
        if _image_size(X) != self.size_:
            raise InputError(f"this SVM was trained on {self.size_}x{self.size_} maps, not {_image_size(X)}")
        out = np.empty(len(X))
        for start, images in _image_chunks(X, CHUNK, self.encoding):
            features = _svm_features(images, self.features)
            dots = np.asarray(features @ self._sv_t, dtype=np.float64)
            norms = np.asarray(features.multiply(features).sum(axis=1), dtype=np.float64)
            squared = np.maximum(norms + self._sv_norms[None, :] - 2.0 * dots, 0.0)
            out[start : start + len(images)] = np.exp(-self.gamma_ * squared) @ self.dual_coef_ + self.intercept_
        return out

    def _state(self):
        self._check_fitted("support_vectors_")
        meta = {
            "intercept": self.intercept_,
            "gamma": self.gamma_,
            "size": self.size_,
            "training_time_s": self.training_time_s_,
        }
        return meta, {"support_vectors": self.support_vectors_.astype(bool), "dual_coef": self.dual_coef_}

    @classmethod
    def _from_state(cls, kind, params, meta, arrays):
        model = cls(**params)
        model.classes_ = FP_DP_CLASSES.copy()
        vectors, dual = arrays["support_vectors"], arrays["dual_coef"]
        model.size_ = int(meta["size"])
        width = int(np.prod(feature_shape(model.features, model.size_)))
        # numbers, one coefficient per support vector of the features' width (load_model names the file)
        if (
            vectors.dtype.kind not in "biuf"
            or dual.dtype.kind not in "biuf"
            or vectors.shape[1:] != (width,)
            or dual.shape != vectors.shape[:1]
        ):
            raise ValueError(
                f"support vectors {vectors.dtype}{vectors.shape} and dual coefficients {dual.dtype}{dual.shape} "
                f"do not fit {width} features"
            )
        model.support_vectors_ = vectors.astype(np.float32)
        model.dual_coef_ = dual.astype(np.float64)
        model.intercept_ = float(meta["intercept"])
        model.gamma_ = float(meta["gamma"])
        model.training_time_s_ = float(meta.get("training_time_s", 0.0))
        model._prepare()
        return model


# --- PyTorch image classifiers ------------------------------------------------------------------------------


def _torch():
    import torch  # noqa: PLC0415 (PyTorch: only the CNN and MLP classifiers need it)

    # the machine is shared: never more than 2 threads
    if torch.get_num_threads() > 2:
        torch.set_num_threads(2)
    return torch


def _build_network(kind: str, architecture: str, size: int, width: int, features: str = "pixels"):
    """The network of `kind` and `architecture` for `size x size` maps, on inputs of `features`
    (`feature_shape`: `(3, N, N)` pixels, `(2, N, N)` co-occurrence maps, `(2, 2N - 1)` offsets)."""
    torch = _torch()
    nn = torch.nn
    shape = feature_shape(features, size)
    if kind == "cnn" and len(shape) != 3:
        raise InputError(f"a CNN needs image-shaped inputs (features 'pixels' or 'cooccurrence'), not {features!r}")
    channels = shape[0]
    if kind == "cnn" and architecture == "plain":
        # the usual small image CNN (two 3x3 convolutions, max pooling, dropout, a dense layer)
        return nn.Sequential(
            nn.Conv2d(channels, width, 3, padding=1),
            nn.ReLU(),
            nn.Conv2d(width, 2 * width, 3, padding=1),
            nn.ReLU(),
            nn.MaxPool2d(2),
            nn.Dropout(0.25),
            nn.Flatten(),
            nn.Linear(2 * width * (size // 2) ** 2, 128),
            nn.ReLU(),
            nn.Dropout(0.5),
            nn.Linear(128, 2),
        )
    if kind == "cnn" and architecture == "rowcol":
        return _RowColumnCNN(size, width, channels)
    if kind == "mlp" and architecture == "plain":
        return nn.Sequential(
            nn.Flatten(),
            nn.Linear(int(np.prod(shape)), width),
            nn.ReLU(),
            nn.Dropout(0.2),
            nn.Linear(width, width),
            nn.ReLU(),
            nn.Dropout(0.2),
            nn.Linear(width, 2),
        )
    raise InputError(f"unknown {kind} architecture {architecture!r}")


class _RowColumnCNN:  # built lazily so that importing vinadv.classify does not import torch
    def __new__(cls, size: int, width: int, channels: int = 3):
        torch = _torch()
        nn = torch.nn

        class RowColumnCNN(nn.Module):
            """The image and a few local 3x3 features, then convolutions spanning a whole row and a whole column
            (the FP/DP rule compares cells of one row or one column at any distance), global max pooling, two
            dense layers."""

            def __init__(self):
                super().__init__()
                self.local = nn.Sequential(nn.Conv2d(channels, 4, 3, padding=1), nn.ReLU())
                self.rows = nn.Conv2d(channels + 4, width, (1, 2 * size - 1), padding=(0, size - 1))
                self.cols = nn.Conv2d(channels + 4, width, (2 * size - 1, 1), padding=(size - 1, 0))
                self.head = nn.Sequential(nn.Linear(2 * width, 32), nn.ReLU(), nn.Linear(32, 2))

            def forward(self, x):
                f = torch.cat([x, self.local(x)], dim=1)
                r = torch.relu(self.rows(f)).amax(dim=(2, 3))
                c = torch.relu(self.cols(f)).amax(dim=(2, 3))
                return self.head(torch.cat([r, c], dim=1))

        return RowColumnCNN()


@functools.lru_cache(maxsize=8)
def _offset_tensor(size: int):
    """`offset_matrix(size)` as a float32 tensor (kept: built once per map size)."""
    return _torch().from_numpy(offset_matrix(size))


class TorchImageClassifier(PairClassifier):
    """A PyTorch network on path images, trained with cross-entropy.

    `architecture`: CNN 'plain' or 'rowcol', MLP 'plain'. `width`: channels (CNN) or hidden units (MLP).
    `optimizer`: 'adam' or 'adamw'; `schedule`: 'constant' or 'cosine' learning rate; `augment`: a random
    flip/rotation of the square per training batch. `encoding`: the path image encoding ('paper' or 'split').
    `features`: what the network sees of each image, computed batch by batch after augmentation: 'pixels' (the
    image, `(3, N, N)`), 'cooccurrence' (`(2, N, N)` maps) or 'offsets' (`(2, 2N - 1)`, MLP only); see
    `vinadv.classify.cooccurrence`. `seed` fixes initialisation and batch order. The parameters after
    `architecture` are keyword-only.
    """

    kind = "abstract"

    def __init__(
        self,
        architecture: str = "plain",
        *,
        width: int = 32,
        epochs: int = 10,
        batch_size: int = 64,
        learning_rate: float = 1e-3,
        weight_decay: float = 0.0,
        optimizer: str = "adam",
        schedule: str = "constant",
        augment: bool = False,
        encoding: str = "paper",
        seed: int = 0,
        verbose: bool = False,
        features: str = "pixels",
    ):
        self.architecture = architecture
        self.width = width
        self.epochs = epochs
        self.batch_size = batch_size
        self.learning_rate = learning_rate
        self.weight_decay = weight_decay
        self.optimizer = optimizer
        self.schedule = schedule
        self.augment = augment
        self.encoding = encoding
        self.seed = seed
        self.verbose = verbose
        self.features = features

    @staticmethod
    def _tensor(images: np.ndarray):
        torch = _torch()
        return torch.from_numpy(np.ascontiguousarray(images.transpose(0, 3, 1, 2))).float().div_(255.0)

    def _inputs(self, x):
        """The network's inputs of a `(B, 3, N, N)` image tensor: `torch_features` of `features`."""
        offsets = _offset_tensor(int(x.shape[-1])) if self.features == "offsets" else None
        return torch_features(x, self.features, offsets)

    def fit(self, X, y) -> TorchImageClassifier:
        y = self._check_y(X, y)
        torch = _torch()
        start = time.perf_counter()
        torch.manual_seed(self.seed)
        rng = np.random.default_rng(self.seed)
        feature_shape(self.features, _image_size(X))  # checks the name before any work
        images = np.concatenate([chunk for _, chunk in _image_chunks(X, CHUNK, self.encoding)])
        self.size_ = int(images.shape[1])
        inputs = self._tensor(images)
        targets = torch.from_numpy((y == "FP").astype(np.int64))
        self.network_ = _build_network(self.kind, self.architecture, self.size_, self.width, self.features)
        if self.optimizer == "adam":
            opt = torch.optim.Adam(self.network_.parameters(), lr=self.learning_rate, weight_decay=self.weight_decay)
        elif self.optimizer == "adamw":
            opt = torch.optim.AdamW(self.network_.parameters(), lr=self.learning_rate, weight_decay=self.weight_decay)
        else:
            raise InputError(f"unknown optimizer {self.optimizer!r} (adam, adamw)")
        steps = self.epochs * -(-len(y) // self.batch_size)
        cosine = self.schedule == "cosine"
        scheduler = torch.optim.lr_scheduler.CosineAnnealingLR(opt, max(steps, 1)) if cosine else None
        loss_fn = torch.nn.CrossEntropyLoss()
        from tqdm import tqdm  # noqa: PLC0415 (tqdm: only the PyTorch classifiers show progress)

        self.network_.train()
        for _ in tqdm(range(self.epochs), desc=f"training {self.kind}", disable=not self.verbose, unit="epoch"):
            order = torch.from_numpy(rng.permutation(len(y)))
            for batch in order.split(self.batch_size):
                xb, yb = inputs[batch], targets[batch]
                if self.augment:
                    xb = transform_grids(xb, int(rng.integers(8)), axes=(2, 3))
                opt.zero_grad()
                loss = loss_fn(self.network_(self._inputs(xb)), yb)
                loss.backward()
                opt.step()
                if scheduler is not None:
                    scheduler.step()
        self.network_.eval()
        self.training_time_s_ = time.perf_counter() - start
        return self

    def _logits(self, X) -> np.ndarray:
        self._check_fitted("network_")
        if _image_size(X) != self.size_:
            raise InputError(f"this {self.kind} was trained on {self.size_}x{self.size_} maps, not {_image_size(X)}")
        torch = _torch()
        out = np.empty((len(X), 2), dtype=np.float32)
        with torch.inference_mode():
            for start, images in _image_chunks(X, 1024, self.encoding):
                out[start : start + len(images)] = self.network_(self._inputs(self._tensor(images))).numpy()
        return out

    def decision_function(self, X) -> np.ndarray:
        """Logit difference FP - DP per pair, `(n,)` float64 (positive = FP)."""
        logits = self._logits(X).astype(np.float64)
        return logits[:, 1] - logits[:, 0]

    def predict_proba(self, X) -> np.ndarray:
        """`(n, 2)` probabilities of DP and FP (softmax of the logits)."""
        logits = self._logits(X).astype(np.float64)
        logits -= logits.max(axis=1, keepdims=True)
        e = np.exp(logits)
        return e / e.sum(axis=1, keepdims=True)

    def _state(self):
        self._check_fitted("network_")
        arrays = {f"net.{k}": v.detach().numpy().copy() for k, v in self.network_.state_dict().items()}
        return {"size": self.size_, "training_time_s": self.training_time_s_}, arrays

    @classmethod
    def _from_state(cls, kind, params, meta, arrays):
        torch = _torch()
        model = cls(**params)
        model.classes_ = FP_DP_CLASSES.copy()
        model.size_ = int(meta["size"])
        model.training_time_s_ = float(meta.get("training_time_s", 0.0))
        model.network_ = _build_network(kind, model.architecture, model.size_, model.width, model.features)
        state = {k[4:]: torch.from_numpy(np.array(v)) for k, v in arrays.items() if k.startswith("net.")}
        try:
            model.network_.load_state_dict(state)
        except RuntimeError as exc:
            raise InputError(f"model weights do not fit the {kind} architecture: {exc}") from None
        model.network_.eval()
        return model


@register_kind("cnn")
class CNNImageClassifier(TorchImageClassifier):
    """Convolutional network on path images (see `TorchImageClassifier`)."""

    kind = "cnn"


@register_kind("mlp")
class MLPImageClassifier(TorchImageClassifier):
    """Multilayer perceptron on flattened path images or their features (see `TorchImageClassifier`)."""

    kind = "mlp"

    # The same parameters with a wider default: scikit-learn reads the parameters and their defaults from
    # `__init__`'s signature, which `partialmethod` keeps (with `width` 512).
    __init__ = functools.partialmethod(TorchImageClassifier.__init__, width=512)
