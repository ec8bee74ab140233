"""The Python bindings against the C++ engine and CLI: ticks bit for bit, the tap experiment's
trace and metrics, errors. Run by scripts/test.sh against the installed module; RIGIDTOUCH_CLI
names the CLI built from the same tree (default: build/rigidtouch)."""

import csv
import json
import os
import subprocess
import threading

import numpy as np
import pytest

import rigidtouch as rt

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))
STACK = os.path.join(ROOT, "scenes", "stack.xml")
# one short tap: enough for a contact, an impulse train and the metrics, fast
TAP = dict(taps=1, speed=0.2, renderer="train", device="touch")


def cli(*args):
    done = subprocess.run([CLI, *args], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_tick_equals_the_cli_bit_for_bit_on_the_stack():
    # the CLI prints doubles round-trip exactly (JSON shortest form), so == is bit for bit
    steps = 400
    out = json.loads(cli("simulate", "--scene", STACK, "--steps", str(steps), "--tool-force",
                         "0", "0", "-2", "--json"))
    model = rt.load_model(STACK)
    data = rt.make_data(model)
    impulses = []
    for _ in range(steps):
        rt.tick(model, data, tool_force_N=[0.0, 0.0, -2.0])
        impulses += data.impulses
    assert data.step == steps and data.time_s == out["time_s"]
    assert model.body_names == [b["name"] for b in out["bodies"]]
    for k, body in enumerate(out["bodies"]):
        assert data.x_W[k].tolist() == body["position_m"], body["name"]
        assert data.v_W[k].tolist() == body["velocity_mps"], body["name"]
        assert data.w_W[k].tolist() == body["angular_velocity_radps"], body["name"]
    assert [e["kinetic_energy_after_J"] for e in impulses] == [
        e["kinetic_energy_after_J"] for e in out["impulses"]]
    assert len(impulses) > 0  # the tool's fall onto the stack starts collision windows
    # run() (the loop in C++, without the GIL) is the same tick
    rt.reset_data(model, data)
    rt.run(model, data, steps, tool_force_N=[0.0, 0.0, -2.0])
    assert data.x_W[model.tool].tolist() == out["bodies"][model.tool]["position_m"]


def test_two_threads_step_the_pile_as_one_does():
    # the 100-box pile's groups and pairs are shared with a worker thread: the same bits
    pile = os.path.join(ROOT, "scenes", "pile.xml")
    states = []
    for threads in (1, 2):
        options = rt.LoadOptions()
        options.threads = threads
        model = rt.load_model(pile, options)
        data = rt.make_data(model)
        rt.run(model, data, 300, tool_force_N=[0.0, 0.0, -2.0])
        states.append((data.x_W.tolist(), data.v_W.tolist(), data.w_W.tolist()))
    assert states[0] == states[1]
    options.threads = 3
    with pytest.raises(ValueError, match="threads is 3"):
        rt.load_model(pile, options)


def test_state_arrays_are_live_views():
    model = rt.load_model(STACK)
    data = rt.make_data(model)
    x = data.x_W
    assert x.shape == (model.nbody, 3) and data.q_WB_xyzw.shape == (model.nbody, 4)
    z0 = x[model.tool, 2]
    rt.run(model, data, 50)
    assert x[model.tool, 2] < z0  # the same memory, moved by the ticks: no copy
    assert np.shares_memory(x, data.x_W)
    np.testing.assert_allclose(np.linalg.norm(data.q_WB_xyzw, axis=1), 1.0, atol=1e-12)
    # a state written from Python is what the next tick starts from
    rt.reset_data(model, data)
    data.v_W[model.tool] = [0.0, 0.0, -1.0]
    rt.tick(model, data)
    assert data.x_W[model.tool, 2] < 0.506 - 0.9 * model.timestep_s
    # contacts: a read-only structured view of this tick's contacts
    rt.reset_data(model, data)
    rt.run(model, data, 5)
    c = data.contacts
    assert len(c) == data.ncontact > 0
    assert set(rt.contact_dtype().names) >= {"p_W", "n_W", "depth_m", "normal_force_N"}
    assert not c.flags.writeable
    np.testing.assert_allclose(np.linalg.norm(c["n_W"], axis=1), 1.0, atol=1e-12)
    assert rt.kinetic_energy(model, data) >= 0.0


def test_kinetic_energy_is_the_closed_form():
    # after one tick in free fall from rest the tool alone moves: E = m v^2 / 2
    model = rt.load_model(STACK)
    data = rt.make_data(model)
    data.x_W[model.tool] = [1.0, 1.0, 1.0]  # far from the stack: no contact
    rt.tick(model, data)
    v = data.v_W[model.tool]
    m = model.body_masses_kg[model.tool]
    assert rt.kinetic_energy(model, data) >= 0.5 * m * float(v @ v) * (1 - 1e-12)


def test_bad_input_raises_value_error_naming_it():
    with pytest.raises(ValueError, match="no_such_scene.xml"):
        rt.load_model("no_such_scene.xml")
    model = rt.load_model(STACK)
    before = model.contact.stiffness_N_per_m
    with pytest.raises(ValueError, match="stiffness_N_per_m"):
        rt.configure(model, contact={"stiffness_N_per_m": -5.0})
    assert model.contact.stiffness_N_per_m == before  # refused: the model is unchanged
    with pytest.raises(ValueError, match="contact.stiffnes: unknown field"):
        rt.configure(model, contact={"stiffnes": 5.0})
    with pytest.raises(ValueError, match="render.renderer"):
        rt.configure(model, render={"renderer": "no-such-renderer"})
    with pytest.raises(ValueError, match="--speed"):
        rt.tap(**dict(TAP, speed=5.0))
    with pytest.raises(ValueError, match="--no-such-flag"):
        rt.tap(no_such_flag=1)
    with pytest.raises(ValueError, match="unknown field 'speed'"):
        rt.tick(model, rt.make_data(model), device_state={"speed": 1})
    rt.configure(model, contact={"stiffness_N_per_m": 3000.0}, render={"renderer": "impulse"})
    assert model.contact.stiffness_N_per_m == 3000.0 and model.render.renderer == "impulse"


def test_data_of_another_model_is_refused_before_the_tick():
    # a Data sized for the wall, stepped with the stack's model, was read and written past its
    # buffers (a crash); now every call that takes both refuses it
    wall = rt.load_model(os.path.join(ROOT, "scenes", "wall.xml"))
    stack = rt.load_model(STACK)
    wall_data = rt.make_data(wall)
    for call in (lambda: rt.tick(stack, wall_data), lambda: rt.run(stack, wall_data, 1),
                 lambda: rt.reset_data(stack, wall_data),
                 lambda: rt.kinetic_energy(stack, wall_data)):
        with pytest.raises(ValueError, match="not made by make_data for this model"):
            call()
    # another load of the same file is another model too; the data's own model still works
    with pytest.raises(ValueError, match="make_data"):
        rt.tick(rt.load_model(os.path.join(ROOT, "scenes", "wall.xml")), wall_data)
    rt.configure(wall, contact={"stiffness_N_per_m": 3000.0})
    rt.tick(wall, wall_data)
    assert wall_data.step == 1


def test_tap_equals_the_cli_tap(tmp_path):
    # the same flags through the same settings resolution: the same run, to the last bit
    trace_csv = tmp_path / "trace.csv"
    flags = rt.tap_args(**TAP)
    printed = json.loads(cli("tap", *flags, "--json", "--trace", str(trace_csv)))
    result = rt.tap(**TAP)
    for key in ("renderer", "stiffness_N_per_m", "damping_Ns_per_m", "timestep_s", "device",
                "energy_to_user_J", "taps"):
        assert result.metrics[key] == printed[key], key
    # the trace: the CSV's columns, in its order, with the same values
    with open(trace_csv) as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    assert list(result.trace.dtype.names) == header
    assert len(result.trace) == len(body)
    for k, name in enumerate(header):
        column = result.trace[name]
        assert [float(r[k]) for r in body] == column.astype(float).tolist(), name
    # units: every column carries its SI unit, or is a count, a flag or a unit normal
    dimensionless = {"wall_nx", "wall_ny", "wall_nz", "tool_contacts", "impulses", "clipped",
                     "tap", "step"}
    for name in header:
        assert name in dimensionless or name.rsplit("_", 1)[1] in ("s", "m", "mps", "N", "J"), name
    assert not result.trace.flags.writeable
    assert result.taps[0]["contact"] and result.taps[0]["peak_force_N"] > 0.0


def test_trace_as_dataframe():
    pandas = pytest.importorskip("pandas")
    result = rt.tap(**TAP)
    frame = result.frame()
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame.columns) == list(rt.trace_dtype().names)
    assert frame["device_fz_N"].max() == result.trace["device_fz_N"].max()
    assert len(result.taps_frame()) == 1


