"""Dependencies point down (shared/DESIGN.md): the core and the renderer never import the packages that
drive them. Imports are read from the source with `ast`, inside functions too, so a lazy import counts."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

SOURCE = Path(__file__).resolve().parents[1] / "src" / "camgen"
LOW = ("config", "job", "motion", "optics", "sensor", "isp", "actors", "vehicles", "props", "annotate", "render", "io")
"""Packages (and the `camgen.job` module) below `plan`."""
HIGH = ("plan", "batch", "cli", "sim", "fit", "bench", "preview")
"""Packages that drive the ones in LOW."""


def _package_of(path: Path) -> list[str]:
    """The package a module's relative imports start from, as its name's parts."""
    parts = ["camgen", *path.relative_to(SOURCE).with_suffix("").parts]
    return parts[:-1]


def imported_modules(source: str, package: list[str]) -> set[str]:
    """Every module `source` (a module of `package`) imports, absolute, wherever the statement stands."""
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = package[: len(package) - node.level + 1] if node.level else []
            module = ".".join([*base, node.module] if node.module else base)
            names.add(module)
            names.update(f"{module}.{alias.name}" for alias in node.names)  # `from camgen import plan`
    return names


def _sources(package: str) -> list[Path]:
    directory = SOURCE / package
    return sorted(directory.rglob("*.py")) if directory.is_dir() else [SOURCE / f"{package}.py"]


@pytest.mark.parametrize("package", LOW)
def test_low_packages_import_nothing_above_them(package):
    upward = {
        f"{path.relative_to(SOURCE)} imports {name}"
        for path in _sources(package)
        for name in imported_modules(path.read_text(encoding="utf-8"), _package_of(path))
        if name.split(".")[:2] in (["camgen", high] for high in HIGH)
    }
    assert not upward, "\n".join(sorted(upward))


def test_the_check_sees_lazy_and_relative_imports():
    source = "def f():\n    from camgen.plan.execute import execute\n    from .. import batch\n"
    names = imported_modules(source, ["camgen", "render"])
    assert {"camgen.plan.execute", "camgen.batch"} <= names


GEOMETRY = ("actors", "vehicles", "props")
"""Pure geometry (DESIGN.md "camgen.actors"): no renderer, no OpenGL."""


@pytest.mark.parametrize("package", GEOMETRY)
def test_geometry_packages_draw_nothing(package):
    drawing = {
        f"{path.relative_to(SOURCE)} imports {name}"
        for path in _sources(package)
        for name in imported_modules(path.read_text(encoding="utf-8"), _package_of(path))
        if name.split(".")[:2] == ["camgen", "render"] or name.split(".")[0] in ("pyrender", "OpenGL")
    }
    assert not drawing, "\n".join(sorted(drawing))
