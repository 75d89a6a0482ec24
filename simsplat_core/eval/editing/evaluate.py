"""Run editors on the prompt set and check every edit against ground truth (``simsplat eval editing``).

    scenes = [EvalScene.prepare(SceneTruth.from_log(log, nodes), ctx) for ...]
    outcomes = evaluate_editing(scenes, prompts, editing_methods())
    completion_table(outcomes)                       # outcomes.py

Methods (:func:`editing_methods`) are one editor with different ``EditorOptions``: ``ours`` (everything),
``chatsim-like`` and ``omnire-like`` (``editing.options``). ``ours`` and ``chatsim-like`` read the prompt's
words; ``omnire-like`` has no language grounding and gets the prompt's id-based form
(``EditPrompt.structured``; a request naming an object that does not exist has none and counts as refused).

Per (method, prompt): the edit runs (parse + ground + apply + validate, timed); a refusal passes an
infeasible prompt and fails a feasible one; a carried-out edit is re-done by the world itself
(``world_edit.py``), the frames where what changed is seen are picked from the world's renders, the edited
Gaussian scene is rendered there and at the log's test frames, and the state checks (``checks.py``) and
pixel checks (``pixels.py``) decide; fidelity (``fidelity.py``) is measured at the test frames when the
world drew every added object natively. Only those frames are rendered (``EvalConfig.render_all`` renders
every frame).
"""

from __future__ import annotations

import dataclasses
import logging
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from simsplat_core.editing.apply import Editor, apply_edit
from simsplat_core.editing.draft import EditContext
from simsplat_core.editing.options import CHATSIM_LIKE, DEFAULT_OPTIONS, OMNIRE_LIKE, EditorOptions
from simsplat_core.editing.renders import frame_views, render_frame
from simsplat_core.editing.result import EditedScene, EditRefused
from simsplat_core.eval.editing.checks import check_refusal, check_states
from simsplat_core.eval.editing.fidelity import FidelityScore, edit_fidelity, render_fidelity
from simsplat_core.eval.editing.observation import (
    AssetLook,
    EditObservation,
    PixelEvidence,
    ViewSet,
    ego_contact_frames,
    state_changes,
)
from simsplat_core.eval.editing.outcomes import PromptOutcome
from simsplat_core.eval.editing.pixels import MIN_VIEW_PIXELS, check_pixels, object_crops
from simsplat_core.eval.editing.prompts import EditPrompt
from simsplat_core.eval.editing.truth import SceneTruth
from simsplat_core.eval.editing.world_edit import EditedWorld, edit_world
from simsplat_core.language.appearance.captioner import AppearanceCaption, describe_track
from simsplat_core.scene.graph import SceneGraph
from simsplat_core.types import SceneLog
from simsplat_core.world.agents import Agent

logger = logging.getLogger(__name__)

#: ``progress(done, total, label)`` after each (method, prompt).
Progress = Callable[[int, int, str], None]


@dataclass(frozen=True)
class Method:
    """An editor configuration: its name, options, and whether it reads words (else the id-based form)."""

    name: str
    options: EditorOptions
    from_words: bool = True


#: The compared editors (SIMSplat Table 3 rows).
#: Every editor is evaluated with the ego on its log: the world re-renders each edit from the log's camera poses
#: (fidelity, pixel checks), and task completion is about the asked change, not the ego's.
METHODS: dict[str, Method] = {
    "ours": Method("ours", dataclasses.replace(DEFAULT_OPTIONS, ego_reacts=False), True),
    "chatsim-like": Method("chatsim-like", CHATSIM_LIKE, True),
    "omnire-like": Method("omnire-like", OMNIRE_LIKE, False),
}


def editing_methods(names: Sequence[str] | None = None) -> list[Method]:
    """The methods named (default: all, in table order). Raises ``KeyError`` naming an unknown one."""
    unknown = [n for n in names or () if n not in METHODS]
    if unknown:
        raise KeyError(f"unknown editing methods {unknown}; known: {list(METHODS)}")
    return [METHODS[n] for n in (names or METHODS)]


@dataclass(frozen=True)
class EvalConfig:
    """How much to render.

    Attributes:
        check_frames: frames (besides the test frames) where the edit is seen, rendered for the pixel checks.
        search_stride: the world's renders are searched every this many frames for where the edit shows.
        render_all: render every frame instead.
    """

    check_frames: int = 4
    search_stride: int = 3
    render_all: bool = False


