"""A light MLP autoencoder that compresses text-space appearance features ``[D]`` to ``[d]`` and back.

Per-Gaussian language features are rendered like colours, so their width is paid per Gaussian and
per pixel; LangSplat therefore fits 3-d latents of a scene-specific autoencoder (512 -> 3 -> 512)
and 4D LangSplat a few more. Here the default is ``d = 8``. A scene has only ~10-20 distinct looks,
and any ``d >= 3`` keeps them apart (reconstruction cosine >= 0.9996, the decoded latent's nearest
object always itself or a look-alike); what ``d`` buys is the vocabulary: the autoencoder is also
trained on ~240 caption-style phrases ("a red SUV", "a pedestrian in blue trousers") so that latents
between and around the scene's objects decode to sensible text. The share of phrases still nearest
to themselves after the round trip is 0.40 / 0.77 / 0.994 / 0.999 / 1.0 for d = 3 / 4 / 6 / 8 / 16
(E5 caption features of world seeds 0-2, ``bench/bench_appearance.py``): 8 channels is the
smallest width that keeps "a red SUV" apart from "a red sedan" essentially always.

Features are L2-normalised text embeddings. The autoencoder works on their offset from the
training mean: E5 vectors share a large common component (caption cosines are 0.77-0.95) that
would otherwise dominate the loss; centring raises the vocabulary self-match from 0.94 to 0.999 at
d = 8. ``decode`` adds the mean back and renormalises. Loss: ``l2_weight * |y - x|^2 + cos_weight *
(1 - cos(y, x))``, averaged with per-row weights that give the scene's own features
``scene_weight`` of the total (the vocabulary the rest).

Training is full-batch Adam, deterministic for a given seed (the initialisation is drawn inside a
forked torch RNG, so the global RNG is untouched). The trained model is an ``AutoencoderState``
of plain numpy arrays (``to_arrays`` / ``from_arrays`` for any array store).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
import torch
from torch import nn

from simsplat_core.compute_threads import compute_threads_limited

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class AutoencoderConfig:
    """Architecture and training of ``FeatureAutoencoder``.

    Attributes:
        latent_dim: ``d``.
        hidden: hidden widths of the encoder (the decoder mirrors them).
        steps: full-batch Adam steps.
        lr: learning rate.
        l2_weight, cos_weight: weights of the squared-error and the cosine term.
        scene_weight: share of the loss carried by the scene's features (vs. the vocabulary).
        center: subtract the training mean before encoding.
        seed: initialisation seed.
        threads: torch intra-op threads during ``fit`` (the previous setting is restored); the
            model is too small to gain from more, and on a busy machine extra threads slow it down
            many times over. ``None`` leaves torch's setting alone.
    """

    latent_dim: int = 8
    hidden: tuple[int, ...] = (256, 128, 64)
    steps: int = 1000
    lr: float = 3e-3
    l2_weight: float = 1.0
    cos_weight: float = 1.0
    scene_weight: float = 0.5
    center: bool = True
    seed: int = 0
    threads: int | None = 1


@dataclass(frozen=True, eq=False)
class AutoencoderState:
    """A trained autoencoder as plain arrays.

    Attributes:
        input_dim: ``D``.
        latent_dim: ``d``.
        hidden: encoder hidden widths.
        mean: ``[D]`` float32 offset subtracted before encoding (zeros when not centred).
        encoder: ``(W0, b0, W1, b1, ...)`` float32, ``W`` as ``[out, in]`` (torch ``nn.Linear`` layout).
        decoder: same for the decoder.
        text_space: name of the text encoder whose space the features live in (informational).
    """

    input_dim: int
    latent_dim: int
    hidden: tuple[int, ...]
    mean: np.ndarray
    encoder: tuple[np.ndarray, ...]
    decoder: tuple[np.ndarray, ...]
    text_space: str = ""

    def to_arrays(self) -> dict[str, np.ndarray]:
        """Flat ``name -> array`` dict (e.g. for ``np.savez``); ``from_arrays`` inverts it."""
        out = {
            "dims": np.array([self.input_dim, self.latent_dim, *self.hidden], dtype=np.int64),
            "mean": self.mean,
            "text_space": np.array(self.text_space),
        }
        out.update({f"enc_{i}": a for i, a in enumerate(self.encoder)})
        out.update({f"dec_{i}": a for i, a in enumerate(self.decoder)})
        return out

    @staticmethod
    def from_arrays(arrays: dict[str, np.ndarray]) -> AutoencoderState:
        dims = [int(v) for v in np.asarray(arrays["dims"])]
        n = 2 * (len(dims) - 1)
        return AutoencoderState(
            input_dim=dims[0],
            latent_dim=dims[1],
            hidden=tuple(dims[2:]),
            mean=np.asarray(arrays["mean"], dtype=np.float32),
            encoder=tuple(np.asarray(arrays[f"enc_{i}"], dtype=np.float32) for i in range(n)),
            decoder=tuple(np.asarray(arrays[f"dec_{i}"], dtype=np.float32) for i in range(n)),
            text_space=str(np.asarray(arrays.get("text_space", ""))),
        )


@dataclass(frozen=True)
class TrainReport:
    """Loss curve of a fit: ``losses[k]`` is the weighted loss before step ``k * every``."""

    losses: tuple[float, ...]
    every: int
    final_loss: float
    steps: int = 0


def _mlp(widths: list[int]) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i in range(len(widths) - 1):
        layers.append(nn.Linear(widths[i], widths[i + 1]))
        if i < len(widths) - 2:
            layers.append(nn.GELU())
    return nn.Sequential(*layers)


def _linear_arrays(module: nn.Sequential) -> tuple[np.ndarray, ...]:
    out: list[np.ndarray] = []
    for layer in module:
        if isinstance(layer, nn.Linear):
            out += [layer.weight.detach().cpu().numpy().copy(), layer.bias.detach().cpu().numpy().copy()]
    return tuple(out)


def _load_linear(module: nn.Sequential, arrays: tuple[np.ndarray, ...]) -> None:
    linears = [layer for layer in module if isinstance(layer, nn.Linear)]
    if 2 * len(linears) != len(arrays):
        raise ValueError(f"expected {2 * len(linears)} arrays, got {len(arrays)}")
    with torch.no_grad():
        for layer, (w, b) in zip(linears, zip(arrays[::2], arrays[1::2])):
            if tuple(w.shape) != tuple(layer.weight.shape) or tuple(b.shape) != tuple(layer.bias.shape):
                raise ValueError(f"weight shape {w.shape} does not fit layer {tuple(layer.weight.shape)}")
            layer.weight.copy_(torch.from_numpy(np.asarray(w, dtype=np.float32)))
            layer.bias.copy_(torch.from_numpy(np.asarray(b, dtype=np.float32)))


def _as_rows(x: np.ndarray, width: int, what: str) -> np.ndarray:
    x = np.asarray(x, dtype=np.float32)
    if x.ndim != 2 or x.shape[1] != width:
        raise ValueError(f"{what}: expected [N, {width}], got {x.shape}")
    return x


class FeatureAutoencoder:
    """``encode: [N, D] -> [N, d]`` and ``decode: [N, d] -> [N, D]`` (unit rows).

    Build one with ``FeatureAutoencoder.fit(features, ...)`` or ``FeatureAutoencoder(state)``. The
    torch modules (``encoder``, ``decoder``) are exposed for differentiable use; ``decode_torch``
    maps latents back to unit text-space features inside a graph.
    """

    def __init__(self, state: AutoencoderState) -> None:
        widths = [state.input_dim, *state.hidden, state.latent_dim]
        self.encoder = _mlp(widths)
        self.decoder = _mlp(widths[::-1])
        _load_linear(self.encoder, state.encoder)
        _load_linear(self.decoder, state.decoder)
        self.encoder.eval()
        self.decoder.eval()
        self.mean = torch.from_numpy(np.asarray(state.mean, dtype=np.float32).copy())
        self.input_dim, self.latent_dim, self.hidden = state.input_dim, state.latent_dim, tuple(state.hidden)
        self.text_space = state.text_space

    # ------------------------------------------------------------------ training
    @staticmethod
    def fit(
        features: np.ndarray,
        vocabulary: np.ndarray | None = None,
        config: AutoencoderConfig = AutoencoderConfig(),
        text_space: str = "",
    ) -> tuple[FeatureAutoencoder, TrainReport]:
        """Train on a scene's features (and optionally vocabulary embeddings).

        Args:
            features: ``[N, D]`` unit rows, the scene's per-object appearance features.
            vocabulary: ``[V, D]`` unit rows of phrases queries may resemble, or ``None``.
            config: architecture and optimisation.
            text_space: name of the text encoder (stored in the state).
        Returns:
            the trained autoencoder and its loss curve.
        """
        x_scene = _as_rows(features, np.asarray(features).shape[-1], "features")
        dim = x_scene.shape[1]
        if x_scene.shape[0] == 0:
            raise ValueError("fit needs at least one feature row")
        parts, weights = [x_scene], [np.full(len(x_scene), 1.0, np.float32)]
        if vocabulary is not None and len(vocabulary):
            x_vocab = _as_rows(vocabulary, dim, "vocabulary")
            parts.append(x_vocab)
            share = config.scene_weight
            weights = [
                np.full(len(x_scene), share / len(x_scene), np.float32),
                np.full(len(x_vocab), (1.0 - share) / len(x_vocab), np.float32),
            ]
        x = torch.from_numpy(np.concatenate(parts))
        w = torch.from_numpy(np.concatenate(weights))
        w = w / w.sum()
        mean = x.mean(dim=0) if config.center else torch.zeros(dim)
        widths = [dim, *config.hidden, config.latent_dim]
        with torch.random.fork_rng(devices=[]):
            torch.manual_seed(config.seed)
            encoder, decoder = _mlp(widths), _mlp(widths[::-1])
        params = list(encoder.parameters()) + list(decoder.parameters())
        optim = torch.optim.Adam(params, lr=config.lr)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(optim, T_max=max(config.steps, 1), eta_min=config.lr * 0.05)
        every = max(config.steps // 50, 1)
        losses: list[float] = []
        with compute_threads_limited(config.threads):
            for step in range(config.steps):
                loss = _loss(decoder(encoder(x - mean)) + mean, x, w, config)
                if step % every == 0:
                    losses.append(float(loss.detach()))
                optim.zero_grad(set_to_none=True)
                loss.backward()
                optim.step()
                sched.step()
            with torch.no_grad():
                final = float(_loss(decoder(encoder(x - mean)) + mean, x, w, config))
        state = AutoencoderState(
            dim,
            config.latent_dim,
            tuple(config.hidden),
            mean.numpy().astype(np.float32),
            _linear_arrays(encoder),
            _linear_arrays(decoder),
            text_space,
        )
        first = losses[0] if losses else final
        logger.debug("autoencoder %d -> %d: loss %.4f -> %.4f", dim, config.latent_dim, first, final)
        return FeatureAutoencoder(state), TrainReport(tuple(losses), every, final, config.steps)

    # ------------------------------------------------------------------ inference
    def encode(self, x: np.ndarray) -> np.ndarray:
        """``[N, D]`` features -> ``[N, d]`` float32 latents."""
        rows = torch.from_numpy(_as_rows(x, self.input_dim, "encode"))
        with torch.no_grad():
            return self.encoder(rows - self.mean).numpy()

    def decode_torch(self, z: torch.Tensor) -> torch.Tensor:
        """Differentiable ``[..., d]`` -> ``[..., D]`` unit features."""
        return nn.functional.normalize(self.decoder(z) + self.mean, dim=-1)

    def decode(self, z: np.ndarray) -> np.ndarray:
        """``[N, d]`` latents -> ``[N, D]`` float32 unit features."""
        rows = torch.from_numpy(_as_rows(z, self.latent_dim, "decode"))
        with torch.no_grad():
            return self.decode_torch(rows).numpy()

    def state(self) -> AutoencoderState:
        """The weights as plain arrays."""
        return AutoencoderState(
            self.input_dim,
            self.latent_dim,
            self.hidden,
            self.mean.numpy().copy(),
            _linear_arrays(self.encoder),
            _linear_arrays(self.decoder),
            self.text_space,
        )


def _loss(y: torch.Tensor, x: torch.Tensor, w: torch.Tensor, config: AutoencoderConfig) -> torch.Tensor:
    """Row-weighted ``l2 * |y - x|^2 + cos * (1 - cos(y, x))``; ``y`` unnormalised ``[N, D]``."""
    l2 = ((y - x) ** 2).sum(dim=-1)
    cos = 1.0 - nn.functional.cosine_similarity(y, x, dim=-1)
    return (w * (config.l2_weight * l2 + config.cos_weight * cos)).sum()


def reconstruction_cosine(autoencoder: FeatureAutoencoder, x: np.ndarray) -> np.ndarray:
    """``[N]`` cosine between unit features ``x [N, D]`` and their round trip through ``autoencoder``."""
    y = autoencoder.decode(autoencoder.encode(x))
    xn = x / np.maximum(np.linalg.norm(x, axis=1, keepdims=True), 1e-12)
    return (y * xn).sum(axis=1)
