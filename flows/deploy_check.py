"""Static checks of the deployment files under ``deploy/``: what ``prefect deploy``, ``ray up`` and ``kubectl apply``
would trip over, found without a Prefect server, a Ray cluster or Kubernetes.

Each check returns :class:`Finding` s naming the file, the deployment (or manifest part) and the field; an empty list
means the file passed. Entry points are imported (``prefect.flows.load_flow_from_entrypoint``), so a flow module that
fails to import is a finding too. A mining configuration a deployment names (its ``mining_config`` parameter, a path
relative to the repository root) is read and checked as the run would (``tasks.mining_config``).
"""

from __future__ import annotations

import copy
import inspect
import types
import typing
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

#: The keys ``ray up`` needs in a cluster YAML.
RAY_REQUIRED = ("cluster_name", "provider")
#: Deployment parameters naming a mining configuration file (checked with ``tasks.mining_config``).
MINING_CONFIG_PARAMETERS = ("mining_config",)
#: Node layouts ``ray up`` accepts: the current node types or the older head/worker spec.
RAY_NODE_LAYOUTS = (("head_node_type", "available_node_types"), ("head_node", "worker_nodes"))


@dataclass(frozen=True)
class Finding:
    """One problem in a deployment file.

    Attributes:
        file: the file, as given.
        item: the deployment's name, or the part of the manifest (``head``, ``worker group NAME``; ``-``: the file).
        field: the field at fault, as a dotted path (``parameters.seed``, ``schedules[0].cron``).
        problem: what is wrong, in words.
    """

    file: str
    item: str
    field: str
    problem: str


def load_yaml(path: Path) -> tuple[Any, list[Finding]]:
    """The parsed document in ``path``, or ``None`` and a finding when it is missing or not YAML."""
    try:
        return yaml.safe_load(path.read_text()), []
    except (OSError, yaml.YAMLError) as exc:
        return None, [Finding(str(path), "-", "-", f"cannot read: {exc}")]


def load_mapping(path: Path) -> tuple[dict[str, Any], list[Finding]]:
    """The YAML mapping in ``path``, or ``{}`` and the finding saying why there is none (missing, not YAML, not a
    mapping)."""
    spec, found = load_yaml(path)
    if found:
        return {}, found
    if not isinstance(spec, dict):
        return {}, [Finding(str(path), "-", "-", "not a mapping")]
    return spec, []


def _is_template(value: Any) -> bool:
    """Whether ``value`` is a Prefect template (``{{ $ENV }}``, ``{{ prefect.variables.x }}``): set at deploy time."""
    return isinstance(value, str) and value.strip().startswith("{{") and value.strip().endswith("}}")


def _matches(value: Any, annotation: Any) -> bool | None:
    """Whether ``value`` (parsed YAML) has the ``annotation`` type; ``None`` when that is not checkable here
    (dataclasses, models and other annotations Prefect coerces itself)."""
    origin = typing.get_origin(annotation)
    if origin in (typing.Union, types.UnionType):
        verdicts = [_matches(value, arg) for arg in typing.get_args(annotation)]
        return None if None in verdicts and not any(verdicts) else any(v is not False for v in verdicts)
    if annotation is type(None):
        return value is None
    if annotation is bool:
        return isinstance(value, bool)
    if annotation is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if annotation is float:
        return isinstance(value, (int, float)) and not isinstance(value, bool)
    if annotation is str:
        return isinstance(value, str)
    if annotation is list or origin is list:
        if not isinstance(value, list):
            return False
        item = (typing.get_args(annotation) or (Any,))[0]
        return item is Any or all(_matches(v, item) is not False for v in value)
    return None