# ---------------------------------------------------------------------------------------------- views
def log_views(log: SceneLog, frames: Sequence[int]) -> ViewSet:
    """The log's images and instance maps at ``frames`` (the log's camera order)."""
    cams = log.cameras
    by_key = {(img.frame_idx, img.camera): img for img in log.images}
    rgb, ids = [], []
    for f in frames:
        images, instances = [], []
        for c in cams:
            img = by_key[(f, c)]
            if img.image is None or img.instance is None:
                raise ValueError(f"{log.seq_id}: frame {f} camera {c} lacks its image or instance map")
            images.append(img.image)
            instances.append(img.instance)
        rgb.append(np.stack(images))
        ids.append(np.stack(instances))
    return ViewSet(tuple(frames), cams, np.stack(rgb).astype(np.float32), np.stack(ids).astype(np.int32))


def gaussian_views(graph: SceneGraph, log: SceneLog, frames: Sequence[int]) -> ViewSet:
    """Renders of ``graph`` at ``frames`` from the log's cameras, with node ids."""
    rgb, ids, cams = [], [], log.cameras
    for f in frames:
        out = render_frame(graph, int(f), frame_views(log, int(f)))
        order = [out.camera(c) for c in cams]
        assert out.node_id is not None
        rgb.append(np.stack([out.rgb[k] for k in order]))
        ids.append(np.stack([out.node_id[k] for k in order]))
    return ViewSet(tuple(int(f) for f in frames), cams, np.stack(rgb).astype(np.float32),
                   np.stack(ids).astype(np.int32))


class WorldViews:
    """The edited world's renders, made once per frame."""

    def __init__(self, world: EditedWorld, cameras: tuple[str, ...]) -> None:
        self.world, self.cameras = world, cameras
        self._cache: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def frame(self, f: int) -> tuple[np.ndarray, np.ndarray]:
        """``([C, H, W, 3] rgb, [C, H, W] instance ids)`` of frame ``f``."""
        if f not in self._cache:
            renders = {r[0]: r for r in self.world.render(f)}
            self._cache[f] = (np.stack([renders[c][3] for c in self.cameras]).astype(np.float32),
                              np.stack([renders[c][5] for c in self.cameras]).astype(np.int32))
        return self._cache[f]

    def silhouettes(self, frames: Sequence[int], object_ids: Sequence[str]) -> dict[str, np.ndarray]:
        """Per object id, ``[F, C]`` pixels its unoccluded silhouette covers in ``views(frames)``
        (``World.silhouette_pixels``)."""
        ids = [self.world.instance[o] for o in object_ids]
        counts = []
        for f in frames:
            per_camera = self.world.world.silhouette_pixels(int(f), ids)
            counts.append(np.stack([per_camera[c] for c in self.cameras]))  # [C, N]
        stacked = np.stack(counts) if counts else np.zeros((0, len(self.cameras), len(ids)), np.int64)
        return {o: stacked[:, :, k] for k, o in enumerate(object_ids)}

    def views(self, frames: Sequence[int]) -> ViewSet:
        pairs = [self.frame(int(f)) for f in frames]
        return ViewSet(tuple(int(f) for f in frames), self.cameras, np.stack([p[0] for p in pairs]),
                       np.stack([p[1] for p in pairs]))


# ---------------------------------------------------------------------------------------------- scenes
@dataclass(frozen=True, eq=False)
class EvalScene:
    """One scene ready for evaluation: its ground truth, the editor's context and the unedited test renders.

    Attributes:
        truth: ground truth (``truth.log`` with images and instance maps).
        ctx: the editor's context of the stored scene.
        unedited: the unedited graph rendered at the test frames.
        psnr_unedited, ssim_unedited: ``unedited`` against the log's test images.
    """

    truth: SceneTruth
    ctx: EditContext
    unedited: ViewSet
    psnr_unedited: float
    ssim_unedited: float

    @classmethod
    def prepare(cls, truth: SceneTruth, ctx: EditContext) -> EvalScene:
        frames = truth.test_frames
        unedited = gaussian_views(ctx.graph, truth.log, frames)
        p, s = render_fidelity(unedited, log_views(truth.log, frames))
        logger.info("%s: unedited test PSNR %.2f dB, SSIM %.3f over %d frames", truth.seq_id, p, s, len(frames))
        return cls(truth, ctx, unedited, p, s)


