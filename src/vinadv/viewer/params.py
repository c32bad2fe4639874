"""The viewer's query and form parameters: validated here, a malformed or unknown one a 400 naming it; the CSRF token
and the annotator's name."""

from __future__ import annotations

import math
import re
import secrets
from urllib.parse import urlencode, urlsplit

from flask import request, session
from werkzeug.exceptions import BadRequest, Forbidden

from vinadv.store import LABELS
from vinadv.vocabulary import HARMS

DEFAULT_PAGE_SIZE = 50
MAX_PAGE_SIZE = 500
ANNOTATOR_COOKIE = "vinadv_annotator"
DEFAULT_ANNOTATOR = "anonymous"
MAX_ID = 2**63 - 1
#: the filters of the pair grid and the pair page (kept in the links between them), and the grid's sort
FILTER_PARAMS = ("label", "attack", "source", "harm", "min_regret", "min_effort", "sort")
GRID_PARAMS = frozenset(FILTER_PARAMS + ("after", "before", "size"))
#: the grid's sorts (`vinadv.store.paging.SORTS`) as its menu names them
SORT_NAMES = {
    "pair": "pair index",
    "label": "label",
    "harm": "harm (harmful first)",
    "regret": "regret added (largest first)",
    "effort": "effort ratio (largest first)",
}
_ANNOTATOR_RE = re.compile(r"^[\w .@+\-]{1,64}$")


def only_params(allowed) -> None:
    unknown = sorted(set(request.args) - set(allowed))
    if unknown:
        raise BadRequest(
            f"unknown query parameter {unknown[0]!r}"
            + (f"; allowed: {', '.join(sorted(allowed))}" if allowed else "; this page takes none")
        )
    for name in request.args:
        if len(request.args.getlist(name)) > 1:
            raise BadRequest(f"query parameter {name!r} given more than once")


def int_param(name: str, *, default: int | None = None, required: bool = False) -> int | None:
    raw = request.args.get(name)
    if raw is None or raw == "":
        if required:
            raise BadRequest(f"query parameter {name!r} is required")
        return default
    if not raw.isascii() or not raw.isdigit() or len(raw) > 19 or int(raw) > MAX_ID:
        raise BadRequest(f"{name}: expected a non-negative integer, got {raw[:40]!r}")
    return int(raw)


def _float_param(name: str) -> float | None:
    raw = request.args.get(name) or None
    if raw is None:
        return None
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or len(raw) > 40:
        raise BadRequest(f"{name}: expected a number, got {raw[:40]!r}")
    return value


def filters(sorts: tuple[str, ...]) -> dict:
    """The grid's filters and sort from the query string; `sorts`: the sorts the run offers."""
    label = request.args.get("label") or None
    if label is not None and label not in LABELS:
        raise BadRequest(f"label: {label[:40]!r} is not one of {'|'.join(LABELS)}")
    raw_attack = request.args.get("attack") or None
    attack = None
    if raw_attack is not None:
        lowered = raw_attack.lower()
        if lowered in ("1", "true", "yes"):
            attack = True
        elif lowered in ("0", "false", "no"):
            attack = False
        else:
            raise BadRequest(f"attack: expected yes or no, got {raw_attack[:40]!r}")
    source = request.args.get("source") or None
    if source is not None and (len(source) > 255 or not source.isprintable()):
        raise BadRequest("source: expected a label source name of at most 255 printable characters")
    harm = request.args.get("harm") or None
    if harm is not None and harm not in HARMS:
        raise BadRequest(f"harm: {harm[:40]!r} is not one of {'|'.join(HARMS)}")
    sort = request.args.get("sort") or "pair"
    if sort not in sorts:
        raise BadRequest(f"sort: {sort[:40]!r} is not one of {'|'.join(sorts)}")
    min_effort = _float_param("min_effort")
    if min_effort is not None and "effort" not in sorts:
        raise BadRequest("min_effort: this run's pairs hold no search effort (no expanded cells)")
    return {
        "label": label,
        "attack": attack,
        "source": source,
        "harm": harm,
        "min_regret": _float_param("min_regret"),
        "min_effort": min_effort,
        "sort": sort,
    }


def store_filters(f: dict) -> dict:
    """The filters as `Store.page_pairs` takes them."""
    return dict(
        label=f["label"],
        attack=f["attack"],
        label_source=f["source"],
        harm=f["harm"],
        min_regret=f["min_regret"],
        min_effort=f["min_effort"],
        sort=f["sort"],
    )


def filter_query(f: dict) -> str:
    query = _filter_items(f)
    return f"?{urlencode(query)}" if query else ""


def page_query(f: dict, size: int) -> str:
    """Filters and page size as a query string prefix that ends ready for `after=`/`before=`."""
    query = _filter_items(f)
    if size != DEFAULT_PAGE_SIZE:
        query["size"] = size
    return "?" + (urlencode(query) + "&" if query else "")


def _filter_items(f: dict) -> dict:
    query = {}
    for name in ("label", "source", "harm"):
        if f[name] is not None:
            query[name] = f[name]
    if f["attack"] is not None:
        query["attack"] = "yes" if f["attack"] else "no"
    for name in ("min_regret", "min_effort"):
        if f[name] is not None:
            query[name] = f"{f[name]:g}"
    if f["sort"] != "pair":
        query["sort"] = f["sort"]
    return query


def csrf_token() -> str:
    """The session's CSRF token (made on first use)."""
    token = session.get("csrf")
    if not token:
        token = session["csrf"] = secrets.token_urlsafe(32)
    return token


def check_csrf() -> None:
    origin = request.headers.get("Origin")
    if origin and origin != "null" and urlsplit(origin).netloc != request.host:
        raise Forbidden(f"cross-origin POST from {origin[:80]!r} refused")
    expected = session.get("csrf")
    given = request.form.get("csrf_token", "")
    if not expected or not given or not secrets.compare_digest(str(expected), given):
        raise Forbidden("missing or invalid CSRF token: reload the page and label again")


def valid_annotator(raw: str) -> str:
    name = (raw or "").strip() or DEFAULT_ANNOTATOR
    if not _ANNOTATOR_RE.match(name):
        raise BadRequest("annotator: 1 to 64 letters, digits, spaces or . @ + - _")
    return name


def annotator_from_cookie() -> str:
    raw = request.cookies.get(ANNOTATOR_COOKIE, "").strip()
    return raw if _ANNOTATOR_RE.match(raw) else DEFAULT_ANNOTATOR
