"""Reading IES LM-63 photometric files (the format: `camgen.world.ies`)."""

from __future__ import annotations

from pathlib import Path

from camgen.errors import ConfigError
from camgen.world.ies import Photometry, parse_ies


def read_ies(path: str | Path) -> Photometry:
    """The candela table of the IES file at `path`; a ConfigError naming the file and what is wrong."""
    path = Path(path)
    try:
        text = path.read_text(encoding="latin-1")  # LM-63 predates UTF-8; keyword lines may hold any byte
    except OSError as exc:
        raise ConfigError(
            f"IES file {str(path)!r} cannot be read ({exc.strerror}); give the path of an LM-63 file"
        ) from None
    try:
        return parse_ies(text)
    except ValueError as exc:
        raise ConfigError(f"IES file {str(path)!r}: {exc}") from None
