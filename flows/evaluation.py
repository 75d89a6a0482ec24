"""The evaluation flow: ``simsplat eval all`` as a Prefect flow, for the on-demand evaluation deployment.

Thin: the deployment's JSON parameters become an ``EvalAllConfig`` and ``tasks.eval_all.evaluate_all`` computes every
table the store's contents allow into one run directory (it publishes each table as a Prefect table artifact).
"""

from __future__ import annotations

from prefect import flow

from tasks.eval_all import EvalAllConfig, EvalAllResult, evaluate_all


@flow(name="simsplat-evaluate")
def evaluation_flow(  # noqa: PLR0913 -- Prefect flow: its parameters are the deployment's inputs
    store_root: str,
    out: str | None = None,
    only: list[str] | None = None,
    per_category: int = 30,
    infeasible: int = 20,
    per_sequence: int = 3,
    clients: list[str] | None = None,
    seed: int = 0,
) -> EvalAllResult:
    """Every evaluation the store allows (reconstruction, throughput, grounding, editing, motion, mining, search) into
    ``out`` (default: ``runs/<run_id>/`` in the store), as ``simsplat eval all`` runs them.

    Args:
        only: the evaluations to run (default: all the store allows).
        per_category, infeasible: editing prompts per category / infeasible prompts.
        per_sequence: mining: accepted scenarios wanted per sequence.
        clients: mining VLM clients (default ``["rule"]``; ``openai`` runs when ``SIMSPLAT_VLM_URL`` and
            ``SIMSPLAT_VLM_MODEL`` are set on the worker).
        seed: seed of the prompt sets and the mining loop.

    Raises:
        ValueError: the store holds no log. KeyError: an unknown evaluation in ``only``.
    """
    config = EvalAllConfig(groups=tuple(only) if only else None, per_category=per_category, infeasible=infeasible,
                           per_sequence=per_sequence, clients=tuple(clients or ("rule",)), seed=seed)
    return evaluate_all(store_root, out_root=out, config=config)