def _check_parameters(flow: Any, parameters: Mapping[str, Any], finding: Callable[[str, str], Finding]
                      ) -> list[Finding]:
    """The deployment's ``parameters`` against the flow function's signature and annotations."""
    signature = inspect.signature(flow.fn)
    try:
        hints = typing.get_type_hints(flow.fn)
    except (NameError, TypeError):  # an annotation that does not resolve: names are still checked
        hints = {}
    accepted = signature.parameters
    found = [finding(f"parameters.{name}", f"{flow.fn.__name__} has no parameter {name!r}")
             for name in parameters if name not in accepted]
    found += [finding(f"parameters.{name}", f"required by {flow.fn.__name__} and not given")
              for name, p in accepted.items()
              if p.default is inspect.Parameter.empty and p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD)
              and name not in parameters]
    for name, value in parameters.items():
        if name in accepted and name in hints and not _is_template(value) and _matches(value, hints[name]) is False:
            found.append(finding(f"parameters.{name}", f"{value!r} is not {_type_name(hints[name])}"))
    return found


def _type_name(annotation: Any) -> str:
    return annotation.__name__ if isinstance(annotation, type) else str(annotation)


def _load_flow(entrypoint: str, root: Path) -> tuple[Any, str]:
    """The flow at ``entrypoint`` (``path.py:function``, the path relative to ``root``), or ``None`` and why not."""
    from prefect.flows import Flow, load_flow_from_entrypoint

    path, sep, name = entrypoint.rpartition(":")
    if not sep or not path.endswith(".py"):
        return None, f"{entrypoint!r} is not PATH.py:FLOW"
    if not (root / path).is_file():
        return None, f"no file {path!r} under {root}"
    try:
        flow: Any = load_flow_from_entrypoint(f"{root / path}:{name}", use_placeholder_flow=False)
    except Exception as exc:  # noqa: BLE001 -- any import failure of the user's module is the finding
        return None, f"does not load: {type(exc).__name__}: {exc}"
    return (flow, "") if isinstance(flow, Flow) else (None, f"{name!r} is not a flow")


def _check_mining_configs(parameters: Mapping[str, Any], root: Path, finding: Callable[[str, str], Finding]
                          ) -> list[Finding]:
    """Each mining configuration file the ``parameters`` name (:data:`MINING_CONFIG_PARAMETERS`, relative to
    ``root``) reads and validates; a finding quotes the file's own error (its field and value)."""
    from tasks.mining_config import MiningConfigError, load_mining_config

    found = []
    for name in MINING_CONFIG_PARAMETERS:
        value = parameters.get(name)
        if not isinstance(value, str) or _is_template(value):
            continue
        try:
            load_mining_config(root / value)
        except MiningConfigError as exc:
            found.append(finding(f"parameters.{name}", str(exc)))
    return found


def _check_schedules(schedules: Any, finding: Callable[[str, str], Finding]) -> list[Finding]:
    """Each ``cron`` schedule parses as Prefect parses it (``CronSchedule``: croniter and the time zone)."""
    from prefect.client.schemas.schedules import CronSchedule
    from pydantic import ValidationError

    if schedules is None:
        return []
    if not isinstance(schedules, list):
        return [finding("schedules", "is not a list")]
    found = []
    for k, schedule in enumerate(schedules):
        if not isinstance(schedule, dict) or "cron" not in schedule:
            continue  # interval and rrule schedules are left to Prefect
        try:
            CronSchedule(cron=schedule["cron"], timezone=schedule.get("timezone"))
        except ValidationError as exc:
            problems = "; ".join(str(e["msg"]) for e in exc.errors())
            found.append(finding(f"schedules[{k}].cron", problems))
    return found


def _work_pool_names(spec: Mapping[str, Any]) -> set[str] | None:
    """The work pools the file declares (``work_pools:`` list of ``name:`` entries), ``None`` when it declares none."""
    pools = spec.get("work_pools")
    if not isinstance(pools, list):
        return None
    return {p["name"] for p in pools if isinstance(p, dict) and "name" in p}


