"""YAML → plain Python data, remembering where every key came from.

PyYAML's composer keeps a mark (line, column) on every node; we walk the node tree ourselves so each
key path maps to the place a user would look at. Duplicate keys are errors (PyYAML would silently keep
the last one).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from camgen.errors import ConfigError, Location, Problem
from camgen.io.files import input_file_problem

KeyPath = tuple[str | int, ...]


@dataclass(frozen=True)
class YamlDocument:
    """Parsed YAML data with the source location of every key path (`()` is the document)."""

    data: Any
    locations: dict[KeyPath, Location] = field(default_factory=dict)

    def locate(self, path: KeyPath) -> Location | None:
        """The location of `path`, or of its deepest ancestor present in the file."""
        for end in range(len(path), -1, -1):
            location = self.locations.get(tuple(path[:end]))
            if location is not None:
                return location
        return None


def _location(file: str, mark: yaml.Mark) -> Location:
    return Location(file=file, line=mark.line + 1, column=mark.column + 1)


MAX_VALUES = 200_000
"""Values one document may expand to: far above any real scene, far below an alias bomb."""

_PLAIN_TAGS = frozenset(
    f"tag:yaml.org,2002:{name}" for name in ("map", "seq", "str", "int", "float", "bool", "null", "timestamp")
)
"""The tags of plain YAML data, given implicitly or written out (``!!int 3``); any other tag
(``!!python/object``, ``!!binary``, ``!custom``) is refused before anything is constructed."""


class _Loader(yaml.SafeLoader):
    """PyYAML's safe loader, which follows YAML 1.1, also reading the exponent numbers of YAML 1.2
    (``1e6``, ``1e-9``, ``1.5e3``) as floats: YAML 1.1 wants a dot and a signed exponent (``1.0e+6``) and reads
    ``1e6`` as text."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+.0123456789"),
)


class _Walker:
    """Builds plain data from composed nodes, recording each key path's location.

    Guards what PyYAML does not: aliases that contain themselves, alias bombs (a few lines expanding
    to billions of values), and tags whose constructor fails — all become located `ConfigError`s.
    """

    def __init__(self, file: str):
        self.file = file
        self.constructor = yaml.SafeLoader("")
        self.locations: dict[KeyPath, Location] = {}
        self.count = 0
        self.open: set[int] = set()

    def fail(self, node: yaml.Node, path: KeyPath, message: str) -> ConfigError:
        return ConfigError([Problem(path, message, _location(self.file, node.start_mark))])

    def scalar(self, node: yaml.Node, path: KeyPath) -> Any:
        try:
            return self.constructor.construct_object(node, deep=True)
        except (yaml.YAMLError, ValueError, TypeError) as exc:
            reason = getattr(exc, "problem", None) or str(exc)
            raise self.fail(node, path, f"cannot be read ({node.tag}): {reason}") from None

    def walk(self, node: yaml.Node, path: KeyPath) -> Any:
        self.count += 1
        if self.count > MAX_VALUES:
            raise self.fail(node, path, f"makes the document expand past {MAX_VALUES} values (nested aliases?)")
        if id(node) in self.open:
            raise self.fail(node, path, "is an alias that contains itself")
        if node.tag not in _PLAIN_TAGS:
            tag = node.tag.replace("tag:yaml.org,2002:", "!!")
            raise self.fail(
                node,
                path,
                f"has the YAML tag {tag}, which camgen does not read: configuration is plain YAML data "
                "(nothing was constructed or run); remove the tag",
            )
        if isinstance(node, yaml.MappingNode):
            self.open.add(id(node))
            try:
                self.constructor.flatten_mapping(node)  # resolves YAML merge keys (<<)
            except yaml.YAMLError as exc:
                raise self.fail(node, path, f"has a bad merge key (<<): {getattr(exc, 'problem', exc)}") from None
            result: dict[str, Any] = {}
            for key_node, value_node in node.value:
                key = self.scalar(key_node, path)
                key = key if isinstance(key, str) else str(key)
                if key in result:
                    raise self.fail(key_node, (*path, key), "appears twice in this mapping")
                self.locations[(*path, key)] = _location(self.file, key_node.start_mark)
                result[key] = self.walk(value_node, (*path, key))
            self.open.discard(id(node))
            return result
        if isinstance(node, yaml.SequenceNode):
            self.open.add(id(node))
            items = []
            for index, item in enumerate(node.value):
                self.locations[(*path, index)] = _location(self.file, item.start_mark)
                items.append(self.walk(item, (*path, index)))
            self.open.discard(id(node))
            return items
        return self.scalar(node, path)


