"""The benchmark report: sections become marked blocks, a partial run replaces only its own, plots
are real PNGs linked relative to the document, and the CLI refuses bad options before running."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from camgen.bench.harness import Case
from camgen.bench.plots import TradeoffPoint, growth_plot, stage_bars, threshold_plot, tradeoff_plot
from camgen.bench.report import Plots, Section, markers, run_sections, write_report
from camgen.cli.main import main


def _section(key: str, value: float) -> Section:
    def body(results, plots: Plots) -> str:
        (result,) = results.values()
        return f"{key} error {result.error:g}"

    return Section(key, f"Title {key}", lambda: [Case(name=f"{key} case", run=lambda: value)], body)


def test_a_full_run_writes_every_block_and_a_partial_run_replaces_only_its_own(tmp_path):
    document = tmp_path / "BENCHMARKS.md"
    plots = Plots(tmp_path / "docs" / "bench", document)
    blocks = run_sections([_section("a", 1.0), _section("b", 2.0)], repeats=1, plots=plots)
    write_report(document, "# header", blocks, ["a", "b"])
    text = document.read_text()
    assert text.startswith("# header") and "## Title a" in text and "a error 1" in text and "b error 2" in text
    document.write_text(text + "\nhand-written tail\n")
    write_report(document, "# header", run_sections([_section("b", 7.0)], repeats=1, plots=plots), ["a", "b"])
    text = document.read_text()
    assert "b error 7" in text and "b error 2" not in text and "a error 1" in text
    assert text.count(markers("b")[0]) == 1 and "hand-written tail" in text
    # A section not in the file yet is appended.
    write_report(document, "# header", run_sections([_section("c", 3.0)], repeats=1, plots=plots), ["a", "b", "c"])
    assert document.read_text().rstrip().endswith(markers("c")[1])


def test_plot_links_are_relative_to_the_document(tmp_path):
    plots = Plots(tmp_path / "docs" / "bench", tmp_path / "BENCHMARKS.md")
    assert plots.link("x.png", "alt") == "![alt](docs/bench/x.png)"


def test_plots_are_png_files(tmp_path):
    paths = [
        tradeoff_plot(
            tmp_path / "t.png",
            "t",
            [TradeoffPoint("a", 1.0, 2.0), TradeoffPoint("b", 3.0, 0.5, True)],
            error_label="e",
            log_time=True,
        ),
        stage_bars(tmp_path / "s.png", "s", [("one", {"render": 3.0, "isp": 1.0}), ("two", {"render": 2.0})]),
        growth_plot(
            tmp_path / "g.png",
            "g",
            [("x", np.array([1.0, 2.0, 4.0]), np.array([1.0, 2.0, 4.0]), 1.0, 1.0)],
            x_label="n",
        ),
        threshold_plot(
            tmp_path / "h.png", "h", np.array([1.0, 10.0]), np.array([0.1, 0.01]), np.array([0.05, 0.04]), threshold=5
        ),
    ]
    for path in paths:
        image = cv2.imread(str(path))
        assert image is not None and image.shape[0] > 100 and image.shape[1] > 300
        assert image.std() > 10  # something is drawn
    assert not list(tmp_path.glob(".*partial*"))


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--section", "nope"], "--section nope: no such section; choose from end_to_end"),
        (["--write", "{tmp}"], "is a directory; give the markdown file to write"),
        (["--plots", "{tmp}/file.png"], "is a file; give a directory for the PNG plots"),
    ],
)
def test_bad_options_are_refused_before_anything_runs(tmp_path, capsys, args, message):
    (tmp_path / "file.png").write_bytes(b"")
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    assert main(["bench", *args]) == 2
    assert message in capsys.readouterr().err


def test_list_names_every_section(capsys):
    assert main(["bench", "--list"]) == 0
    listed = [line.split()[0] for line in capsys.readouterr().out.splitlines()]
    assert listed == [
        "end_to_end",
        "camera_model",
        "skipping",
        "tradeoffs",
        "growth",
        "people",
        "vehicles",
        "exposure",
        "sim",
        "sim_examples",
        "coverage",
        "long",
        "other",
        "device",
        "scale",
    ]


def test_recorded_device_runs_are_listed_as_measured(tmp_path):
    import json

    from camgen.bench.device_frames import recorded_table

    assert "No run is recorded yet" in recorded_table(tmp_path / "none")
    case = {"scene": "parking_lot", "camera": "pole_ptz", "size": "1920×1080", "frame_ms": 250.0, "frames_per_s": 4.0,
            "stage_ms": {"render": 120.0, "isp": 30.0, "annotate": 60.0, "io.files": 20.0, "sensor": 5.0}}  # fmt: skip
    record = {"where": "OpenGL: NVIDIA H100; 16 CPUs; x86_64", "video": False, "note": "at abc1234", "cases": [case]}
    (tmp_path / "h100.json").write_text(json.dumps(record), encoding="utf-8")
    text = recorded_table(tmp_path)
    assert "| h100 | NVIDIA H100, 16 CPUs | parking_lot | pole_ptz | 1920×1080 | 4.00 | 250 | " in text
    assert "render 120, annotate 60, isp 30, io.files 20 |" in text  # the four largest stages, largest first
    assert "at abc1234" in text and "PyAV was not installed" in text


def test_a_failing_section_is_reported_and_the_others_still_written(tmp_path):
    document = tmp_path / "BENCHMARKS.md"
    plots = Plots(tmp_path / "plots", document)

    def broken(results, plots):
        raise KeyError("linear")

    failures, written = [], {}
    blocks = run_sections(
        [Section("bad", "Bad", lambda: [Case(name="x", run=lambda: None)], broken), _section("good", 1.0)],
        repeats=1,
        plots=plots,
        failures=failures,
        on_block=lambda key, text: written.setdefault(key, text),
    )
    assert failures == [("bad", "KeyError: 'linear'")]
    assert "This section failed in this run" in blocks["bad"] and "good error 1" in blocks["good"]
    assert set(written) == {"bad", "good"}  # each block handed over as soon as its section finished
    with pytest.raises(KeyError):  # without a failures list, the error propagates
        run_sections([Section("bad", "Bad", lambda: [], broken)], repeats=1, plots=plots)


def test_device_frames_refuses_fewer_than_two_frames(capsys):
    from camgen.bench.device_frames import main as device_frames

    with pytest.raises(SystemExit) as stop:
        device_frames(["--frames", "1"])
    assert stop.value.code == 2
    assert "--frames must be at least 2 (a warm-up and a timed frame), got 1" in capsys.readouterr().err
