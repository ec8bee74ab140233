"""bench/scale_goals.py: the large scenes' time goals judged against the machine's own tail."""

import importlib.util
import json
import os
import subprocess
import sys

import pytest

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))
SCRIPT = os.path.join(ROOT, "bench", "scale_goals.py")

_spec = importlib.util.spec_from_file_location("scale_goals", SCRIPT)
sg = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sg)


def bench_report(median_us, p999_us, job_p999_us):
    tails = {"steps": {"p999": p999_us / median_us}, "job": {"p999": job_p999_us / median_us}}
    return {"median_ns": median_us * 1e3, "p999_ns": p999_us * 1e3,
            "reference": {"median_ns": median_us * 1e3, "p999_ns": job_p999_us * 1e3,
                          "tail_over_median": tails}}


def test_a_value_within_its_goal_is_met_whatever_the_machine():
    assert sg.judge(499.0, 500.0) == sg.MET
    assert sg.judge(500.0, 500.0) == sg.MET
    assert sg.judge(900.0, 1000.0, floor_us=3000.0) == sg.MET


def test_a_tail_the_fixed_job_also_misses_is_not_judgeable():
    assert sg.judge(1500.0, 1000.0, floor_us=1200.0) == sg.NOT_JUDGEABLE
    # the machine's floor within the goal: the step's own tail missed it
    assert sg.judge(1500.0, 1000.0, floor_us=900.0) == sg.MISSED
    # a median has no floor
    assert sg.judge(501.0, 500.0) == sg.MISSED


def test_rows_of_a_scene_report():
    rows = sg.scene_goals("pile1000", bench_report(450.0, 1400.0, 1300.0), 500.0, 1000.0)
    assert [r["verdict"] for r in rows] == [sg.MET, sg.NOT_JUDGEABLE]
    assert rows[0]["machine_us"] is None
    assert rows[1]["measured_us"] == pytest.approx(1400.0)
    assert rows[1]["machine_us"] == pytest.approx(1300.0)
    assert rows[1]["p999_over_median"] == pytest.approx({"steps": 1400.0 / 450.0,
                                                         "fixed_job": 1300.0 / 450.0})
    rows = sg.scene_goals("pile2000", bench_report(1100.0, 2000.0, 1200.0), 1000.0)
    assert [r["verdict"] for r in rows] == [sg.MISSED]


def test_the_loop_goal_is_strictly_under_20_us_and_names_what_the_machine_allowed():
    loop = {"period_error_p99_s": 20e-6, "realtime_priority_active": False,
            "memory_locked": True, "pinned_cpu": 1}
    row = sg.loop_goal({"loop": loop})
    assert row["verdict"] == sg.MISSED
    assert row["allowed"] == {"realtime_priority_active": False, "memory_locked": True,
                              "pinned_cpu": 1}
    loop["period_error_p99_s"] = 19e-6
    assert sg.loop_goal({"loop": loop})["verdict"] == sg.MET


def test_exit_status_from_the_verdicts():
    def rows(*verdicts):
        return [{"verdict": v} for v in verdicts]
    assert sg.status(rows(sg.MET, sg.MET)) == 0
    assert sg.status(rows(sg.MET, sg.NOT_JUDGEABLE)) == 3
    assert sg.status(rows(sg.NOT_JUDGEABLE, sg.MISSED, sg.MET)) == 1


def run_script(*args):
    return subprocess.run([sys.executable, SCRIPT, "--cli", CLI, *args], capture_output=True,
                          text=True, timeout=600)


def test_the_script_runs_both_scenes_and_its_status_follows_its_verdicts():
    proc = run_script("--scenes", os.path.join(ROOT, "scenes"), "--steps", "30", "--warmup", "200",
                      "--serve-seconds", "0", "--threads", "1", "--json")
    assert proc.returncode in (0, 1, 3), proc.stderr
    out = json.loads(proc.stdout)
    assert out["threads"] == 1
    goals = [r["goal"] for r in out["goals"]]
    assert goals == ["pile1000 median <= 500 us", "pile1000 p99.9 <= 1000 us",
                     "pile2000 median <= 1000 us"]
    for r in out["goals"]:
        assert r["measured_us"] > 0.0
        assert r["verdict"] == sg.judge(r["measured_us"], float(r["goal"].split()[-2]),
                                        r["machine_us"])
    assert out["status"] == proc.returncode == sg.status(out["goals"])


def test_a_failed_run_is_named_and_nothing_is_judged(tmp_path):
    proc = run_script("--scenes", str(tmp_path), "--steps", "10", "--serve-seconds", "0")
    assert proc.returncode == 2
    assert proc.stdout == ""
    assert proc.stderr.startswith("scale_goals: ")
    assert os.path.join(str(tmp_path), "pile1000.xml") in proc.stderr


def test_bad_arguments_are_refused_with_the_values():
    proc = run_script("--steps", "0")
    assert proc.returncode == 2
    assert "--steps must be at least 1" in proc.stderr and "got 0, 2000, 10.0" in proc.stderr
    proc = run_script("--warmup", "199")
    assert proc.returncode == 2
    assert "--warmup at least 200" in proc.stderr and "got 5000, 199, 10.0" in proc.stderr
