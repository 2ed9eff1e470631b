"""What the subcommands share: profile search paths and kind detection."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from camgen.config.yaml_source import load_yaml

PROFILE_PATH_ENV = "CAMGEN_PROFILE_PATH"


def add_profile_dirs_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--profiles",
        metavar="DIR",
        action="append",
        type=Path,
        default=[],
        help=f"directory to look up profile names in (repeatable; also ${PROFILE_PATH_ENV}, then the "
        "scene's own and sibling profiles/ directories, then ./profiles)",
    )


def profile_dirs(args: argparse.Namespace) -> list[Path]:
    from_env = [Path(p) for p in os.environ.get(PROFILE_PATH_ENV, "").split(os.pathsep) if p]
    return [*args.profiles, *from_env]


def detect_kind(path: Path) -> str | None:
    """'profile', 'scene' or 'dataset' from the file's top-level keys; None if it cannot tell."""
    keys = set(load_yaml(path).data)
    if keys & {"sensor", "lens", "extends"}:
        return "profile"
    if keys & {"cameras", "actors", "environment"}:
        return "scene"
    if "scenes" in keys:
        return "dataset"
    return None
