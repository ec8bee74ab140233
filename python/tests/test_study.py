"""The study toolkit from Python against the CLI, and the power analysis's statistics."""

import json
import math
import os
import subprocess

import pytest

import rigidtouch as rt
from rigidtouch import power

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))
WALLS = os.path.join(ROOT, "studies", "walls.json")


def test_simulate_cohort_equals_the_cli(tmp_path):
    done = subprocess.run([CLI, "study", "simulate", "--protocol", WALLS, "--participants", "2",
                           "--seed", "7", "--log-dir", str(tmp_path), "--json"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    printed = json.loads(done.stdout)
    report = rt.simulate_cohort(WALLS, 2, 7)
    assert report["tests"] == printed["tests"]
    # the logs the CLI wrote, analysed from Python: the same numbers
    logs = sorted(str(p) for p in tmp_path.iterdir())
    analysed = rt.analyze_logs(logs)
    for a, b in zip(analysed["tests"], printed["tests"]):
        assert a["mean_percent_correct"] == b["mean_percent_correct"]
    with pytest.raises(ValueError, match="participants = 0"):
        rt.simulate_cohort(WALLS, 0, 1)
    with pytest.raises(ValueError, match="no_such_protocol.json"):
        rt.simulate_cohort("no_such_protocol.json", 1, 1)


def test_t_tail_closed_forms():
    # df = 1 is Cauchy: P(T > t) = 1/2 - atan(t)/pi; df = 2: (1 - t / sqrt(t^2 + 2)) / 2
    for t in (-3.0, -0.5, 0.0, 0.7, 2.0, 6.314, 40.0):
        assert power.t_sf(t, 1) == pytest.approx(0.5 - math.atan(t) / math.pi, rel=1e-12, abs=1e-15)
        assert power.t_sf(t, 2) == pytest.approx((1 - t / math.sqrt(t * t + 2)) / 2, rel=1e-12,
                                                 abs=1e-15)
    # large df tends to the normal tail: 1 - Phi(1.644853627) = 0.05
    assert power.t_sf(1.6448536269514722, 1e7) == pytest.approx(0.05, rel=1e-5)


def test_power_grows_with_the_effect():
    # no effect: about alpha of the cohorts are significant whatever n; a large one: power 1
    import random
    rng = random.Random(3)
    null = [50 + rng.gauss(0, 10) for _ in range(400)]
    hits = sum(power.one_sided_t_p(rng.sample(null, 10), 50.0) < 0.05 for _ in range(2000))
    assert 0.03 < hits / 2000 < 0.07
    strong = [80 + rng.gauss(0, 10) for _ in range(400)]
    assert power.one_sided_t_p(strong[:5], 50.0) < 0.01