def parse_yaml(text: str, file: str) -> YamlDocument:
    """Parse one YAML document from `text`; `file` names it in error messages."""
    try:
        node = yaml.compose(text, Loader=_Loader)
    except yaml.MarkedYAMLError as exc:
        # Point at where the broken construct opened (an unclosed [ or {), else where parsing stopped.
        mark = exc.context_mark or exc.problem_mark
        where = _location(file, mark) if mark else Location(file, 1, 1)
        reason = exc.problem or "is not valid YAML"
        if exc.context_mark is not None and exc.context:
            reason += f" ({exc.context} that starts here)"
        raise ConfigError([Problem((), f"YAML syntax error: {reason}", where)]) from None
    except yaml.YAMLError as exc:
        raise ConfigError([Problem((), f"YAML error: {exc}", Location(file, 1, 1))]) from None
    except RecursionError:
        raise ConfigError([Problem((), "is nested too deeply to read", Location(file, 1, 1))]) from None
    if node is None:
        raise ConfigError([Problem((), "the file is empty; expected a mapping of keys", Location(file, 1, 1))])
    walker = _Walker(file)
    walker.locations[()] = _location(file, node.start_mark)
    try:
        data = walker.walk(node, ())
    except RecursionError:
        raise ConfigError([Problem((), "is nested too deeply to read", Location(file, 1, 1))]) from None
    if not isinstance(data, dict):
        raise ConfigError(
            [Problem((), f"the top level must be a mapping of keys, got {type(data).__name__}", walker.locations[()])]
        )
    return YamlDocument(data=data, locations=walker.locations)


MAX_YAML_BYTES = 16 * 2**20
"""Largest YAML file read: far above any real profile, scene or dataset (a scene of thousands of
actors is a few MiB), far below what would exhaust memory (a device or a video given by mistake)."""


def load_yaml(path: Path) -> YamlDocument:
    """Read and parse a YAML file; a missing or unreadable file, a directory, a device or FIFO, and a file
    over `MAX_YAML_BYTES` are each a `ConfigError` (found with `os.stat`, before the file is opened)."""
    problem = input_file_problem(path, max_bytes=MAX_YAML_BYTES, what="YAML config")
    if problem:
        raise ConfigError(f"{path}: {problem}")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from None
    return parse_yaml(text, str(path))


def merge_documents(base: YamlDocument, override: YamlDocument) -> YamlDocument:
    """Deep-merge `override` onto `base`: mappings merge key by key, anything else is replaced.

    Locations follow the value that wins, so an error in an inherited key points at the base file.
    """
    locations: dict[KeyPath, Location] = {}

    def merge(a: Any, b: Any, path: KeyPath) -> Any:
        if isinstance(a, dict) and isinstance(b, dict):
            merged = {}
            for key in [*a, *(k for k in b if k not in a)]:
                sub = (*path, key)
                if key in b and key in a:
                    locations[sub] = override.locations.get(sub) or base.locations[sub]
                    merged[key] = merge(a[key], b[key], sub)
                elif key in b:
                    _copy_locations(override, sub, locations)
                    merged[key] = b[key]
                else:
                    _copy_locations(base, sub, locations)
                    merged[key] = a[key]
            return merged
        _copy_locations(override, path, locations)
        return b

    data = merge(base.data, override.data, ())
    locations[()] = override.locations[()]
    return YamlDocument(data=data, locations=locations)


def _copy_locations(source: YamlDocument, prefix: KeyPath, into: dict[KeyPath, Location]) -> None:
    n = len(prefix)
    for path, location in source.locations.items():
        if path[:n] == prefix:
            into[path] = location
