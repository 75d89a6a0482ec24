"""The versioned mining configuration: what a scheduled run mines, kept in the repository as a YAML file.

    loaded = load_mining_config("deploy/mining/nightly.yaml")     # MiningConfigError naming the file and field
    loaded.config.mining.scenarios_per_log, loaded.config.searches.queries, loaded.config.vlm.client
    loaded.source                      # ConfigSource(path, version, key): what a run record keeps
    mining_config_key(loaded.config)   # the content key (64 hex digits) of what the file asks for

Format, version 1 (every section and field but ``version`` is optional; unknown fields are errors)::

    version: 1
    description: free text, not part of the content key
    searches:                          # saved searches: their hits seed the mining loop (tasks.search.search_seeds)
      queries: ["a pedestrian crossing in front of us while a car turns"]
      variants_per_hit: 2              # seed proposals per hit subject (mining.search_seeds.hit_variants)
      only_hits: false                 # true: mine only the logs where a saved search holds
    mining:
      scenarios_per_log: 3             # accepted scenarios wanted per log (K)
      categories: [add_pedestrian, modify_vehicle]   # edit categories (empty or left out: all six)
      max_attempts: 3                  # attempts per proposal
      seed: 0                          # the run's seed (and the rule-based client's)
    vlm:
      client: rule                     # rule (built-in, offline) or openai (an OpenAI-compatible endpoint)
      endpoint: http://127.0.0.1:8000/v1   # openai only; left out: SIMSPLAT_VLM_URL
      model: qwen2-vl-7b               # openai only; left out: SIMSPLAT_VLM_MODEL
      api_key_env: SIMSPLAT_VLM_API_KEY    # the NAME of the variable holding the key (never the key itself)
    dataset:                           # where the accepted scenarios are appended, one increment per run
      name: nightly
      formats: [womd, scenarionet, parquet]
      out: null                        # a folder or URI; null: the store's datasets/ (a run's --export wins)

The content key hashes the parsed contents (comments, formatting and ``description`` left out), so a file that
asks for the same mining has the same key wherever it lies; a change of any setting changes it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from simsplat_core.mining.rule_proposals import selected_categories
from simsplat_core.search.describe import parse_description
from simsplat_core.vlm.openai_chat import ENV_API_KEY, OpenAIChatConfig
from storage.dataset_formats import FORMATS
from storage.datasets import check_dataset_name
from storage.keys import content_key

#: The format version this module writes about; files of other versions are refused.
FORMAT_VERSION = 1
SUPPORTED_VERSIONS: tuple[int, ...] = (1,)
#: Fields left out of the content key (they do not change what is mined).
UNKEYED_FIELDS = frozenset({"description"})
_ENV_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_LONGEST_VALUE = 80
#: Fields whose value an error never repeats: what was put there may be a secret (a key instead of its name).
_UNSHOWN = frozenset({("vlm",), ("vlm", "api_key_env")})


class MiningConfigError(ValueError):
    """A mining configuration file that cannot be used.

    Attributes:
        file: the file, as given; field: the field at fault as a dotted path (``mining.categories[1]``; ``-``: the
            file itself); problem: what is wrong, in words.
    """

    def __init__(self, file: str, field: str, problem: str) -> None:
        super().__init__(f"{file}: {field}: {problem}" if field != "-" else f"{file}: {problem}")
        self.file = file
        self.field = field
        self.problem = problem


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class SavedSearches(_Section):
    """Saved searches: free-form descriptions whose hits seed the loop (variants of what each hit's subject does)."""

    queries: tuple[str, ...] = ()
    variants_per_hit: Annotated[int, Field(ge=1)] = 2
    only_hits: bool = False

    @field_validator("queries")
    @classmethod
    def _parses(cls, queries: tuple[str, ...]) -> tuple[str, ...]:
        for query in queries:
            parse_description(query)  # ValueError for a blank one
        return tuple(q.strip() for q in queries)


class MiningSection(_Section):
    """What to mine per log."""

    scenarios_per_log: Annotated[int, Field(ge=1)] = 3
    categories: tuple[str, ...] = ()
    max_attempts: Annotated[int, Field(ge=1)] = 3
    seed: int = 0

    @field_validator("categories")
    @classmethod
    def _known_categories(cls, categories: tuple[str, ...]) -> tuple[str, ...]:
        selected_categories(categories)
        if len(set(categories)) != len(categories):
            raise ValueError(f"repeated categories in {list(categories)}")
        return categories


class VLMSection(_Section):
    """The mining client: the built-in rule-based one, or an OpenAI-compatible endpoint (the key by variable name)."""

    client: Literal["rule", "openai"] = "rule"
    endpoint: str | None = None
    model: str | None = None
    api_key_env: str = ENV_API_KEY

    @field_validator("endpoint")
    @classmethod
    def _http(cls, endpoint: str | None) -> str | None:
        if endpoint is not None and not endpoint.startswith(("http://", "https://")):
            raise ValueError("must start with http:// or https://")
        return endpoint

    @field_validator("api_key_env")
    @classmethod
    def _variable_name(cls, name: str) -> str:
        if not _ENV_NAME.match(name):
            raise ValueError("must be the name of an environment variable (letters, digits, '_'), not a key")
        return name

    @model_validator(mode="after")
    def _endpoint_only_for_openai(self) -> VLMSection:
        if self.client == "rule" and (self.endpoint is not None or self.model is not None):
            raise ValueError("endpoint and model are for client: openai (the rule-based client runs offline)")
        return self

    def chat_config(self) -> OpenAIChatConfig | None:
        """The OpenAI-compatible client's settings when the file names its endpoint and model (``None``: the rule
        client, or endpoint and model from ``SIMSPLAT_VLM_URL`` / ``SIMSPLAT_VLM_MODEL``)."""
        if self.client != "openai" or self.endpoint is None or self.model is None:
            return None
        return OpenAIChatConfig(base_url=self.endpoint, model=self.model, api_key_env=self.api_key_env)


class DatasetSection(_Section):
    """The dataset the run's accepted scenarios are appended to."""

    name: str
    formats: tuple[str, ...] = FORMATS
    out: str | None = None

    @field_validator("name")
    @classmethod
    def _safe_name(cls, name: str) -> str:
        return check_dataset_name(name)

    @field_validator("formats")
    @classmethod
    def _known_formats(cls, formats: tuple[str, ...]) -> tuple[str, ...]:
        unknown = [f for f in formats if f not in FORMATS]
        if unknown or not formats:
            raise ValueError(f"{unknown or 'none given'}: choose from {list(FORMATS)}")
        return formats


class MiningConfigFile(_Section):
    """A parsed mining configuration (module docstring)."""

    version: int
    description: str = ""
    searches: SavedSearches = SavedSearches()
    mining: MiningSection = MiningSection()
    vlm: VLMSection = VLMSection()
    dataset: DatasetSection | None = None


@dataclass(frozen=True)
class ConfigSource:
    """Which configuration a run used (kept in its run record).

    Attributes:
        path: the file, as given; version: its format version; key: its content key (:func:`mining_config_key`).
    """

    path: str
    version: int
    key: str


@dataclass(frozen=True)
class LoadedMiningConfig:
    """A mining configuration file read and checked: its contents and where they came from."""

    config: MiningConfigFile
    source: ConfigSource

    @property
    def key(self) -> str:
        return self.source.key


def mining_config_key(config: MiningConfigFile) -> str:
    """The content key (64 hex digits) of what ``config`` asks for: its parsed contents less ``description``."""
    return content_key("mining-config", config.model_dump(mode="json", exclude=set(UNKEYED_FIELDS)))


def _dotted(loc: tuple[int | str, ...]) -> str:
    path = ""
    for part in loc:
        path += f"[{part}]" if isinstance(part, int) else (f".{part}" if path else str(part))
    return path or "-"


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= _LONGEST_VALUE else text[: _LONGEST_VALUE - 1] + "…"


def _first_error(file: str, exc: ValidationError) -> MiningConfigError:
    """The first of pydantic's errors as a :class:`MiningConfigError` naming the field and the value given."""
    error = exc.errors()[0]
    loc = tuple(part for part in error["loc"] if not (isinstance(part, str) and part.startswith("function-")))
    problem = str(error["msg"]).removeprefix("Value error, ")
    if error["type"] == "extra_forbidden":
        problem = "unknown field (a typo?)"
    elif error["type"] != "missing" and "input" in error and loc not in _UNSHOWN:
        shown = _shown(error["input"])
        problem += "" if shown in problem else f" (got {shown})"
    more = len(exc.errors()) - 1
    return MiningConfigError(file, _dotted(loc), problem + (f"; and {more} more problem(s)" if more else ""))


def parse_mining_config(data: Any, file: str = "<mining config>") -> MiningConfigFile:
    """``data`` (parsed YAML) checked as a mining configuration; ``file`` names it in errors.

    Raises:
        MiningConfigError: not a mapping, no or an unsupported ``version``, or a bad field (named, with its value).
    """
    if not isinstance(data, dict):
        raise MiningConfigError(file, "-", f"not a mapping of settings (got {type(data).__name__})")
    version = data.get("version")
    if "version" not in data:
        raise MiningConfigError(file, "version", f"missing (this code reads version {FORMAT_VERSION})")
    if isinstance(version, bool) or version not in SUPPORTED_VERSIONS:
        raise MiningConfigError(file, "version", f"{_shown(version)} is not a supported version "
                                f"({list(SUPPORTED_VERSIONS)})")
    try:
        return MiningConfigFile.model_validate(data)
    except ValidationError as exc:
        raise _first_error(file, exc) from None


def load_mining_config(path: str | Path) -> LoadedMiningConfig:
    """The mining configuration in the YAML file ``path`` (module docstring), with its source for the run record.

    Raises:
        MiningConfigError: the file is missing, not YAML, or not a valid configuration (naming the field).
    """
    file = str(path)
    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except OSError as exc:
        raise MiningConfigError(file, "-", f"cannot read: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise MiningConfigError(file, "-", f"not YAML: {exc}") from None
    config = parse_mining_config(data, file)
    return LoadedMiningConfig(config, ConfigSource(file, config.version, mining_config_key(config)))


__all__ = ["FORMAT_VERSION", "SUPPORTED_VERSIONS", "ConfigSource", "DatasetSection", "LoadedMiningConfig",
           "MiningConfigError", "MiningConfigFile", "MiningSection", "SavedSearches", "VLMSection",
           "load_mining_config", "mining_config_key", "parse_mining_config"]