def check_deployment(deployment: Mapping[str, Any], file: str, root: Path, pools: set[str] | None) -> list[Finding]:
    """One entry of ``deployments:``: its entry point, parameters, schedules and work pool."""
    item = str(deployment.get("name", "(unnamed)"))

    def finding(field: str, problem: str) -> Finding:
        return Finding(file, item, field, problem)

    found = [] if "name" in deployment else [finding("name", "missing")]
    parameters = deployment.get("parameters") or {}
    if not isinstance(parameters, dict):
        found.append(finding("parameters", "is not a mapping"))
        parameters = {}
    entrypoint = deployment.get("entrypoint")
    if not isinstance(entrypoint, str):
        found.append(finding("entrypoint", "missing"))
    else:
        flow, why = _load_flow(entrypoint, root)
        found += [finding("entrypoint", why)] if flow is None else _check_parameters(flow, parameters, finding)
    found += _check_mining_configs(parameters, root, finding)
    found += _check_schedules(deployment.get("schedules"), finding)
    pool = (deployment.get("work_pool") or {}).get("name")
    if pools is not None and pool is not None and not _is_template(pool) and pool not in pools:
        found.append(finding("work_pool.name", f"{pool!r} is not among the file's work_pools ({sorted(pools)})"))
    return found


def check_prefect_file(path: Path, root: Path | None = None) -> list[Finding]:
    """A ``prefect.yaml``: every deployment, entry points relative to ``root`` (default the working directory, as
    ``prefect deploy`` resolves them: run it from the repository root)."""
    spec, found = load_yaml(path)
    if found:
        return found
    file = str(path)
    if not isinstance(spec, dict) or not isinstance(spec.get("deployments"), list) or not spec["deployments"]:
        return [Finding(file, "-", "deployments", "no list of deployments")]
    root = root or Path.cwd()
    pools = _work_pool_names(spec)
    for deployment in spec["deployments"]:
        if not isinstance(deployment, dict):
            found.append(Finding(file, "-", "deployments", f"{deployment!r} is not a mapping"))
            continue
        found += check_deployment(deployment, file, root, pools)
    return found


#: What makes ``ray start --head`` run the autoscaler, which is what starts the worker nodes of a ``ray up`` cluster.
RAY_AUTOSCALER_FLAG = "--autoscaling-config"


def _ray_launcher_findings(spec: dict[str, Any], file: str) -> list[Finding]:
    """What ``ray up`` itself refuses before it contacts any machine: its preparation of the config (defaults, a
    local provider's machine list) and its JSON schema (``ray.autoscaler``; nothing when Ray's cluster launcher or
    its ``jsonschema`` is not installed)."""
    try:
        from ray.autoscaler._private.util import prepare_config, validate_config
    except ImportError:
        return []
    try:
        validate_config(prepare_config(copy.deepcopy(spec)))
    except ImportError:
        return []
    except Exception as exc:  # noqa: BLE001 -- whatever Ray's own validation raises is the finding
        field = ".".join(str(part) for part in getattr(exc, "absolute_path", ())) or "-"
        return [Finding(file, "-", field, f"`ray up` refuses it: {getattr(exc, 'message', None) or exc}")]
    return []


def _check_ray_commands(spec: dict[str, Any], file: str) -> list[Finding]:
    """The head's start commands, when given, start the autoscaler (without it ``ray up`` never starts a worker
    node; Ray's own default commands do)."""
    commands = spec.get("head_start_ray_commands")
    if not isinstance(commands, list) or any(RAY_AUTOSCALER_FLAG in str(c) for c in commands):
        return []
    return [Finding(file, "head", "head_start_ray_commands",
                    f"no `ray start --head ... {RAY_AUTOSCALER_FLAG}=~/ray_bootstrap_config.yaml`: without the "
                    "autoscaler the head never starts the worker nodes")]


