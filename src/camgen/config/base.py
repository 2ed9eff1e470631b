"""The base of every configuration model, and the one way a model reports a cross-field problem."""

from __future__ import annotations

from pydantic import BaseModel, ConfigDict
from pydantic_core import PydanticCustomError


class Model(BaseModel):
    """Frozen, strict about unknown keys, no NaN or infinity; field docstrings become schema docs."""

    model_config = ConfigDict(
        extra="forbid",
        frozen=True,
        allow_inf_nan=False,
        use_attribute_docstrings=True,
        validate_default=True,
    )


def invalid(subpath: str, message: str) -> PydanticCustomError:
    """A validation error about the key at `subpath` below the model that raises it.

    `subpath` uses dots and ``[i]`` like the messages do (``lens.zoom_table[2].f_number``); the YAML
    layer turns it into a file location. `message` continues the key path: ``must be ≥ 0.5, got 0.3``.
    """
    return PydanticCustomError("camgen", "{message}", {"message": message, "subpath": subpath})


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
