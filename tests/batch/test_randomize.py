"""Dataset randomisation: deterministic per job, each knob changes the compiled job within its range, bad
ranges named at their key, and a job's draws independent of the other jobs."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from camgen.batch.expand import compile_batch_job, expand
from camgen.batch.randomize import _kept_actors
from camgen.config.loader import load_dataset
from camgen.config.scene import Actor
from camgen.errors import ConfigError
from tests.batch.conftest import make_dataset
from tests.conftest import PTZ_PROFILE, SCENE, write

CROWD_SCENE = (
    SCENE.replace("focus_distance_m", "")
    .replace(
        "actors:\n",
        "actors:\n"
        + "".join(f"  - {{name: p{i}, class: person, path: {{waypoints_m: [[{i}, 2], [{i}, 8]]}}}}\n" for i in range(5))
        + "  - {name: wanderer, class: person, random_walk: {region_m: [[-5, 2], [5, 9]], seed: 11}}\n",
    )
    .replace("      pitch_deg: -20\n", "      pitch_deg: -20\n    focus_distance_m: 8\n")
)

RANDOM = """\
description: randomised walkers
scenes: [scenes/crowd.yaml]
profiles: [small, wide]
seeds: [3, 4]
seed: 17
randomize:
  light_scale_range: [0.01, 2]
  mount_position_jitter_m: 0.5
  mount_angle_jitter_deg: 3
  actor_count_range: [2, 4]
  walk_seeds: true
  profile_spread_pct: {read_noise_e: 5, prnu_pct: 10, dsnu_e: 10, dark_current_e_per_s: 10, focus_distance_m: 5}
