"""A worked example of rigidtouch from Python, notebook style (docs/python.md): the engine tick by
tick, the tap experiment and its trace, a small Z-width sweep with its figure, and a power
analysis. Run after building with -DRIGIDTOUCH_BUILD_PYTHON=ON and installing:

    PYTHONPATH=PREFIX/lib/python3/dist-packages python3 examples/python/worked_example.py \
        --out-dir out/python

scripts/test.sh runs it (about 15 s on 2 cores)."""

import argparse
import os
import tempfile

import numpy as np

import rigidtouch as rt
from rigidtouch.figures import zwidth_figure
from rigidtouch.power import power_analysis

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--out-dir", help="default: a new temporary directory")
    # made only when no folder is given (a default of mkdtemp() would make one on every run)
    out_dir = parser.parse_args().out_dir or tempfile.mkdtemp(prefix="rigidtouch-example-")
    os.makedirs(out_dir, exist_ok=True)

    # %% 1. The engine, one tick at a time: a tool pushed onto a stack of boxes with 2 N
    model = rt.load_model(os.path.join(ROOT, "scenes", "stack.xml"))
    data = rt.make_data(model)
    print(f"{model.nbody} bodies, h = {model.timestep_s} s, renderer {model.render.renderer}")
    for _ in range(300):
        command = rt.tick(model, data, tool_force_N=[0.0, 0.0, -2.0])
    tool = model.tool
    print(f"after {data.time_s:.3f} s: tool at z = {data.x_W[tool, 2]:.4f} m, "
          f"{data.ncontact} contacts, kinetic energy {rt.kinetic_energy(model, data):.2e} J")
    print("deepest contact:", f"{data.contacts['depth_m'].max():.2e} m")

    # %% 2. Change the contact law; a bad value names the field and leaves the model as it was
    rt.configure(model, contact={"stiffness_N_per_m": 3000.0, "damping_Ns_per_m": 3.0})
    try:
        rt.configure(model, render={"t_collision_s": 0.5})
    except ValueError as e:
        print("refused:", e)

    # %% 3. The tap experiment: the simulated hand taps a wall on the simulated omega3 device
    for renderer in ("penalty", "train"):
        result = rt.tap(renderer=renderer, device="omega3", taps=2, speed=0.2)
        first = result.taps[0]
        print(f"{renderer:8s} peak {first['peak_force_N']:.2f} N, rate hardness "
              f"{first['rate_hardness_N_per_m']:.0f} N/m, penetration "
              f"{1e3 * first['max_penetration_m']:.2f} mm")
    trace = result.trace  # numpy structured array, the trace CSV's columns
    contact = trace[trace["tool_contacts"] > 0]
    print(f"train: {len(trace)} ticks, {len(contact)} in contact, "
          f"{int(trace['impulses'].sum())} impulses, largest impulsive force "
          f"{np.abs(trace['impulsive_fz_N']).max():.2f} N")
    try:
        print(result.frame()[["time_s", "tool_z_m", "device_fz_N"]].describe().loc[["min", "max"]])
    except ImportError:
        print("(pandas not installed: no DataFrame)")

    # %% 4. A small Z-width sweep on two local Dask workers, and its figure
    spec = {"base": {"taps": 1, "speed": 0.2, "device": "omega3"},
            "grid": {"renderer": ["penalty", "train"],
                     "stiffness": {"logspace": [2.5, 4.5, 5]},
                     "damping": [0.0, 2.0, 4.0, 8.0]}}
    results = os.path.join(out_dir, "zwidth.jsonl")
    if os.path.exists(results):
        os.remove(results)
    summary = rt.sweep(spec, results, workers=2)
    print(f"sweep: {summary['ran']} points in {summary['wall_time_s']:.1f} s")
    for (renderer, device), (passive, n) in zwidth_figure(
            results, os.path.join(out_dir, "zwidth.png")).items():
        print(f"  {renderer} on {device}: {passive} of {n} points passive")

    # %% 5. How many participants does the method's study need? (a small pool, to be quick)
    power = power_analysis(os.path.join(ROOT, "studies", "walls.json"), pool=8, cohorts=200)
    for test in power["tests"]:
        print(f"{test['name']}: {test['participants_needed']} participants for 80 % power")
    print("figures and results in", out_dir)


# the guard matters: the sweep's Dask workers are new processes that import this file
if __name__ == "__main__":
    main()
