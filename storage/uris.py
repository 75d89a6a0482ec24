"""Object-store URIs: joining a relative path onto a URI that carries options, and keeping secrets out of them.

A store or landing location in an object store is named by a URI that ``pyarrow.fs.FileSystem.from_uri``
accepts, options included: ``s3://bucket/prefix?endpoint_override=127.0.0.1:9000&scheme=http&region=eu-west-1``.
The options follow the path, so a path below the location goes *before* the query
(``s3://bucket/prefix/logs/seq0?endpoint_override=...``): ``join_uri`` does that, and the result opens the same
filesystem again (it is what ``ArtifactStore.uri`` returns, so another store can be opened from it).

Credentials are never part of a URI: they come from the environment (``AWS_ACCESS_KEY_ID``,
``AWS_SECRET_ACCESS_KEY``, ``AWS_SESSION_TOKEN``; ``AWS_PROFILE`` and instance roles work too, through the AWS
SDK's usual chain), so every URI the pipeline prints or records is safe to show. ``reject_credentials`` refuses
a URI whose user-info or query carries them, naming the option but never its value. The endpoint may be given as
the ``endpoint_override`` option or by ``AWS_ENDPOINT_URL`` (or ``AWS_ENDPOINT_URL_S3``) in the environment,
which pyarrow honours as well.
"""

from __future__ import annotations

from urllib.parse import parse_qsl, urlsplit

#: Query options of ``pyarrow``'s S3 / GCS URIs that carry secrets (refused: set them in the environment).
SECRET_OPTIONS = frozenset({"access_key", "secret_key", "session_token", "access_token", "credential_token"})


class CredentialsInUriError(ValueError):
    """A storage URI carries credentials; they belong in the environment."""


def is_uri(location: str) -> bool:
    """Whether ``location`` is a URI (``scheme://...``) rather than a local path."""
    return "://" in location


def split_query(uri: str) -> tuple[str, str]:
    """``(uri without its query, "?query")``; the second is ``""`` when there is no query."""
    base, mark, query = uri.partition("?")
    return base, f"{mark}{query}" if mark else ""


def join_uri(uri: str, relpath: str) -> str:
    """``uri`` with the ``/``-separated ``relpath`` appended to its path, its query kept last (module docstring)."""
    if not relpath:
        return uri
    base, query = split_query(uri)
    sep = "" if base.endswith("/") or base.endswith(":") else "/"
    return f"{base}{sep}{relpath}{query}"


def split_name(location: str) -> tuple[str, str]:
    """``(parent, last name)`` of a ``/``-separated path or URI; a URI's query stays with the parent, so the parent
    opens the same filesystem (``"s3://b/p/x.png?o=1"`` -> ``("s3://b/p?o=1", "x.png")``)."""
    base, query = split_query(location) if is_uri(location) else (location, "")
    parent, _, name = base.rstrip("/").rpartition("/")
    return f"{parent}{query}" if parent else parent, name


def reject_credentials(uri: str) -> None:
    """Raise when ``uri`` carries credentials in its user-info or query (module docstring).

    Raises:
        CredentialsInUriError: naming the offending option (never its value) and the environment variables to use.
    """
    if not is_uri(uri):
        return
    parts = urlsplit(uri)
    found = sorted({key for key, _ in parse_qsl(parts.query, keep_blank_values=True)} & SECRET_OPTIONS)
    if parts.password is not None or parts.username is not None:
        found.insert(0, "user-info (user:secret@)")
    if found:
        shown = f"{parts.scheme}://{parts.hostname or ''}{parts.path}"
        raise CredentialsInUriError(
            f"{shown}: credentials in the URI ({', '.join(found)}) are not accepted, so that no log or record ever "
            "shows them; set AWS_ACCESS_KEY_ID / AWS_SECRET_ACCESS_KEY (and AWS_SESSION_TOKEN) in the environment")
