"""Articulated scenes from Python: the joint state as numpy arrays equal, bit for bit, to what
`rigidtouch simulate --json` lists for the same steps, and scenes loaded without a tool."""

import json
import math
import os
import subprocess

import numpy as np
import pytest

import rigidtouch as rt

ROOT = os.environ.get("RIGIDTOUCH_SOURCE_DIR",
                      os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..")))
CLI = os.environ.get("RIGIDTOUCH_CLI", os.path.join(ROOT, "build", "rigidtouch"))
ARM = os.path.join(ROOT, "scenes", "arm.xml")
DOOR = os.path.join(ROOT, "scenes", "door.xml")


def cli(*args):
    done = subprocess.run([CLI, *args], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_arm_joint_state_equals_the_cli_bit_for_bit():
    # the CLI prints doubles round-trip exactly (JSON shortest form), so == is bit for bit
    steps = 300
    out = json.loads(cli("simulate", "--scene", ARM, "--tool", "none", "--steps", str(steps),
                         "--json"))
    model = rt.load_model(ARM, tool=None)
    assert not model.has_tool
    data = rt.make_data(model)
    for _ in range(steps // 2):  # tick and run step alike
        rt.tick(model, data)
    rt.run(model, data, steps - steps // 2)
    state = rt.joint_state(model, data)
    joints = out["joints"]
    assert state["names"] == [j["name"] for j in joints] == [
        "base_yaw", "shoulder", "elbow", "wrist_roll", "wrist_pitch", "hand_roll"]
    assert state["types"] == ["hinge"] * 6
    assert isinstance(state["position"], np.ndarray) and state["position"].shape == (6,)
    assert state["position"].tolist() == [j["position"] for j in joints]
    assert state["velocity"].tolist() == [j["velocity"] for j in joints]
    assert state["at_limit"].tolist() == [j["at_limit"] for j in joints]
    # the arm sagged under gravity: the shoulder moved, so the comparison is not of zeros
    assert abs(state["position"][1]) > 1e-3
    # the ranges as the MJCF gives them (radians), every joint limited (autolimits)
    assert state["range"].shape == (6, 2)
    assert state["range"][1].tolist() == [-2.0, 2.0]
    assert state["range"][0].tolist() == [-2.9, 2.9]
    assert state["limited"].all()
    # qpos and qvel hold the same numbers at the joints' addresses
    assert data.qpos[model.joint_qpos_adr].tolist() == state["position"].tolist()
    assert data.qvel[model.joint_dof_adr].tolist() == state["velocity"].tolist()
    assert model.joint_names == state["names"] and model.joint_types == state["types"]


def test_door_hinge_range_and_limit():
    model = rt.load_model(DOOR)  # with its tool
    assert model.has_tool
    data = rt.make_data(model)
    rt.run(model, data, 10)
    state = rt.joint_state(model, data)
    assert state["names"] == ["hinge"]
    lo, hi = state["range"][0]
    assert lo == pytest.approx(-100.0 * math.pi / 180.0, abs=1e-12)
    assert hi == 0.0
    assert state["at_limit"][0]  # resting closed against its stop
    assert abs(state["position"][0]) < 1e-3


def test_tool_none_and_its_errors():
    model = rt.load_model(ARM, tool=None)
    data = rt.make_data(model)
    with pytest.raises(ValueError, match="tool=None"):
        rt.tick(model, data, tool_force_N=[0.0, 0.0, -1.0])
    with pytest.raises(ValueError, match="tool=None"):
        rt.run(model, data, 1, tool_force_N=[1.0, 0.0, 0.0])
    rt.tick(model, data, tool_force_N=[0.0, 0.0, 0.0])  # no push: fine
    with pytest.raises(ValueError, match="tool must be"):
        rt.load_model(ARM, tool=3)
    with pytest.raises(ValueError, match="'hand' is a link"):
        rt.load_model(ARM, tool="hand")
    # a scene without trees has no joints: empty arrays, not errors
    flat = rt.load_model(os.path.join(ROOT, "scenes", "stack.xml"))
    flat_state = rt.joint_state(flat, rt.make_data(flat))
    assert flat_state["names"] == [] and flat_state["position"].shape == (0,)
    assert flat_state["range"].shape == (0, 2)
