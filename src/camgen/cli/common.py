"""What the subcommands share: profile search paths, checks of output paths, and kind detection."""

from __future__ import annotations

import argparse
import os
from pathlib import Path

from camgen.config.yaml_source import load_yaml
from camgen.errors import ConfigError
from camgen.io.files import output_directory_problem, output_file_problem

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
    """--profiles, then $CAMGEN_PROFILE_PATH; each must be a directory (a typo would otherwise only
    show as a profile name not found, far from its cause)."""
    from_env = [Path(p) for p in os.environ.get(PROFILE_PATH_ENV, "").split(os.pathsep) if p]
    sources = [(f"--profiles {d}", d) for d in args.profiles]
    sources += [(f"${PROFILE_PATH_ENV} entry {d}", d) for d in from_env]
    for source, directory in sources:
        if not directory.is_dir():
            state = "no such directory" if not directory.exists() else "is not a directory"
            raise ConfigError(f"{source}: {state}; give a directory that holds profile YAML files")
    return [*args.profiles, *from_env]


def check_output_directory(path: Path, option: str, fix: str = "give a directory you can write to") -> None:
    """Before any work: `path`, given as `option`, can be made (or is) a directory camgen can write in."""
    problem = output_directory_problem(path)
    if problem:
        raise ConfigError(f"{option} {path}: {problem}; {fix}")


def check_output_file(path: Path, option: str, fix: str = "give a file name in a directory you can write to") -> None:
    """Before any work: `path`, given as `option`, can be written as a file (an existing file is replaced)."""
    problem = output_file_problem(path)
    if problem:
        raise ConfigError(f"{option} {path}: {problem}; {fix}")


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
