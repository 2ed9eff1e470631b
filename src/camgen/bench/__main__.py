"""python -m camgen.bench [...]: the same as `camgen bench [...]`."""

from __future__ import annotations

import sys

from camgen.cli.main import main

if __name__ == "__main__":
    sys.exit(main(["bench", *sys.argv[1:]]))
