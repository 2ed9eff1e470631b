"""Writing what a fit found as profile YAML: a fragment, or a profile that extends a base profile.

A fitted profile is written under a temporary name, validated by camgen's own loader (so what lands
under the final name always loads), and renamed into place.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import yaml

from camgen.config.loader import load_profile
from camgen.errors import ConfigError, Problem
from camgen.io.files import atomic_path


def profile_text(fragment: dict, *, header: Sequence[str], extends: str | None = None) -> str:
    """YAML of `fragment` (nested keys as in a profile), after `header` as comment lines and, when
    given, an ``extends:`` line naming the base profile."""
    lines = [f"# {line}".rstrip() for line in header]
    body = {"extends": extends, **fragment} if extends is not None else fragment
    return "\n".join(lines) + "\n" + yaml.safe_dump(body, sort_keys=False, allow_unicode=True, width=120)


def relative_reference(base: Path, output: Path) -> str:
    """How `output` names `base` in its ``extends:`` (a path relative to the output's folder)."""
    return Path(os.path.relpath(base.resolve(), output.resolve().parent)).as_posix()


def write_profile(output: Path, fragment: dict, *, header: Sequence[str], base: Path | None) -> None:
    """Write the fitted keys to `output`: with `base`, a full profile (``extends:`` the base, checked by
    loading it); without, a fragment to merge into a profile."""
    extends = relative_reference(base, output) if base is not None else None
    with atomic_path(output) as tmp:
        tmp.write_text(profile_text(fragment, header=header, extends=extends), encoding="utf-8")
        if base is not None:
            try:
                load_profile(tmp)
            except ConfigError as exc:
                problems = [Problem(p.path, p.message, None) for p in exc.problems]
                raise ConfigError(
                    [Problem((), f"{output}: the fitted profile does not validate against {base}:"), *problems]
                ) from None
