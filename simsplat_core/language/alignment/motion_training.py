"""Motion-aware language alignment (SIMSplat Sec. 3.2): train the trajectory encoder, produce ``f_mot`` / ``f_loc``.

    aligner = MotionAligner.fit(logs, MotionAlignerConfig())
    feats = aligner.features(log)                       # {object_id: ObjectMotionFeatures}
    q = encoder.encode_queries(["the car turning left"])[0]
    mot_sim, loc_sim = aligner.score(q, feats)          # [N] each, in the order of feats

Per object the encoder gives convex weights over fixed text prototypes (``language.codebooks``):
``f_mot = sum_k w_k p_k`` over the motion codebook of its kind (vehicle / pedestrian) and
``f_loc = 1/2 sum_s w_s p_s + 1/2 sum_c w_c p_c`` over the location sector and context prototypes,
all in the text encoder's space (384-d for E5).

Loss, per sample with auto-labels ``(y_mot, y_sector, y_context)`` (``language.motion_labels``)::

    L = lambda_align * (L_mot + L_loc) + lambda_commit * L_commit
    L_mot = 1 - cos_c(f_mot, p_{y_mot})
    L_loc = 1 - cos_c(f_loc, 1/2 (p_{y_sector} + p_{y_context}))
    L_commit = C(w_mot, y_mot) + 1/2 (C(w_sector, y_sector) + C(w_context, y_context))

``cos_c`` is the cosine after subtracting the group's prototype mean (see ``language.codebooks``: raw E5
cosines between these phrases sit in 0.8-0.95 and give almost no gradient).

The commitment ``C`` keeps the convex combination close to one vertex of the simplex, so ``f_mot``
sits near a phrase embedding instead of a blurred average. Two choices (``config.commitment``):

* ``"label"`` (default): ``C(w, y) = -log w_y / log K``, the KL divergence from the one-hot
  assignment to the auto-label's prototype -- the VQ-VAE commitment (van den Oord et al., NeurIPS
  2017) with the code assigned by the auto-labeller instead of by the nearest code;
* ``"entropy"``: ``C(w) = H(w) / log K``, sharpness only (entropy minimisation, Grandvalet & Bengio,
  NIPS 2004; soft-to-hard VQ, Agustsson et al., NIPS 2017).

The label form is needed because E5 barely separates some classes: "crossing from left to right" and
"from right to left" have a prototype cosine of 0.997, so ``L_mot`` cannot tell them apart and with
the entropy form the encoder collapsed both directions onto one prototype (on 10 held-out seeds every
crossing of the other direction was misread: 4/4, or 7/7 with another width); with the label form
none was.

Persisting: ``aligner.state()`` is a ``MotionAlignerState`` of plain numpy arrays and a JSON config
(``save`` / ``load`` write one ``.npz``); ``MotionAligner.from_state`` restores identical features.
"""

from __future__ import annotations

import contextlib
import dataclasses
import io
import json
import logging
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch

from simsplat_core.compute_threads import compute_threads_limited
from simsplat_core.language.alignment.motion_dataset import RealismConfig, SampleConfig, TrainingSamples, build_samples
from simsplat_core.language.alignment.motion_encoder import HEADS, InputConfig, TrajectoryEncoder, trajectory_inputs
from simsplat_core.language.codebooks import MotionCodebooks, centred_cosine, convex_combination, cosine_scores
from simsplat_core.language.motion_labels import LabelThresholds, label_trajectory
from simsplat_core.language.scene_language import ObjectMotionFeatures
from simsplat_core.language.text import TextEncoder, default_text_encoder
from simsplat_core.scenario.map_context import MapContext
from simsplat_core.scenario.trajectory import AGENT_KINDS, log_trajectories
from simsplat_core.types import SceneLog

logger = logging.getLogger(__name__)

STATE_VERSION = 1


