"""The sweep runner: points of a grid, records per point, failures recorded, resume after an
interruption with no point lost or repeated, and the `rigidtouch sweep` command."""

import json
import os
import subprocess

import pytest

import rigidtouch as rt
from rigidtouch import sweeps as sw

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))

# 2 renderers x 2 stiffnesses, one of them refused by the tap experiment (negative)
SPEC = {"base": {"taps": 1, "speed": 0.2, "device": "touch"},
        "grid": {"renderer": ["penalty", "train"], "stiffness": [800.0, -5.0]}}


def records(path):
    with open(path) as f:
        return [json.loads(line) for line in f]


def test_points_of_a_grid():
    pts = sw.points({"base": {"taps": 1},
                     "grid": {"renderer": ["penalty", "train"],
                              "stiffness": {"linspace": [100, 300, 3]}}})
    assert len(pts) == 6
    assert pts[0] == {"taps": 1, "renderer": "penalty", "stiffness": 100.0}
    assert pts[-1] == {"taps": 1, "renderer": "train", "stiffness": 300.0}
    with pytest.raises(sw.SpecError, match="grid.stiffness.logspace"):
        sw.points({"grid": {"stiffness": {"logspace": [1, 2]}}})
    with pytest.raises(sw.SpecError, match="unknown field"):
        sw.points({"grids": {}})
    with pytest.raises(sw.SpecError, match="trace"):
        sw.points({"base": {"trace": "x.csv"}})
    # a key that is no flag of tap is a spec error before anything runs (it was a failed point,
    # with CLI11's words in the results file only)
    with pytest.raises(sw.SpecError, match=r"grid.nosuch is not a flag of tap \(--nosuch\)"):
        sw.points({"base": {}, "grid": {"nosuch": [1]}})
    with pytest.raises(sw.SpecError, match=r"base.stifness is not a flag of tap"):
        sw.points({"base": {"stifness": 300.0}})
    assert sw.points({"base": {"wall_point": [0, 0, 0], "wall_normal": [0, 0, 1]}})


def test_sweep_records_and_resumes(tmp_path):
    out = str(tmp_path / "results.jsonl")
    summary = rt.sweep(SPEC, out, workers=1)
    assert summary["ran"] == 4 and summary["failed"] == 2
    full = records(out)
    assert sorted(r["point"] for r in full) == [0, 1, 2, 3]
    failed = [r for r in full if not r["ok"]]
    assert {r["params"]["stiffness"] for r in failed} == {-5.0}
    assert all("stiffness" in r["error"] for r in failed)
    ok = {r["params"]["renderer"]: r for r in full if r["ok"]}
    # a point means what the same flags mean to tap(): the same run
    direct = rt.tap(taps=1, speed=0.2, device="touch", renderer="train", stiffness=800.0)
    assert ok["train"]["energy_to_user_J"] == direct.metrics["energy_to_user_J"]
    assert ok["train"]["stiffness_N_per_m"] == 800.0
    assert ok["train"]["passive"] == (direct.metrics["max_cumulative_energy_to_user_J"] <= 1e-9)

    # interrupted: two whole records and a torn third line; the rerun completes the rest only
    with open(out) as f:
        lines = f.readlines()
    with open(out, "w") as f:
        f.writelines(lines[:2])
        f.write(lines[2][: len(lines[2]) // 2])
    summary = rt.sweep(SPEC, out, workers=1)
    assert summary["already_done"] == 2 and summary["ran"] == 2
    again = records(out)
    assert [json.dumps(r) for r in again[:2]] == [line.rstrip("\n") for line in lines[:2]]
    assert sorted(r["key"] for r in again) == sorted(r["key"] for r in full)  # none lost or twice
    # complete: nothing to do
    assert rt.sweep(SPEC, out, workers=1)["ran"] == 0


def test_the_sweep_command(tmp_path):
    spec = tmp_path / "grid.json"
    spec.write_text(json.dumps({"base": {"taps": 1}, "grid": {"renderer": ["impulse"]}}))
    out = tmp_path / "results.jsonl"
    done = subprocess.run([CLI, "sweep", "--spec", str(spec), "--out", str(out), "--workers", "1",
                           "--json"], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["ran"] == 1
    assert records(out)[0]["renderer"] == "impulse"
    spec.write_text(json.dumps({"grid": {"renderer": []}}))
    done = subprocess.run([CLI, "sweep", "--spec", str(spec), "--out", str(out)],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 2
    assert "rigidtouch: error: grid.renderer: an empty list" in done.stderr


def test_zwidth_figure_counts_the_passive_points(tmp_path):
    pytest.importorskip("matplotlib")
    from rigidtouch.figures import zwidth_figure
    made = [{"ok": True, "renderer": "penalty", "device": "omega3", "timestep_s": 0.001,
             "stiffness_N_per_m": k, "damping_Ns_per_m": b, "passive": b > k * 0.001 / 2}
            for k in (1000.0, 4000.0) for b in (0.0, 1.0, 3.0)]
    made.append({"ok": False, "params": {}, "error": "ValueError: x"})
    png = tmp_path / "z.png"
    assert zwidth_figure(made, str(png)) == {("penalty", "omega3"): (3, 6)}
    assert png.stat().st_size > 1000


class _Clock:
    def __init__(self):
        self.now = 100.0

    def __call__(self):
        return self.now


def test_progress_is_silent_at_first_then_a_line_every_two_seconds_with_the_time_left():
    import io
    clock = _Clock()
    out = io.StringIO()  # not a terminal: lines, not a bar
    progress = sw.Progress(stream=out, clock=clock)
    progress(1, 10)  # 0 s: nothing printed in the first 2 s
    clock.now += 1.5
    progress(2, 10)
    assert out.getvalue() == ""
    clock.now += 1.0  # 2.5 s: due
    progress(3, 10)
    clock.now += 1.0  # 3.5 s: less than 2 s after the last line
    progress(4, 10)
    clock.now += 1.0  # 4.5 s
    progress(5, 10)
    lines = out.getvalue().splitlines()
    assert len(lines) == 2, lines
    assert all(line.startswith("rigidtouch: progress: sweep: ") for line in lines)
    # 5 points in 4.5 s since the start, 5 left: about 4.5 s
    assert lines[1] == ("rigidtouch: progress: sweep: 50% (5 of 10 points), 4.5 s elapsed, "
                        "about 4.5 s left"), lines[1]
    progress.finish()  # no bar was drawn: nothing to end
    assert out.getvalue().count("\n") == 2


def test_progress_formats_durations_like_the_cli():
    assert sw._duration(0.44) == "0.4 s"
    assert sw._duration(12.2) == "12 s"
    assert sw._duration(185) == "3 min 05 s"
    assert sw._duration(2 * 3600 + 7 * 60) == "2 h 07 min"


def test_sweep_quiet_prints_no_progress(tmp_path):
    spec = tmp_path / "spec.json"
    spec.write_text(json.dumps({"base": {"taps": 1, "speed": 0.2, "device": "touch"},
                                "grid": {"renderer": ["penalty"]}}))
    out = tmp_path / "out.jsonl"
    r = subprocess.run([CLI, "sweep", "--spec", str(spec), "--out", str(out), "--workers", "1",
                        "--quiet", "--json"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert "progress" not in r.stderr
    assert json.loads(r.stdout)["ran"] == 1