def check_ray_cluster(path: Path) -> list[Finding]:
    """A ``ray up`` cluster YAML: a name, a provider with a type, and a head/worker layout (node types or the older
    head/worker spec; a ``local`` provider lists its machines instead); when those are there, what ``ray up``'s own
    validation refuses, and head start commands that would start no worker node."""
    spec, found = load_mapping(path)
    if found:
        return found
    file = str(path)
    found = [Finding(file, "-", key, "missing") for key in RAY_REQUIRED if not spec.get(key)]
    provider = spec.get("provider")
    if isinstance(provider, dict) and not provider.get("type"):
        found.append(Finding(file, "provider", "provider.type", "missing"))
    if isinstance(provider, dict) and provider.get("type") == "local":
        found += [Finding(file, "provider", f"provider.{key}", "missing (a local cluster lists its machines)")
                  for key in ("head_ip", "worker_ips") if key not in provider]
    elif not any(all(key in spec for key in layout) for layout in RAY_NODE_LAYOUTS):
        found.append(Finding(file, "-", "head_node_type", "neither head_node_type + available_node_types nor "
                             "head_node + worker_nodes"))
    if not found:
        found = _ray_launcher_findings(spec, file)
    return found + _check_ray_commands(spec, file)


def _check_pod(template: Any, file: str, item: str, field: str) -> list[Finding]:
    """A group's ``template.spec.containers``: at least one, each with an image and resources."""
    containers = ((template or {}).get("spec") or {}).get("containers") if isinstance(template, dict) else None
    if not isinstance(containers, list) or not containers:
        return [Finding(file, item, f"{field}.template.spec.containers", "missing")]
    found = []
    for k, container in enumerate(containers):
        where = f"{field}.template.spec.containers[{k}]"
        if not isinstance(container, dict):
            found.append(Finding(file, item, where, "is not a mapping"))
            continue
        if not container.get("image"):
            found.append(Finding(file, item, f"{where}.image", "missing"))
        resources = container.get("resources") or {}
        if not (resources.get("requests") or resources.get("limits")):
            found.append(Finding(file, item, f"{where}.resources", "no requests or limits"))
    return found


def check_kuberay(path: Path) -> list[Finding]:
    """A KubeRay manifest: ``apiVersion: ray.io/v1``, ``kind: RayCluster``, a ``headGroupSpec`` and
    ``workerGroupSpecs``, every container with an image and resources."""
    spec, found = load_mapping(path)
    if found:
        return found
    file = str(path)
    if spec.get("apiVersion") != "ray.io/v1":
        found.append(Finding(file, "-", "apiVersion", f"{spec.get('apiVersion')!r} is not 'ray.io/v1'"))
    if spec.get("kind") != "RayCluster":
        found.append(Finding(file, "-", "kind", f"{spec.get('kind')!r} is not 'RayCluster'"))
    body: dict[str, Any] = spec["spec"] if isinstance(spec.get("spec"), dict) else {}
    head = body.get("headGroupSpec")
    if not isinstance(head, dict):
        found.append(Finding(file, "head", "spec.headGroupSpec", "missing"))
    else:
        found += _check_pod(head.get("template"), file, "head", "spec.headGroupSpec")
    workers = body.get("workerGroupSpecs")
    if not isinstance(workers, list) or not workers:
        return [*found, Finding(file, "workers", "spec.workerGroupSpecs", "missing")]
    for k, group in enumerate(workers):
        name = f"worker group {group.get('groupName', k)}" if isinstance(group, dict) else f"worker group {k}"
        template = group.get("template") if isinstance(group, dict) else None
        found += _check_pod(template, file, name, f"spec.workerGroupSpecs[{k}]")
    return found


def check_deploy_files(prefect: Path | None, ray: Path | None, kuberay: Path | None,
                       root: Path | None = None) -> list[Finding]:
    """Every given file's findings, in that order (``None``: that file is not checked)."""
    found: list[Finding] = []
    if prefect is not None:
        found += check_prefect_file(prefect, root)
    if ray is not None:
        found += check_ray_cluster(ray)
    if kuberay is not None:
        found += check_kuberay(kuberay)
    return found