@dataclass(frozen=True)
class MotionAlignerConfig:
    """Everything that determines a trained aligner (with the training logs and the text encoder).

    Attributes:
        inputs: trajectory tensor layout.
        samples: windows / mirroring of the training samples.
        thresholds: auto-labeller thresholds.
        hidden, dropout: encoder size.
        epochs, batch_size, lr, weight_decay: AdamW schedule (cosine-decayed learning rate).
        lambda_align, lambda_commit: loss weights (module docstring).
        commitment: ``"label"`` or ``"entropy"`` (module docstring).
        seed: seeds windows, initialisation, dropout and batch order.
    """

    inputs: InputConfig = field(default_factory=InputConfig)
    samples: SampleConfig = field(default_factory=SampleConfig)
    thresholds: LabelThresholds = field(default_factory=LabelThresholds)
    hidden: int = 128
    dropout: float = 0.1
    epochs: int = 40
    batch_size: int = 256
    lr: float = 3e-3
    weight_decay: float = 1e-4
    lambda_align: float = 1.0
    lambda_commit: float = 0.1
    commitment: str = "label"
    seed: int = 0

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), sort_keys=True)

    @classmethod
    def from_json(cls, text: str) -> MotionAlignerConfig:
        data = json.loads(text)
        samples = data.pop("samples")
        realism = samples.pop("realism", None)
        if realism is not None:
            realism = RealismConfig(**{**realism, "time_stretch": tuple(realism["time_stretch"])})
        return cls(
            inputs=InputConfig(**data.pop("inputs")),
            samples=SampleConfig(**samples, realism=realism),
            thresholds=LabelThresholds(**data.pop("thresholds")),
            **data,
        )


@dataclass(frozen=True)
class MotionAlignerState:
    """A trained aligner as plain arrays (for ``storage`` to persist).

    Attributes:
        config_json: ``MotionAlignerConfig.to_json()``.
        encoder_name: ``TextEncoder.name`` of the prototypes' text space.
        classes: class names by codebook name.
        prototypes: ``[K, D]`` float32 by codebook name.
        weights: the encoder's ``state_dict`` as numpy arrays.
        version: layout version of this state.
    """

    config_json: str
    encoder_name: str
    classes: dict[str, tuple[str, ...]]
    prototypes: dict[str, np.ndarray]
    weights: dict[str, np.ndarray]
    version: int = STATE_VERSION

    def save(self, path: str | Path) -> None:
        """One ``.npz``: arrays under ``prototypes/`` and ``weights/``, the rest as JSON under ``meta``."""
        meta = {
            "version": self.version,
            "config_json": self.config_json,
            "encoder_name": self.encoder_name,
            "classes": {k: list(v) for k, v in self.classes.items()},
        }
        arrays: dict[str, Any] = {"meta": np.array(json.dumps(meta))}
        arrays.update({f"prototypes/{k}": v for k, v in self.prototypes.items()})
        arrays.update({f"weights/{k}": v for k, v in self.weights.items()})
        buffer = io.BytesIO()
        np.savez(buffer, **arrays)
        Path(path).write_bytes(buffer.getvalue())

    @classmethod
    def load(cls, path: str | Path) -> MotionAlignerState:
        with np.load(Path(path), allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta["version"] != STATE_VERSION:
                raise ValueError(f"{path}: motion aligner state version {meta['version']}, expected {STATE_VERSION}")
            prototypes = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith("prototypes/")}
            weights = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith("weights/")}
        return cls(
            meta["config_json"],
            meta["encoder_name"],
            {k: tuple(v) for k, v in meta["classes"].items()},
            prototypes,
            weights,
            meta["version"],
        )


@contextlib.contextmanager
def single_threaded_torch() -> Iterator[None]:
    """Run torch on one intra-op thread, restoring the previous setting afterwards.

    The encoder's matrices are tiny: thread hand-offs cost more than they save, and on a busy
    machine the OpenMP spin-waits made a 10 s training run take minutes (measured: 10 s with one
    thread vs 250 s with two, 2 shared cores). One thread also makes the run bit-reproducible.
    """
    with compute_threads_limited(1):
        yield


