"""camgen schema: JSON Schema of profiles, scenes and datasets, for editor completion of YAML."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from rich.console import Console

from camgen.cli.common import check_output_directory
from camgen.config import Dataset, Profile, Scene
from camgen.io.files import write_text_atomic

MODELS = {"profile": Profile, "scene": Scene, "dataset": Dataset}


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("schema", help="print or write the JSON Schema of the YAML files")
    parser.add_argument("kind", nargs="?", choices=[*MODELS, "all"], default="all")
    parser.add_argument(
        "-o",
        "--output",
        type=Path,
        metavar="DIR",
        help="write <kind>.schema.json files into DIR instead of printing",
    )
    parser.set_defaults(run=run)


def schema_of(kind: str) -> dict:
    schema = MODELS[kind].model_json_schema(by_alias=True)
    schema["$schema"] = "https://json-schema.org/draft/2020-12/schema"
    return schema


def run(args: argparse.Namespace, out: Console, err: Console) -> int:
    kinds = list(MODELS) if args.kind == "all" else [args.kind]
    if args.output:
        check_output_directory(args.output, "-o", "give a directory for the <kind>.schema.json files")
        for kind in kinds:
            target = args.output / f"{kind}.schema.json"
            write_text_atomic(target, json.dumps(schema_of(kind), indent=2, ensure_ascii=False) + "\n")
            out.print(f"wrote {target}", markup=False)
        return 0
    document = schema_of(kinds[0]) if len(kinds) == 1 else {k: schema_of(k) for k in kinds}
    print(json.dumps(document, indent=2, ensure_ascii=False))
    return 0