@dataclass
class SourceAgents:
    """Finds the ground-truth agent an asset was cut out of (its build, skin, hair, gait)."""

    truths: dict[str, SceneTruth] = field(default_factory=dict)

    def __call__(self, look: AssetLook) -> Agent | None:
        truth = self.truths.get(look.source_seq)
        if truth is None or not look.source_object:
            return None
        try:
            return truth.agent(look.source_object)
        except KeyError:
            return None


# ---------------------------------------------------------------------------------------------- one edit
def run_edit(scene: EvalScene, prompt: EditPrompt, method: Method) -> tuple[EditObservation, EditedScene | None]:
    """Run one method on one prompt; refusals and errors become observations (errors are logged)."""
    started = time.perf_counter()
    try:
        if method.from_words:
            edited = Editor(scene.ctx, method.options).edit(prompt.text)
        elif prompt.structured is None:
            return EditObservation.refusal("not_found", "the request names no object of the scene by id"), None
        else:
            edited = apply_edit(scene.ctx, prompt.structured, method.options)
    except EditRefused as exc:
        return EditObservation.refusal(exc.reason, str(exc), time.perf_counter() - started), None
    except Exception as exc:  # an editor bug must not stop the evaluation: it is a failed edit
        logger.warning("%s %s %r raised %s:\n%s", method.name, prompt.prompt_id, prompt.text, type(exc).__name__,
                       traceback.format_exc())
        return EditObservation("error", f"{type(exc).__name__}: {exc}", seconds=time.perf_counter() - started), None
    seconds = time.perf_counter() - started
    bank = scene.ctx.bank
    looks = {}
    for added in edited.delta.added:
        if bank is None:
            raise RuntimeError("the editor added an asset without an asset bank")
        looks[added.object_id] = AssetLook.of_asset(bank.get(added.asset_id))
    return EditObservation(None, "; ".join(edited.summary_lines()), edited.original_states, edited.states, looks,
                           seconds, bool(edited.validation.ok)), edited


def pick_frames(scene: EvalScene, obs: EditObservation, world: WorldViews, config: EvalConfig) -> tuple[int, ...]:
    """The test frames plus up to ``config.check_frames`` frames where what the edit changed is seen."""
    truth = scene.truth
    n = truth.log.num_frames
    if config.render_all:
        return tuple(range(n))
    assert obs.before is not None and obs.after is not None
    changes = state_changes(obs.before, obs.after)
    shown = [world.world.instance[o] for o in (*changes.added, *changes.moved, *changes.redrawn)
             if o in world.world.instance]
    gone = [truth.facts[o].instance_id for o in changes.removed if o in truth.facts]
    search = sorted(set(range(0, n, config.search_stride)) | set(truth.test_frames))
    seen = []
    original = log_views(truth.log, search) if gone else None
    for k, f in enumerate(search):
        _, inst = world.frame(f)
        count = max((int((inst == i).sum(axis=(1, 2)).max()) for i in shown), default=0)
        if original is not None:
            count = max(count, max(int((original.ids[k] == i).sum(axis=(1, 2)).max()) for i in gone))
        if count >= MIN_VIEW_PIXELS:
            seen.append(f)
    if len(seen) > config.check_frames:
        seen = [seen[int(i)] for i in np.linspace(0, len(seen) - 1, config.check_frames).round()]
    return tuple(sorted(set(seen) | set(truth.test_frames)))


def reference_captions(truth: SceneTruth, prompt: EditPrompt, obs: EditObservation, frames: tuple[int, ...],
                       sources: SourceAgents) -> dict[str, AppearanceCaption]:
    """The captioner's captions of the world's own rendering of each inserted / replacing object with the
    *asked* colours (``PixelEvidence.reference_captions``); empty when no colour was asked."""
    asset = prompt.intent.asset
    if asset is None or (asset.color is None and asset.upper is None and asset.lower is None):
        return {}
    assert obs.before is not None and obs.after is not None
    changes = state_changes(obs.before, obs.after)
    objects = [o for o in (*changes.added, *changes.redrawn) if o in obs.looks]
    if not objects:
        return {}
    asked = {o: dataclasses.replace(obs.looks[o], color=asset.upper or asset.color or obs.looks[o].color,
                                    lower=asset.lower or obs.looks[o].lower) for o in objects}
    world = edit_world(truth.world, obs.before, obs.after, {**obs.looks, **asked}, sources)
    views = WorldViews(world, truth.log.cameras).views(frames)
    out = {}
    for o in objects:
        row = obs.after.index(o)
        crops = object_crops(views, world.instance[o], o, obs.after.categories[row], obs.after.size[row])
        if crops:
            out[o] = describe_track(crops)
    return out