"""


def make_random(directory: Path, text: str = RANDOM) -> Path:
    path = make_dataset(directory, text)
    write(directory, "scenes/crowd.yaml", CROWD_SCENE)
    return path


@pytest.fixture
def random_dataset(tmp_path: Path) -> Path:
    return make_random(tmp_path)


@pytest.fixture
def compiled(random_dataset):
    jobs = expand(random_dataset)
    return jobs, [compile_batch_job(job) for job in jobs]


def test_two_expansions_give_identical_draws_and_job_hashes(random_dataset, compiled):
    jobs, first = compiled
    again = expand(random_dataset)
    assert [job.randomized for job in again] == [job.randomized for job in jobs]
    assert [compile_batch_job(job).job_id for job in again] == [job.job_id for job in first]
    assert len({job.job_id for job in first}) == len(first)


def test_a_different_dataset_seed_draws_different_values(tmp_path, random_dataset):
    other = make_random(tmp_path / "other", RANDOM.replace("seed: 17", "seed: 18"))
    for a, b in zip(expand(random_dataset), expand(other), strict=True):
        assert a.name == b.name
        assert a.randomized["light_scale"] != b.randomized["light_scale"]
        assert a.randomized["cameras"] != b.randomized["cameras"]


def test_adding_a_seed_or_a_profile_leaves_the_other_jobs_draws(tmp_path, random_dataset):
    bigger = make_random(tmp_path / "bigger", RANDOM.replace("[3, 4]", "[2, 3, 4, 5]").replace("wide]", "wide, fixed]"))
    before = {job.name: job.randomized for job in expand(random_dataset)}
    after = {job.name: job.randomized for job in expand(bigger)}
    assert len(after) == 12
    assert {name: after[name] for name in before} == before


def test_switching_a_knob_off_leaves_the_others(tmp_path, random_dataset):
    fewer = make_random(tmp_path / "fewer", RANDOM.replace("  walk_seeds: true\n", ""))
    for a, b in zip(expand(random_dataset), expand(fewer), strict=True):
        assert "walk_seeds" not in b.randomized
        assert {k: v for k, v in a.randomized.items() if k != "walk_seeds"} == b.randomized


def test_light_scale_multiplies_every_light_within_its_range(compiled):
    jobs, compiled_jobs = compiled
    for job, result in zip(jobs, compiled_jobs, strict=True):
        scale = job.randomized["light_scale"]
        assert 0.01 <= scale <= 2
        assert result.scene.lights[0].illuminance_lux == pytest.approx(1000 * scale)
    scales = [math.log(job.randomized["light_scale"]) for job in jobs]
    assert len(set(scales)) == len(scales)


def test_mount_jitter_moves_and_turns_each_camera_within_its_range(compiled):
    jobs, compiled_jobs = compiled
    for job, result in zip(jobs, compiled_jobs, strict=True):
        drawn = job.randomized["cameras"]["cam"]
        mount = result.scene.cameras[0].mount
        offset = [m - p for m, p in zip(mount.position_m, (0, -5, 3), strict=True)]
        assert offset == pytest.approx(drawn["mount_position_offset_m"])
        assert all(0 < abs(d) <= 0.5 for d in offset)
        angles = drawn["mount_angle_offset_deg"]
        assert (mount.yaw_deg - 90, mount.pitch_deg + 20, mount.roll_deg) == pytest.approx(
            (angles["yaw_deg"], angles["pitch_deg"], angles["roll_deg"])
        )
        assert all(0 < abs(a) <= 3 for a in angles.values())
    assert len({result.cameras[0].states[0].T_world_from_cam for result in compiled_jobs}) == len(jobs)


def test_actor_count_keeps_a_subset_in_scene_order(compiled):
    jobs, compiled_jobs = compiled
    order = ["p0", "p1", "p2", "p3", "p4", "wanderer", "walker"]
    for job, result in zip(jobs, compiled_jobs, strict=True):
        kept = [actor.name for actor in result.scene.actors]
        assert kept == job.randomized["actors_kept"]
        assert 2 <= len(kept) <= 4
        assert kept == sorted(kept, key=order.index)
    assert len({tuple(job.randomized["actors_kept"]) for job in jobs}) > 1


def test_actor_count_is_capped_by_the_actors_there_are(tmp_path):
    path = make_random(tmp_path, RANDOM.replace("[2, 4]", "[10, 20]"))
    assert all(len(job.randomized["actors_kept"]) == 7 for job in expand(path))


def test_walk_seeds_reseed_every_random_walk(compiled):
    jobs, compiled_jobs = compiled
    seeds = set()
    for job, result in zip(jobs, compiled_jobs, strict=True):
        seed = job.randomized["walk_seeds"]["wanderer"]
        seeds.add(seed)
        walker = [actor for actor in result.scene.actors if actor.name == "wanderer"]
        assert all(actor.random_walk.seed == seed != 11 for actor in walker)
    assert len(seeds) == len(jobs)


def test_profile_spread_varies_the_unit_and_gives_it_a_serial(compiled):
    jobs, compiled_jobs = compiled
    base = {"read_noise_e": 2.0, "prnu_pct": 0.5, "dsnu_e": 0.5, "dark_current_e_per_s": 1.0}
    serials = set()
    for job, result in zip(jobs, compiled_jobs, strict=True):
        drawn = job.randomized["cameras"]["cam"]
        factors = drawn["profile_factors"]
        camera = result.cameras[0]
        noise = camera.profile.sensor.noise
        for key, value in base.items():
            assert getattr(noise, key) == pytest.approx(value * factors[key])
            assert factors[key] != 1 and abs(factors[key] - 1) < 0.6
        assert result.scene.cameras[0].focus_distance_m == pytest.approx(8 * factors["focus_distance_m"])
        assert camera.serial == drawn["serial"]
        serials.add(camera.serial)
    assert len(serials) == len(jobs)


def test_no_randomize_leaves_jobs_as_before(dataset):
    assert all(job.randomized == {} for job in expand(dataset))


@pytest.mark.parametrize(
    ("replace", "by", "key"),
    [
        ("[0.01, 2]", "[2, 0.01]", "randomize.light_scale_range"),
        ("[0.01, 2]", "[-1, 2]", r"randomize.light_scale_range\[0\]"),
        ("[2, 4]", "[4, 2]", "randomize.actor_count_range"),
        ("prnu_pct: 10", "prnu_pct: -1", "randomize.profile_spread_pct.prnu_pct"),
        ("mount_angle_jitter_deg: 3", "mount_angle_jitter_deg: -3", "randomize.mount_angle_jitter_deg"),
        ("walk_seeds: true", "walk_seed: true", "randomize.walk_seed"),
    ],
)
def test_bad_ranges_name_the_dataset_key(tmp_path, replace, by, key):
    path = make_random(tmp_path, RANDOM.replace(replace, by))
    with pytest.raises(ConfigError, match=rf"tiny\.yaml:\d+.*{key}"):
        load_dataset(path)


PTZ_SCENE = SCENE.replace("profile: fixed", "profile: ptz").replace(
    "      pitch_deg: -20\n", "      pitch_deg: -20\n    ptz: {presets: [{name: gate, pan_deg: 20, tilt_deg: -10}]}\n"
)


def test_ptz_programs_pick_one_listed_program_per_ptz_camera(tmp_path):
    text = (
        "scenes: [scenes/head.yaml]\nseeds: {start: 0, count: 6}\nrandomize:\n"
        "  ptz_programs: [{type: hold}, {type: preset, preset: gate, start_s: 0.5}]\n"
    )
    path = make_dataset(tmp_path, text)
    write(tmp_path, "profiles/ptz.yaml", PTZ_PROFILE)
    write(tmp_path, "scenes/head.yaml", PTZ_SCENE)
    jobs = expand(path)
    indices = [job.randomized["cameras"]["cam"]["ptz_program_index"] for job in jobs]
    assert set(indices) == {0, 1}
    for job, index in zip(jobs, indices, strict=True):
        program = compile_batch_job(job).scene.cameras[0].ptz.program
        assert program.type == ("hold", "preset")[index]


def test_a_drawn_ptz_program_naming_a_missing_preset_names_the_job(tmp_path):
    text = "scenes: [scenes/head.yaml]\nrandomize:\n  ptz_programs: [{type: preset, preset: door}]\n"
    path = make_dataset(tmp_path, text)
    write(tmp_path, "profiles/ptz.yaml", PTZ_PROFILE)
    write(tmp_path, "scenes/head.yaml", PTZ_SCENE)
    with pytest.raises(ConfigError, match=r"job head-own-seed0.*after randomize.*'door'"):
        compile_batch_job(expand(path)[0])


def test_a_rider_is_kept_or_left_out_with_its_two_wheeler():
    actors = [
        Actor.model_validate({"name": "walker", "class": "person", "path": {"waypoints_m": [[0, 0], [5, 0]]}}),
        Actor.model_validate({"name": "cyclist", "class": "person", "rides": "bike"}),
        Actor.model_validate({"name": "bike", "class": "bicycle", "path": {"waypoints_m": [[0, 2], [9, 2]]}}),
        Actor.model_validate({"name": "car", "class": "car", "path": {"waypoints_m": [[0, 5], [9, 5]]}}),
    ]
    seen = set()
    for seed in range(40):
        kept = _kept_actors(actors, (1, 2), set(), np.random.default_rng(seed))
        assert ("cyclist" in kept) == ("bike" in kept), kept
        assert 1 <= len(set(kept) - {"cyclist"}) <= 2
        seen.add(tuple(kept))
    assert ("cyclist", "bike") in {tuple(k for k in kept if k in ("cyclist", "bike")) for kept in seen}
    # A followed rider keeps its two-wheeler.
    assert {"cyclist", "bike"} <= set(_kept_actors(actors, (1, 1), {"cyclist"}, np.random.default_rng(0)))
