"""`camgen schema` emits JSON Schema that independent validators accept the examples against."""

from __future__ import annotations

import json

import jsonschema
import pytest
import yaml

from camgen.cli.main import main
from tests.conftest import REPO

EXAMPLES = {
    "profile": sorted((REPO / "profiles").glob("*.yaml")),
    "scene": sorted((REPO / "scenes").glob("*.yaml")),
    "dataset": sorted((REPO / "datasets").glob("*.yaml")),
}


@pytest.fixture(scope="module")
def schemas(tmp_path_factory):
    out = tmp_path_factory.mktemp("schemas")
    assert main(["schema", "-o", str(out)]) == 0
    return {kind: json.loads((out / f"{kind}.schema.json").read_text()) for kind in EXAMPLES}


@pytest.mark.parametrize(
    ("kind", "path"), [(k, p) for k, paths in EXAMPLES.items() for p in paths], ids=lambda v: getattr(v, "stem", v)
)
def test_examples_validate_against_the_schema(schemas, kind, path):
    data = yaml.safe_load(path.read_text())
    if kind == "profile" and "extends" in data:
        pytest.skip("a partial profile completes only after `extends` is merged")
    jsonschema.validate(data, schemas[kind])


def test_schema_rejects_what_camgen_rejects(schemas):
    scene = yaml.safe_load((REPO / "scenes/parking_lot.yaml").read_text())
    scene["actors"][0]["path"]["speed_m_s"] = -1
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(scene, schemas["scene"])
    scene = yaml.safe_load((REPO / "scenes/parking_lot.yaml").read_text())
    scene["cameras"][0]["mount"]["yaw_degrees"] = 3
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(scene, schemas["scene"])


def test_schema_documents_units(schemas):
    sensor = schemas["profile"]["$defs"]["Sensor"]["properties"]
    assert "µm" in sensor["pixel_pitch_um"]["description"]