def evaluate_prompt(scene: EvalScene, prompt: EditPrompt, method: Method, config: EvalConfig | None = None,
                    sources: SourceAgents | None = None) -> PromptOutcome:
    """Run and check one (method, prompt) (module docstring)."""
    config = config or EvalConfig()
    obs, edited = run_edit(scene, prompt, method)
    validation = "" if obs.validation_ok is None else ("ok" if obs.validation_ok else "failed")
    refusal = obs.refused or ""
    if prompt.infeasible:
        result = check_refusal(prompt.intent, obs)
        return PromptOutcome(prompt, method.name, result.passed, result.reason, refusal, obs.seconds, 0.0,
                             validation, None, result.measured)
    if edited is None:
        return PromptOutcome(prompt, method.name, False, f"{'error' if refusal == 'error' else 'refused'} "
                             f"({refusal}): {obs.message}", refusal, obs.seconds, 0.0, validation)
    started = time.perf_counter()
    truth = scene.truth
    states = check_states(truth, prompt.intent, obs)
    assert obs.before is not None and obs.after is not None
    sources = sources or SourceAgents({truth.seq_id: truth})
    world = edit_world(truth.world, obs.before, obs.after, obs.looks, sources)
    views = WorldViews(world, truth.log.cameras)
    frames = pick_frames(scene, obs, views, config)
    changes = state_changes(obs.before, obs.after)
    shown = [o for o in (*changes.added, *changes.moved, *changes.redrawn) if o in world.instance]
    evidence = PixelEvidence(gaussian_views(edited.graph, truth.log, frames), views.views(frames),
                             log_views(truth.log, frames), dict(world.instance),
                             {o: f.instance_id for o, f in truth.facts.items()}, world.native,
                             reference_captions(truth, prompt, obs, frames, sources),
                             views.silhouettes(frames, shown), ego_contact_frames(obs.after))
    pixels = check_pixels(prompt.intent, obs, evidence)
    fidelity: FidelityScore | None = None
    if all(o in world.native for o in (*changes.added, *changes.redrawn)):
        test = truth.test_frames
        fidelity = edit_fidelity(evidence.edited.take(test), evidence.world_edited.take(test),
                                 evidence.world_original.take(test), scene.unedited)
    passed = states.passed and pixels.passed
    reason = f"{states.reason} | pixels: {pixels.reason}"
    measured = {**states.measured, **pixels.measured}
    if world.notes:
        reason += " | world: " + "; ".join(world.notes)
    return PromptOutcome(prompt, method.name, passed, reason, refusal, obs.seconds, time.perf_counter() - started,
                         validation, fidelity, measured)


def evaluate_editing(scenes: Sequence[EvalScene], prompts: Sequence[EditPrompt], methods: Sequence[Method],
                     config: EvalConfig | None = None, progress: Progress | None = None) -> list[PromptOutcome]:
    """Every method on every prompt of the given scenes (prompts of other scenes are skipped, named)."""
    by_seq = {s.truth.seq_id: s for s in scenes}
    sources = SourceAgents({s: scene.truth for s, scene in by_seq.items()})
    skipped = sorted({p.seq_id for p in prompts if p.seq_id not in by_seq})
    if skipped:
        logger.warning("no scene for prompts of %s: skipped", skipped)
    todo = [(m, p) for m in methods for p in prompts if p.seq_id in by_seq]
    out = []
    for k, (method, prompt) in enumerate(todo):
        outcome = evaluate_prompt(by_seq[prompt.seq_id], prompt, method, config, sources)
        out.append(outcome)
        logger.info("%s %s: %s (%s)", method.name, prompt.prompt_id, "ok" if outcome.completed else "FAILED",
                    outcome.reason[:200])
        if progress is not None:
            progress(k + 1, len(todo), f"{method.name} {prompt.category}")
    return out


__all__ = ["METHODS", "EvalConfig", "EvalScene", "Method", "SourceAgents", "WorldViews", "editing_methods",
           "evaluate_editing", "evaluate_prompt", "gaussian_views", "log_views", "pick_frames", "reference_captions",
           "run_edit"]
