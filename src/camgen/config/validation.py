"""Turn pydantic validation errors into located, readable `Problem`s.

``scenes/lot.yaml:23:7: cameras[1].ptz.pan_max_deg_s must be > 0, got -30``
"""

from __future__ import annotations

import difflib
import re
import types
import typing
from typing import Any

from pydantic import BaseModel, ValidationError

from camgen.config.base import Why, parse_subpath
from camgen.config.yaml_source import KeyPath, YamlDocument
from camgen.errors import ConfigError, Problem


def show_value(value: Any, limit: int = 60) -> str:
    """A value as the user wrote it in YAML, shortened."""
    if isinstance(value, str):
        text = repr(value)
    elif value is None:
        text = "null"
    elif isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, float):
        text = f"{value:g}"
    elif isinstance(value, dict):
        text = "{" + ", ".join(f"{k}: {show_value(v, 20)}" for k, v in value.items()) + "}"
    elif isinstance(value, list | tuple):
        text = "[" + ", ".join(show_value(v, 20) for v in value) + "]"
    else:
        text = str(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def _data_path(loc: tuple, data: Any) -> KeyPath:
    """Map a pydantic `loc` onto the user's data, dropping union tags pydantic inserts."""
    path: list[str | int] = []
    node = data
    for i, part in enumerate(loc):
        last = i == len(loc) - 1
        if isinstance(node, dict) and part in node:
            node = node[part]
            path.append(part)
        elif isinstance(node, list) and isinstance(part, int) and 0 <= part < len(node):
            node = node[part]
            path.append(part)
        elif isinstance(node, dict) and part == node.get("type"):
            continue  # the tag of a discriminated union, also when a model validator's error ends on it
        elif isinstance(part, str) and not isinstance(node, dict):
            continue  # the label of a union's form ('list[constrained-int]') below a list or a value
        elif last or not isinstance(node, dict):
            path.append(part)
        # else: a discriminator tag such as 'box' in ('meshes', 0, 'box', 'size_m'): not user data
    return tuple(path)


def _unwrap(annotation: Any) -> list[Any]:
    """The candidate types behind Optional/Union/Annotated."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return _unwrap(typing.get_args(annotation)[0])
    if origin in (typing.Union, types.UnionType):
        out = []
        for arg in typing.get_args(annotation):
            out += _unwrap(arg)
        return out
    return [annotation]


def _model_at(root: type[BaseModel], path: KeyPath, data: Any) -> type[BaseModel] | None:
    """The model class whose keys live at `path` in `data` (resolving unions by their `type` key)."""
    candidates: list[Any] = [root]
    for part in path:
        nxt: list[Any] = []
        for candidate in candidates:
            for t in _unwrap(candidate):
                origin = typing.get_origin(t)
                if isinstance(part, int) and origin in (list, tuple):
                    nxt.append(typing.get_args(t)[0])
                elif isinstance(part, str) and isinstance(t, type) and issubclass(t, BaseModel):
                    for name, info in t.model_fields.items():
                        if part in (name, info.alias):
                            nxt.append(info.annotation)
        candidates = nxt
    models = [t for c in candidates for t in _unwrap(c) if isinstance(t, type) and issubclass(t, BaseModel)]
    node = _value_at(data, path)
    if len(models) > 1 and isinstance(node, dict):
        tagged = [m for m in models if "type" in m.model_fields and _literal_matches(m, node.get("type"))]
        models = tagged or models
    return models[0] if models else None


def _has(node: Any, part: str | int) -> bool:
    if isinstance(node, dict):
        return part in node
    return isinstance(part, int) and 0 <= part < len(node)


def _literal_matches(model: type[BaseModel], value: Any) -> bool:
    return value in typing.get_args(model.model_fields["type"].annotation)


def _value_at(data: Any, path: KeyPath) -> Any:
    node = data
    for part in path:
        if not isinstance(node, dict | list) or not _has(node, part):
            return None
        node = node[part]
    return node


def _tuple_length(root: type[BaseModel], path: KeyPath, data: Any) -> int | None:
    """Length of the fixed-length tuple field at `path`, if it is one."""
    if not path or not isinstance(path[-1], str):
        return None
    parent = _model_at(root, path[:-1], data)
    if parent is None:
        return None
    for name, info in parent.model_fields.items():
        if path[-1] in (name, info.alias):
            for t in _unwrap(info.annotation):
                args = typing.get_args(t)
                if typing.get_origin(t) is tuple and args and args[-1] is not Ellipsis:
                    return len(args)
    return None


def _why(root: type[BaseModel], path: KeyPath, data: Any) -> str | None:
    """The `Why` beside the bounds of the field (or list item) at `path`, if it has one."""
    items = len(path) - next((i for i, part in enumerate(reversed(path)) if isinstance(part, str)), len(path))
    field_path, indices = path[:items], path[items:]
    parent = _model_at(root, field_path[:-1], data) if field_path else None
    info = next((i for n, i in (parent.model_fields.items() if parent else ()) if field_path[-1] in (n, i.alias)), None)
    if info is None:
        return None
    metadata, annotation = list(info.metadata), info.annotation
    for index in indices:
        candidates = [t for t in _unwrap(annotation) if typing.get_origin(t) in (list, tuple)]
        if not candidates:
            return None
        args = typing.get_args(candidates[0])
        if typing.get_origin(candidates[0]) is list or args[-1] is Ellipsis:
            annotation = args[0]
        elif isinstance(index, int) and index < len(args):
            annotation = args[index]
        else:
            return None
        metadata = []
    metadata += _metadata(annotation)
    return next((m.text for m in metadata if isinstance(m, Why)), None)


def _metadata(annotation: Any) -> list[Any]:
    """The `Annotated` metadata of a type, also inside Optional/Union."""
    origin = typing.get_origin(annotation)
    if origin is typing.Annotated:
        return [*annotation.__metadata__, *_metadata(typing.get_args(annotation)[0])]
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _metadata(arg)]
    return []


def allowed_keys(model: type[BaseModel]) -> list[str]:
    return [info.alias or name for name, info in model.model_fields.items()]


def _phrase(error: dict, root: type[BaseModel], path: KeyPath, data: Any) -> str:
    kind = error["type"]
    ctx = error.get("ctx", {})
    value = error.get("input")
    got = f", got {show_value(value)}"
    if kind == "camgen":
        return ctx["message"]
    if kind == "missing":
        return "is required"
    if kind == "extra_forbidden":
        parent = _model_at(root, path[:-1], data)
        keys = allowed_keys(parent) if parent else []
        close = difflib.get_close_matches(str(path[-1]), keys, n=1, cutoff=0.6)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        listing = f"; allowed keys here: {', '.join(keys)}" if keys else ""
        return f"is not a known key{hint}{listing}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        op = {"greater_than": ">", "greater_than_equal": "≥", "less_than": "<", "less_than_equal": "≤"}[kind]
        bound = next(iter(ctx.values()))
        why = _why(root, path, data)
        return f"must be {op} {show_value(bound)}{got}" + (f"; {why}" if why else "")
    if kind == "finite_number":
        return f"must be a finite number{got}"
    if kind == "number_type" and isinstance(value, bool):
        return f"must be a number{got}: true and false are booleans, not numbers"
    if kind == "number_type" and _reads_as_number(value):
        return f"must be a number{got}, which the quotes make text; remove the quotes"
    if kind in ("number_type", "float_type", "float_parsing", "int_type", "int_parsing"):
        return f"must be a number{got}"
    if kind == "int_from_float":
        return f"must be a whole number{got}"
    if kind == "int_parsing_size":
        why = _why(root, path, data)
        return f"must be a whole number of a sensible size{got}" + (f"; {why}" if why else "")
    if kind in ("bool_type", "bool_parsing"):
        quoted = "; remove the quotes" if isinstance(value, str) and value.lower() in ("true", "false") else ""
        return f"must be true or false{got}{quoted}"
    if kind == "string_type":
        return f"must be text{got}"
    if kind in ("list_type", "tuple_type"):
        return f"must be a list{got}"
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        return f"must be a mapping of keys{got}"
    if kind in ("too_short", "too_long"):
        expected = ctx.get("min_length") if kind == "too_short" else ctx.get("max_length")
        actual = ctx.get("actual_length")
        word = "at least" if kind == "too_short" else "at most"
        why = _why(root, path, data)
        return f"must have {word} {expected} item{'s' if expected != 1 else ''}, got {actual}: {show_value(value)}" + (
            f"; {why}" if why else ""
        )
    if kind in ("string_too_short", "string_too_long"):
        return f"must be {'non-empty' if kind == 'string_too_short' else 'shorter'} text{got}"
    if kind == "string_pattern_mismatch":
        return f"must use only letters, digits, '_', '-' and '.'{got}"
    if kind == "literal_error":
        close = ""
        if isinstance(value, str):
            options = [o.strip(" '") for o in ctx.get("expected", "").replace(" or ", ", ").split(",")]
            match = difflib.get_close_matches(value, options, n=1, cutoff=0.5)
            close = f"; did you mean {match[0]!r}?" if match else ""
        return f"must be one of {ctx.get('expected')}{got}{close}"
    if kind == "union_tag_invalid":
        options = [o.strip(" '") for o in str(ctx.get("expected_tags", "")).split(",")]
        match = difflib.get_close_matches(str(ctx.get("tag")), options, n=1, cutoff=0.5)
        close = f"; did you mean {match[0]!r}?" if match else ""
        return f"must be one of {ctx.get('expected_tags')}, got {show_value(ctx.get('tag'))}{close}"
    if kind == "union_tag_not_found":
        return "is required (it selects the kind of item)"
    if kind in ("value_error", "assertion_error"):
        return str(ctx.get("error", error["msg"]))
    return f"{error['msg'][0].lower()}{error['msg'][1:]}{got}"


def _reads_as_number(text: Any) -> bool:
    try:
        float(text)
    except (TypeError, ValueError):
        return False
    return True


_KIND_OF_INPUT = {
    "list_type": "a list",
    "tuple_type": "a list",
    "dict_type": "a mapping of keys",
    "model_type": "a mapping of keys",
    "model_attributes_type": "a mapping of keys",
    "number_type": "a number",
    "float_type": "a number",
    "float_parsing": "a number",
    "int_type": "a number",
    "int_parsing": "a number",
    "string_type": "text",
    "bool_type": "true or false",
    "bool_parsing": "true or false",
}
"""Errors that say only that the input is not the kind a form of a union wants, and that kind."""


def _one_form_per_union(errors: list[dict], data: Any) -> list[dict]:
    """A union of forms (``seeds: [1, 2]`` or ``seeds: {start, count}``) that takes none reports every
    form's failure. Keep the form the input was meant for: drop the forms that failed only on the kind
    of input when another form got further into it; when none did, say the kinds allowed in one error."""
    mismatched: dict[KeyPath, list[dict]] = {}
    kept = []
    for error in errors:
        loc = tuple(error["loc"])
        if error["type"] in _KIND_OF_INPUT and len(loc) > 1 and isinstance(loc[-1], str):
            where = _data_path(loc, data)
            where = where[:-1] if where[-1:] == loc[-1:] else where
            node = _value_at(data, where)
            if not (isinstance(node, dict) and loc[-1] in node):
                mismatched.setdefault(where, []).append(error)
                continue
        kept.append(error)
    for where, forms in mismatched.items():
        if any(_data_path(tuple(e["loc"]), data)[: len(where)] == where for e in kept):
            continue
        if len(forms) == 1:
            kept += forms
            continue
        kinds = " or ".join(dict.fromkeys(_KIND_OF_INPUT[e["type"]] for e in forms))
        message = f"must be {kinds}, got {show_value(forms[0]['input'])}"
        kept.append(
            {
                **forms[0],
                "loc": tuple(forms[0]["loc"])[:-1],
                "type": "camgen",
                "ctx": {"message": message, "subpath": ""},
            }
        )
    return kept


def problems_from(exc: ValidationError, doc: YamlDocument | None, root: type[BaseModel]) -> list[Problem]:
    """One located `Problem` per pydantic error, in file order."""
    data = doc.data if doc is not None else None
    problems = []
    errors = exc.errors(include_url=False)
    if data is not None:
        errors = _one_form_per_union(errors, data)
    for error in errors:
        path = _data_path(tuple(error["loc"]), data) if data is not None else tuple(error["loc"])
        if error["type"] == "missing" and path and isinstance(path[-1], int):
            # A fixed-length list such as position_m: [x, y] — say so instead of "[2] is required".
            path = path[:-1]
            given = _value_at(data, path)
            expected = _tuple_length(root, path, data)
            count = f"{expected} items" if expected else "more items"
            error = {
                **error,
                "type": "camgen",
                "ctx": {
                    "message": f"must have {count}, got {len(given) if isinstance(given, list) else 0}: "
                    f"{show_value(given)}",
                    "subpath": "",
                },
            }
        if error["type"] == "camgen":
            path = path + parse_subpath(error["ctx"]["subpath"])
        elif error["type"] in ("union_tag_invalid", "union_tag_not_found"):
            path = (*path, error["ctx"].get("discriminator", "'type'").strip("'"))
        message = _phrase(error, root, path, data)
        problems.append(Problem(path=path, message=message, location=doc.locate(path) if doc else None))
    # A misspelt required key gives two errors (unknown key, missing key); the suggestion covers both.
    suggested = set()
    for problem in problems:
        match = re.search(r"did you mean '([^']+)'\?", problem.message)
        if match and problem.message.startswith("is not a known key"):
            suggested.add((*problem.path[:-1], match.group(1)))
    problems = [p for p in problems if not (p.message == "is required" and p.path in suggested)]
    problems.sort(key=lambda p: (p.location.file, p.location.line, p.location.column) if p.location else ("", 0, 0))
    return problems


def validate(model: type[BaseModel], doc: YamlDocument) -> Any:
    """Validate `doc` against `model`, raising a located `ConfigError` listing every problem."""
    try:
        return model.model_validate(doc.data)
    except ValidationError as exc:
        raise ConfigError(problems_from(exc, doc, model)) from None