def test_python_loop_on_the_simulated_device_equals_tap():
    # the hand, device and tick driven from Python give the tap experiment's trace bit for bit
    model, device, limits = rt.prepare_tap(**TAP)
    assert limits["name"] == "touch"
    data = rt.make_data(model)
    forces, positions = [], []
    while not device.finished:
        state = device.read()
        command = rt.tick(model, data, state)
        device.write(command)
        positions.append(device.true_position_m[2])
        forces.append(device.displayed_force_N[2])
        device.end_period(model.timestep_s)
    trace = rt.tap(**TAP).trace
    assert forces == trace["device_fz_N"].tolist()
    assert positions == trace["tool_z_m"].tolist()


def test_tap_releases_the_gil():
    # while the tap runs in C++ on another thread, this one keeps counting; with the GIL held
    # through the run the count would not move between its start and end
    counter = [0]
    seen = {}
    done = threading.Event()

    def work():
        seen["before"] = counter[0]
        rt.tap(**dict(TAP, taps=3))
        seen["after"] = counter[0]
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    while not done.is_set():
        counter[0] += 1
    thread.join()
    assert seen["after"] - seen["before"] > 1000


def test_settings_resolve_as_on_the_command_line(tmp_path):
    # a config file's field is used, a flag overrides it, and an error says where a value was set
    config = tmp_path / "k.json"
    config.write_text(json.dumps({"contact": {"stiffness_N_per_m": 321.0}}))
    assert rt.tap(config=str(config), **TAP).metrics["stiffness_N_per_m"] == 321.0
    assert rt.tap(config=str(config), stiffness=350.0, **TAP).metrics["stiffness_N_per_m"] == 350.0
    config.write_text(json.dumps({"render": {"t_collision_s": 0.5}}))
    with pytest.raises(ValueError, match=r"t_collision_s.*set in .*k\.json"):
        rt.tap(config=str(config), **TAP)
    # load options: nested sections are edited in place, then used by load_model
    options = rt.LoadOptions()
    options.contact.stiffness_N_per_m = 1234.0
    options.render.renderer = "impulse"
    model = rt.load_model(STACK, options)
    assert model.contact.stiffness_N_per_m == 1234.0 and model.render.renderer == "impulse"
    with pytest.raises(ValueError, match="none.json"):
        rt.load_model(STACK, options, config=str(tmp_path / "none.json"))
