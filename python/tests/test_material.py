"""rigidtouch.fit_material against `rigidtouch material fit`: the same samples give the same
material (docs/materials.md). RIGIDTOUCH_CLI names the CLI built from the same tree."""

import json
import os
import subprocess

import numpy as np
import pytest

import rigidtouch as rt

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))


def read_taps(path):
    """The recording's taps as dicts of arrays, split on the tap column."""
    with open(path, encoding="utf-8") as f:
        lines = [line for line in f if line.strip() and not line.startswith("#")]
    names = lines[0].strip().split(",")
    values = np.array([[float(x) for x in line.split(",")] for line in lines[1:]])
    columns = {name: values[:, i] for i, name in enumerate(names)}
    taps = []
    for k in np.unique(columns["tap"]):
        rows = columns["tap"] == k
        taps.append({"time_s": columns["time_s"][rows],
                     "acceleration_mps2": columns["acceleration_mps2"][rows],
                     "velocity_mps": columns["velocity_mps"][rows]})
    return taps


def test_fit_material_gives_the_clis_material(tmp_path):
    csv = tmp_path / "wood.csv"
    out = tmp_path / "wood.json"
    subprocess.run([CLI, "material", "synth", "wood", "--out", str(csv)], check=True)
    done = subprocess.run([CLI, "material", "fit", str(csv), "--out", str(out), "--json"],
                          capture_output=True, text=True, check=True)
    from_cli = json.loads(done.stdout)["material"]
    from_python = rt.fit_material(read_taps(csv), name="wood")
    for key in ("amplitude_Ns_per_m", "decay_per_s", "frequency_hz", "amplitude_mps2_per_mps",
                "effective_mass_kg"):
        # the same doubles in, the same arithmetic: equal to rounding (1e-12 relative)
        assert from_python[key] == pytest.approx(from_cli[key], rel=1e-12), key
    assert from_python["fit"]["taps"] == 5
    # and the dict is a material file --material reads
    path = tmp_path / "from_python.json"
    path.write_text(json.dumps(from_python))
    done = subprocess.run([CLI, "tap", "--renderer", "event", "--material", str(path), "--taps",
                           "1", "--json"],
                          capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["material"] == "wood"


def test_fit_material_errors_name_the_tap_and_sample():
    t = np.arange(400) / 2000.0
    flat = {"time_s": t, "force_N": np.zeros(400) + 0.01 * np.sin(t * 7e3), "impact_speed_mps": 0.2}
    with pytest.raises(ValueError, match="tap 0"):
        rt.fit_material([flat])
    with pytest.raises(ValueError, match="exactly one of"):
        rt.fit_material([{"time_s": t}])
    bad = {"time_s": t, "force_N": np.full(400, np.nan), "velocity_mps": np.zeros(400)}
    with pytest.raises(ValueError, match="not a finite number"):
        rt.fit_material([bad])


def test_an_acceleration_material_is_converted_for_the_device_as_the_cli_does(tmp_path):
    """A material fitted from acceleration on the Touch (0.599 kg) and rendered on a device of
    apparent mass 0.645 kg (effective 1.199 kg): rt.tap renders the amplitude the CLI renders,
    the recorded acceleration times the device's effective mass (docs/materials.md)."""
    csv = tmp_path / "wood.csv"
    subprocess.run([CLI, "material", "synth", "wood", "--out", str(csv)], check=True)
    material = rt.fit_material(read_taps(csv), name="wood")
    path = tmp_path / "wood.json"
    path.write_text(json.dumps(material))
    device = tmp_path / "heavy.json"
    device.write_text(json.dumps({
        "name": "heavy", "max_force_N": 0, "max_stiffness_N_per_m": 400,
        "max_damping_Ns_per_m": 4, "apparent_mass_kg": 0.645, "encoder_resolution_m": 5.5e-5,
        "velocity_filter_hz": 100, "delay_ticks": 0}))
    flags = ["tap", "--renderer", "event", "--material", str(path), "--device", str(device),
             "--taps", "1", "--json"]
    done = subprocess.run([CLI] + flags, capture_output=True, text=True, check=True)
    from_cli = json.loads(done.stdout)
    assert "rigidtouch: note: material 'wood'" in done.stderr
    from_python = rt.tap(renderer="event", material=str(path), device=str(device), taps=1)
    rendered = material["amplitude_mps2_per_mps"] * (0.645 + 0.554)
    assert from_cli["material_amplitude_Ns_per_m"] == pytest.approx(rendered, rel=1e-12)
    assert from_python.metrics["material_amplitude_Ns_per_m"] == \
        from_cli["material_amplitude_Ns_per_m"]
    assert from_python.metrics["material_effective_mass_kg"] == pytest.approx(1.199, rel=1e-12)
    # the same tap: the same peak force to the last bit the JSON prints
    assert from_python.taps[0]["peak_force_N"] == from_cli["taps"][0]["peak_force_N"]