def _commitment(weights: torch.Tensor, target: torch.Tensor, kind: str) -> torch.Tensor:
    """``[N]`` commitment of ``[N, K]`` convex weights, normalised by ``log K``.

    ``"label"``: cross-entropy ``-log w_target`` (KL from the one-hot assignment to the auto-label's
    prototype); ``"entropy"``: ``H(w)`` (sharpness only, any prototype).
    """
    log_w = weights.clamp_min(1e-12).log()
    if kind == "label":
        value = -log_w.gather(1, target[:, None])[:, 0]
    elif kind == "entropy":
        value = -(weights * log_w).sum(-1)
    else:
        raise ValueError(f"unknown commitment {kind!r}; use 'label' or 'entropy'")
    return value / np.log(weights.shape[-1])


class _Prototypes:
    """The codebooks as torch tensors (prototypes and centres)."""

    def __init__(self, books: MotionCodebooks) -> None:
        t = lambda a: torch.as_tensor(np.asarray(a, dtype=np.float32))  # noqa: E731
        self.motion = {kind: t(books.motion(kind).prototypes) for kind in AGENT_KINDS}
        self.sector = t(books.sector.prototypes)
        self.context = t(books.context.prototypes)
        self.motion_centre = t(books.motion_centre)
        self.location_centre = t(books.location_centre)

    def aggregate(self, logits: dict[str, torch.Tensor], kind: torch.Tensor) -> dict[str, torch.Tensor]:
        """Convex weights and features: ``w_<head>`` ``[N, K]``, ``f_mot`` / ``f_loc`` ``[N, D]`` (``kind`` ``[N]``)."""
        out = {f"w_{name}": torch.softmax(logits[name], dim=-1) for name in HEADS}
        f_mot = torch.zeros(kind.shape[0], self.sector.shape[1])
        for k, name in enumerate(AGENT_KINDS):
            rows = kind == k
            f_mot[rows] = convex_combination(out[f"w_{name}"][rows], self.motion[name])
        out["f_mot"] = f_mot
        out["f_loc"] = 0.5 * (
            convex_combination(out["w_sector"], self.sector) + convex_combination(out["w_context"], self.context)
        )
        return out


def alignment_loss(
    logits: dict[str, torch.Tensor],
    kind: torch.Tensor,
    motion: torch.Tensor,
    sector: torch.Tensor,
    context: torch.Tensor,
    protos: _Prototypes,
    lambda_align: float,
    lambda_commit: float,
    commitment: str = "label",
) -> tuple[torch.Tensor, dict[str, float]]:
    """The loss of the module docstring for a batch; returns ``(loss, {term: value})``.

    ``kind`` / ``motion`` / ``sector`` / ``context`` are ``[N]`` int64 label indices.
    """
    agg = protos.aggregate(logits, kind)
    target_mot = torch.zeros_like(agg["f_mot"])
    commit_mot = torch.zeros(kind.shape[0])
    for k, name in enumerate(AGENT_KINDS):
        rows = kind == k
        target_mot[rows] = protos.motion[name][motion[rows]]
        commit_mot[rows] = _commitment(agg[f"w_{name}"][rows], motion[rows], commitment)
    target_loc = 0.5 * (protos.sector[sector] + protos.context[context])
    l_mot = (1.0 - centred_cosine(agg["f_mot"], target_mot, protos.motion_centre)).mean()
    l_loc = (1.0 - centred_cosine(agg["f_loc"], target_loc, protos.location_centre)).mean()
    commit_loc = _commitment(agg["w_sector"], sector, commitment) + _commitment(agg["w_context"], context, commitment)
    l_commit = (commit_mot + 0.5 * commit_loc).mean()
    loss = lambda_align * (l_mot + l_loc) + lambda_commit * l_commit
    terms = {"mot": l_mot.item(), "loc": l_loc.item(), "commit": l_commit.item(), "total": loss.item()}
    return loss, terms


def _tensors(samples: TrainingSamples) -> dict[str, torch.Tensor]:
    return {
        name: torch.as_tensor(getattr(samples, name)) for name in ("seq", "glob", "kind", "motion", "sector", "context")
    }


