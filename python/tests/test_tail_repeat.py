"""bench/tail_repeat.py: a deterministic run twice, its slow steps compared step by step."""

import importlib.util
import json
import os
import subprocess
import sys

import numpy as np
import pytest

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
SCRIPT = os.path.join(ROOT, "bench", "tail_repeat.py")

_spec = importlib.util.spec_from_file_location("tail_repeat", SCRIPT)
tr = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(tr)


def test_slow_steps_at_the_same_indices_are_counted_in_both():
    a = np.full(1000, 100.0)
    b = np.full(1000, 100.0)
    a[[10, 500, 900]] = 300.0  # three steps slow in both runs: their own work
    b[[10, 500, 900]] = 280.0
    a[10], b[10] = 400.0, 380.0  # the slowest of each
    a[[20, 30]] = 250.0  # slow in one run only: the machine
    b[[40, 50, 60]] = 250.0
    out = tr.compare(a, b)
    # above the p99 (the 10 slowest of 1000, ties included): a has 5, b 6 slow steps
    assert out["above_p99"] == {"steps": 5, "in_both": 3, "by_chance": pytest.approx(5 * 6 / 1000)}
    assert out["above_p999"] == {"steps": 1, "in_both": 1, "by_chance": pytest.approx(0.001)}
    assert out["runs"][0]["median_us"] == pytest.approx(100.0)


def test_unrelated_runs_share_about_what_chance_gives():
    rng = np.random.default_rng(7)
    a, b = rng.exponential(size=100000), rng.exponential(size=100000)
    out = tr.compare(a, b)
    assert abs(out["rank_correlation"]) < 0.02  # 1/sqrt(n) = 0.003
    s = out["above_p99"]
    assert s["by_chance"] == pytest.approx(10.0, rel=0.01)
    assert s["in_both"] < 30  # 10 expected, standard deviation about 3


def test_identical_runs_share_every_slow_step():
    a = np.random.default_rng(3).exponential(size=5000)
    out = tr.compare(a, a.copy())
    assert out["rank_correlation"] == pytest.approx(1.0)
    assert out["above_p99"]["in_both"] == out["above_p99"]["steps"] == 50


def run_script(*args):
    # the environment, PYTHONPATH with it, is inherited: the script imports rigidtouch
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True,
                          timeout=600)


def test_the_script_times_two_runs_of_a_scene():
    proc = run_script(os.path.join(ROOT, "scenes", "pile.xml"), "--steps", "200", "--warmup",
                      "50", "--threads", "1", "--json")
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert len(out["runs"]) == 2
    for r in out["runs"]:
        assert 0.0 < r["median_us"] <= r["p99_us"] <= r["p999_us"]
    assert out["above_p99"]["steps"] == 2  # 200 distinct times: the two slowest are above p99


def test_a_scene_that_does_not_load_is_named(tmp_path):
    missing = str(tmp_path / "none.xml")
    proc = run_script(missing, "--steps", "5")
    assert proc.returncode == 2
    assert proc.stderr.startswith("tail_repeat: ") and missing in proc.stderr


def test_bad_arguments_are_refused_with_the_values():
    proc = run_script("scene.xml", "--steps", "1")
    assert proc.returncode == 2
    assert "--steps must be at least 2" in proc.stderr and "got 1, 2000" in proc.stderr
