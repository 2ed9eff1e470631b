"""The base of every configuration model, and the one way a model reports a cross-field problem."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel, ConfigDict, GetCoreSchemaHandler
from pydantic_core import CoreSchema, PydanticCustomError, core_schema


def _not_text_or_bool(value: Any) -> Any:
    if isinstance(value, str | bool):
        raise PydanticCustomError("number_type", "Input should be a number")
    return value


def _a_bool(value: Any) -> Any:
    if isinstance(value, str | int | float) and not isinstance(value, bool):
        raise PydanticCustomError("bool_type", "Input should be a valid boolean")
    return value


# Where a core schema nests further schemas (models, unions, lists, tuples, defaults, validators).
_NESTED = ("schema", "items_schema", "choices", "fields", "definitions", "keys_schema", "values_schema", "steps")


def _strict_scalars(schema: CoreSchema, owner: type) -> CoreSchema:
    """`schema` with every number refusing text and booleans, and every boolean refusing text and numbers.

    Pydantic's strict mode would do this but also refuse a YAML list for a tuple, so the check goes in
    front of each number and boolean instead. Other models' schemas are left alone: each model strictens
    its own when it is built.
    """
    kind = schema.get("type")
    if kind in ("float", "int"):
        return core_schema.no_info_before_validator_function(_not_text_or_bool, schema)
    if kind == "bool":
        return core_schema.no_info_before_validator_function(_a_bool, schema)
    if kind == "model" and schema.get("cls") is not owner:
        return schema
    for key in _NESTED:
        nested = schema.get(key)
        if isinstance(nested, dict) and "type" in nested:
            schema[key] = _strict_scalars(nested, owner)
        elif isinstance(nested, dict):  # fields by name, or a tagged union's choices by tag
            schema[key] = {name: _strict_scalars(item, owner) for name, item in nested.items()}
        elif isinstance(nested, list):  # union choices, plain or (schema, label), and definitions
            schema[key] = [
                (_strict_scalars(item[0], owner), item[1]) if isinstance(item, tuple) else _strict_scalars(item, owner)
                for item in nested
            ]
    return schema


class Model(BaseModel):
    """Frozen, strict about unknown keys, no NaN or infinity; field docstrings become schema docs.

    Numbers and booleans are strict as well (`_strict_scalars`): YAML's ``'320'`` is text and ``true`` a
    boolean, and neither is taken for a number; ``'yes'`` or ``1`` is not taken for true.
    """

    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        allow_inf_nan=False,
        use_attribute_docstrings=True,
        validate_default=True,
    )

    @classmethod
    def __get_pydantic_core_schema__(cls, source: type[BaseModel], handler: GetCoreSchemaHandler) -> CoreSchema:
        return _strict_scalars(handler(source), cls)


def invalid(subpath: str, message: str) -> PydanticCustomError:
    """A validation error about the key at `subpath` below the model that raises it.

    `subpath` uses dots and ``[i]`` like the messages do (``lens.zoom_table[2].f_number``); the YAML
    layer turns it into a file location. `message` continues the key path: ``must be ≥ 0.5, got 0.3``.
    """
    return PydanticCustomError("camgen", "{message}", {"message": message, "subpath": subpath})


@dataclass(frozen=True)
class Why:
    """Where a field's bounds come from, for the error when a value breaks them.

    Put it in `Annotated` beside the `Field` bounds: ``Annotated[float, Field(gt=0, le=2000), Why("…")]``.
    The bounds stay pydantic's own (the JSON Schema and `camgen.fit` read them); the message becomes
    ``lens.focal_length_mm must be ≤ 2000, got 1e+06; <text>``. The text states the allowed range in
    words, with its unit and source.
    """

    text: str


def parse_subpath(subpath: str) -> tuple[str | int, ...]:
    """``a.b[2].c`` → ``("a", "b", 2, "c")``."""
    parts: list[str | int] = []
    for token in subpath.replace("[", ".[").split("."):
        if not token:
            continue
        if token.startswith("[") and token.endswith("]"):
            parts.append(int(token[1:-1]))
        else:
            parts.append(token)
    return tuple(parts)
