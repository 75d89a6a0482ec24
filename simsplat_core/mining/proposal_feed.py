"""The mining loop's proposals, one at a time: seed prompts first (e.g. search hits), then the VLM client's, asked
in rounds as needed, without repeats.

    feed = ProposalFeed(client, summary, views, seeds=["a pedestrian jaywalks ahead"], per_round=6, max_rounds=3)
    while (pending := feed.take()) is not None:
        pending.prompt, pending.category, pending.source, pending.propose_s

Round ``r`` (1-based) asks the client for ``r * per_round`` prompts (a deterministic client repeats its earlier
ones, a sampling one may not; repeats -- same words up to case and spacing -- are dropped either way) and ends the
feed when it brings nothing new or after ``max_rounds``. A client that knows its proposals' categories
(:class:`CategorisedProposer`: the rule-based client) is asked through ``proposals`` so each prompt keeps its
category. A failed call (``VLMError``, or ``ValueError`` for a malformed answer or a scene without feasible edits)
ends the client's part of the feed: :meth:`ProposalFeed.take` returns it once as a :class:`Pending` with its
``error`` set, so the loop records it.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from simsplat_core.mining.rule_proposals import Proposal
from simsplat_core.mining.vlm_protocol import ProposalRequest, SceneSummary, VLMClient
from simsplat_core.vlm.openai_chat import VLMError

logger = logging.getLogger(__name__)


@runtime_checkable
class CategorisedProposer(Protocol):
    """A client whose proposals carry their edit category (``RuleBasedVLMClient.proposals``)."""

    def proposals(self, summary: SceneSummary, count: int) -> list[Proposal]:
        """Up to ``count`` proposals with their category."""
        ...


@dataclass(frozen=True)
class Pending:
    """One proposal to work on.

    Attributes:
        prompt: the words (``""`` with ``error``).
        category: its edit category when the proposer said (else ``""``).
        source: ``"seed"`` or ``"client"``.
        propose_s: seconds of the proposing round, charged to the round's first proposal (0 for the others).
        error: why proposing failed (``"<Type>: <message>"``; ``""`` for a proposal).
        target_id: the scene object the proposer meant (``Proposal.target_id``: the rule-based client and search
            seeds know it; ``None``: not said).
    """

    prompt: str
    category: str = ""
    source: str = "client"
    propose_s: float = 0.0
    error: str = ""
    target_id: str | None = None


def _key(prompt: str) -> str:
    return " ".join(prompt.lower().split())


class ProposalFeed:
    """Seed prompts, then the client's proposals in rounds (module docstring).

    Args:
        client: the VLM client.
        summary: the scene's facts.
        views: ``[H, W, 3]`` images of the scene (at least one), or a function making them (called once, when a
            client that reads views is first asked; its time counts as proposing).
        seeds: prompts (or :class:`Proposal` s, whose category is kept) to try first.
        per_round: prompts asked per round; max_rounds: most rounds.
    """

    def __init__(self, client: VLMClient, summary: SceneSummary,
                 views: Sequence[np.ndarray] | Callable[[], Sequence[np.ndarray]],
                 seeds: Iterable[str | Proposal] = (), *, per_round: int = 6, max_rounds: int = 3) -> None:
        self.client = client
        self.summary = summary
        self._views = views
        self.per_round = int(per_round)
        self.max_rounds = int(max_rounds)
        self.rounds = 0
        self.seconds = 0.0
        self._seen: set[str] = set()
        self._queue: deque[Pending] = deque()
        self._open = True
        for seed in seeds:
            if isinstance(seed, Proposal):
                self._push(Pending(seed.prompt, seed.category, "seed", target_id=seed.target_id))
            else:
                self._push(Pending(str(seed), "", "seed"))

    def _push(self, pending: Pending) -> bool:
        key = _key(pending.prompt)
        if not key or key in self._seen:
            return False
        self._seen.add(key)
        self._queue.append(pending)
        return True

    def _ask(self, count: int) -> list[tuple[str, str, str | None]]:
        """``(prompt, category, target id)`` of up to ``count`` proposals of the client."""
        if isinstance(self.client, CategorisedProposer):
            return [(p.prompt, p.category, p.target_id) for p in self.client.proposals(self.summary, count)]
        if callable(self._views):
            self._views = list(self._views())
        request = ProposalRequest(self._views, self.summary, count)
        return [(p, "", None) for p in self.client.propose(request)]

    def _round(self) -> None:
        """One more round of the client's proposals into the queue (or the feed's end)."""
        self.rounds += 1
        count = self.rounds * self.per_round
        started = time.perf_counter()
        try:
            found = self._ask(count)
        except (VLMError, ValueError) as exc:
            self._open = False
            seconds = time.perf_counter() - started
            self.seconds += seconds
            logger.warning("%s: proposing failed (round %d): %s", self.summary.seq_id, self.rounds, exc)
            self._queue.append(Pending("", source="client", propose_s=seconds, error=f"{type(exc).__name__}: {exc}"))
            return
        seconds = time.perf_counter() - started
        self.seconds += seconds
        added = 0
        for prompt, category, target_id in found:
            added += self._push(Pending(prompt, category, "client", seconds if added == 0 else 0.0,
                                        target_id=target_id))
        logger.info("%s: round %d: %d proposal(s), %d new", self.summary.seq_id, self.rounds, len(found), added)
        if added == 0 or self.rounds >= self.max_rounds:
            self._open = False

    def take(self) -> Pending | None:
        """The next proposal (or a proposing failure, once), ``None`` when there is none left."""
        while not self._queue and self._open:
            self._round()
        return self._queue.popleft() if self._queue else None


__all__ = ["CategorisedProposer", "Pending", "ProposalFeed"]