class MotionAligner:
    """A trained trajectory encoder with its codebooks; build with ``fit`` or ``from_state``."""

    def __init__(self, config: MotionAlignerConfig, codebooks: MotionCodebooks, network: TrajectoryEncoder) -> None:
        self.config = config
        self.codebooks = codebooks
        self.network = network.eval()
        self._protos = _Prototypes(codebooks)
        #: per-epoch mean loss terms of the last ``fit`` (empty for restored aligners).
        self.history: list[dict[str, float]] = []
        self.train_seconds = 0.0

    @staticmethod
    def _new_network(config: MotionAlignerConfig, codebooks: MotionCodebooks) -> TrajectoryEncoder:
        sizes = {
            "vehicle": len(codebooks.vehicle),
            "pedestrian": len(codebooks.pedestrian),
            "sector": len(codebooks.sector),
            "context": len(codebooks.context),
        }
        return TrajectoryEncoder(config.inputs.steps, sizes, config.hidden, config.dropout)

    @classmethod
    def fit(
        cls,
        logs: Sequence[SceneLog],
        config: MotionAlignerConfig | None = None,
        encoder: TextEncoder | None = None,
    ) -> MotionAligner:
        """Auto-label ``logs``, build samples and train; deterministic for a given ``config.seed``."""
        config = config or MotionAlignerConfig()
        encoder = encoder or default_text_encoder()
        t0 = time.perf_counter()
        codebooks = MotionCodebooks.build(encoder)
        samples = build_samples(logs, codebooks, config.inputs, config.samples, config.thresholds, config.seed)
        with torch.random.fork_rng(), single_threaded_torch():
            torch.manual_seed(config.seed)
            network = cls._new_network(config, codebooks)
            aligner = cls(config, codebooks, network)
            aligner._train(samples)
        aligner.train_seconds = time.perf_counter() - t0
        logger.info(
            "trained motion aligner on %d logs / %d samples in %.1f s (final loss %.4f)",
            len(logs),
            len(samples),
            aligner.train_seconds,
            aligner.history[-1]["total"] if aligner.history else float("nan"),
        )
        return aligner

    def _train(self, samples: TrainingSamples) -> None:
        cfg = self.config
        data = _tensors(samples)
        n = len(samples)
        steps_per_epoch = max(1, -(-n // cfg.batch_size))
        optim = torch.optim.AdamW(self.network.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
        sched = torch.optim.lr_scheduler.CosineAnnealingLR(optim, T_max=cfg.epochs * steps_per_epoch)
        gen = torch.Generator().manual_seed(cfg.seed)
        self.network.train()
        for _ in range(cfg.epochs):
            order = torch.randperm(n, generator=gen)
            totals: dict[str, float] = {}
            for start in range(0, n, cfg.batch_size):
                idx = order[start : start + cfg.batch_size]
                logits = self.network(data["seq"][idx], data["glob"][idx])
                loss, terms = alignment_loss(
                    logits,
                    data["kind"][idx],
                    data["motion"][idx],
                    data["sector"][idx],
                    data["context"][idx],
                    self._protos,
                    cfg.lambda_align,
                    cfg.lambda_commit,
                    cfg.commitment,
                )
                optim.zero_grad()
                loss.backward()
                optim.step()
                sched.step()
                for key, value in terms.items():
                    totals[key] = totals.get(key, 0.0) + value * len(idx) / n
            self.history.append(totals)
        self.network.eval()

    def evaluate_loss(self, logs: Sequence[SceneLog]) -> dict[str, float]:
        """Loss terms of the trained network on the whole trajectories of ``logs`` (no windows, no mirroring)."""
        cfg = dataclasses.replace(self.config.samples, windows_per_track=0, mirror=False)
        samples = build_samples(logs, self.codebooks, self.config.inputs, cfg, self.config.thresholds, 0)
        data = _tensors(samples)
        with torch.no_grad(), single_threaded_torch():
            logits = self.network(data["seq"], data["glob"])
            _, terms = alignment_loss(
                logits,
                data["kind"],
                data["motion"],
                data["sector"],
                data["context"],
                self._protos,
                self.config.lambda_align,
                self.config.lambda_commit,
                self.config.commitment,
            )
        return terms

    def features(self, log: SceneLog) -> dict[str, ObjectMotionFeatures]:
        """``f_mot`` / ``f_loc`` of every movable object of ``log`` (static objects and signs are skipped)."""
        map_context = MapContext.from_features(log.map_features) if log.map_features else None
        trajectories = log_trajectories(log, map_context, min_frames=1)
        if not trajectories:
            return {}
        labels, seqs, globs = [], [], []
        for traj in trajectories.values():
            labels.append(label_trajectory(traj, log.ego_poses, map_context, self.config.thresholds))
            seq, glob = trajectory_inputs(traj, log.ego_poses, map_context, self.config.inputs)
            seqs.append(seq)
            globs.append(glob)
        kind = torch.as_tensor([AGENT_KINDS.index(t.kind) for t in trajectories.values()])
        with torch.no_grad(), single_threaded_torch():
            logits = self.network(torch.as_tensor(np.stack(seqs)), torch.as_tensor(np.stack(globs)))
            agg = self._protos.aggregate(logits, kind)
        books = self.codebooks
        out = {}
        for i, (oid, traj) in enumerate(trajectories.items()):
            w_mot = agg[f"w_{traj.kind}"][i].numpy()
            w_loc = 0.5 * np.concatenate([agg["w_sector"][i].numpy(), agg["w_context"][i].numpy()])
            out[oid] = ObjectMotionFeatures(
                object_id=oid,
                kind=traj.kind,
                f_mot=agg["f_mot"][i].numpy().astype(np.float32),
                f_loc=agg["f_loc"][i].numpy().astype(np.float32),
                motion_probs=dict(zip(books.motion(traj.kind).classes, map(float, w_mot))),
                location_probs=dict(zip(books.location_classes, map(float, w_loc))),
                labels=labels[i],
            )
        return out

    def score(
        self, query_embedding: np.ndarray, features: Mapping[str, ObjectMotionFeatures]
    ) -> tuple[np.ndarray, np.ndarray]:
        """``(mot_sim [N], loc_sim [N])``: cosine of a ``[D]`` query embedding with each object's ``f_mot`` and
        ``f_loc``, in the order of ``features``. The query must come from the text encoder named
        ``self.codebooks.encoder_name`` (its ``encode_queries``)."""
        query = np.asarray(query_embedding, dtype=np.float32).reshape(-1)
        if query.shape[0] != self.codebooks.dim:
            raise ValueError(f"query has {query.shape[0]} dims, the aligner's text space has {self.codebooks.dim}")
        if not features:
            return np.zeros(0, dtype=np.float32), np.zeros(0, dtype=np.float32)
        f_mot = np.stack([f.f_mot for f in features.values()])
        f_loc = np.stack([f.f_loc for f in features.values()])
        return cosine_scores(f_mot, query), cosine_scores(f_loc, query)

    # ------------------------------------------------------------------ persistence
    def state(self) -> MotionAlignerState:
        books = self.codebooks
        return MotionAlignerState(
            config_json=self.config.to_json(),
            encoder_name=books.encoder_name,
            classes={cb.name: cb.classes for cb in (books.vehicle, books.pedestrian, books.sector, books.context)},
            prototypes={k: v.copy() for k, v in books.arrays().items()},
            weights={k: v.detach().cpu().numpy().copy() for k, v in self.network.state_dict().items()},
        )

    @classmethod
    def from_state(cls, state: MotionAlignerState) -> MotionAligner:
        config = MotionAlignerConfig.from_json(state.config_json)
        codebooks = MotionCodebooks.from_arrays(state.encoder_name, state.classes, state.prototypes)
        network = cls._new_network(config, codebooks)
        network.load_state_dict({k: torch.as_tensor(v) for k, v in state.weights.items()})
        return cls(config, codebooks, network)

    def save(self, path: str | Path) -> None:
        self.state().save(path)

    @classmethod
    def load(cls, path: str | Path) -> MotionAligner:
        return cls.from_state(MotionAlignerState.load(path))
