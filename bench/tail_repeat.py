#!/usr/bin/env python3
"""Whose tail is it: the same deterministic run twice, its slow steps compared step by step.

Usage: PYTHONPATH=build/python tail_repeat.py SCENE.xml [--threads 2] [--steps 4000]
                                              [--warmup 2000] [--json]

A scene's steps are the same work in every run (the results are the same bit for bit, on one
thread or two), so a step that is slow because of its own work (an impulse, a refactorisation) is
slow in both runs, at the same index, while a step slowed by the machine (another tenant, an
interruption) is not. The script loads the scene twice, runs the warm-up in C++, times every
measured step (`rigidtouch.tick`, the tool pushed down with 2 N as in the benchmarks) and prints
each run's median, p99 and p99.9, the rank correlation of the two runs' step times, and how many
of the steps above each run's p99 and p99.9 are the same steps, against the number two unrelated
runs would share by chance.
"""
import argparse
import json
import sys
import time

import numpy as np

import rigidtouch as rt

TOOL_FORCE_N = [0.0, 0.0, -2.0]


def step_times_us(scene, threads, steps, warmup):
    """The wall time of each measured step of one run [us]."""
    options = rt.LoadOptions()
    options.threads = threads
    model = rt.load_model(scene, options)
    data = rt.make_data(model)
    rt.run(model, data, warmup, tool_force_N=TOOL_FORCE_N)
    t = np.empty(steps)
    for k in range(steps):
        start = time.perf_counter_ns()
        rt.tick(model, data, tool_force_N=TOOL_FORCE_N)
        t[k] = time.perf_counter_ns() - start
    return t / 1e3


def compare(a, b):
    """The two runs' statistics and how their slow steps coincide."""
    out = {'runs': [{'median_us': float(np.median(t)), 'p99_us': float(np.percentile(t, 99)),
                     'p999_us': float(np.percentile(t, 99.9))} for t in (a, b)]}
    ranks_a, ranks_b = a.argsort().argsort(), b.argsort().argsort()
    out['rank_correlation'] = float(np.corrcoef(ranks_a, ranks_b)[0, 1])
    n = len(a)
    for name, q in (('p99', 99.0), ('p999', 99.9)):
        slow_a, slow_b = a > np.percentile(a, q), b > np.percentile(b, q)
        out[f'above_{name}'] = {'steps': int(slow_a.sum()), 'in_both': int((slow_a & slow_b).sum()),
                                'by_chance': float(slow_a.sum() * slow_b.sum() / n)}
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('scene')
    p.add_argument('--threads', type=int, default=2, choices=(1, 2))
    p.add_argument('--steps', type=int, default=4000)
    p.add_argument('--warmup', type=int, default=2000)
    p.add_argument('--json', action='store_true')
    args = p.parse_args(argv)
    if args.steps < 2 or args.warmup < 0:
        p.error(f'--steps must be at least 2 and --warmup at least 0 (got {args.steps}, '
                f'{args.warmup})')
    try:
        runs = [step_times_us(args.scene, args.threads, args.steps, args.warmup) for _ in range(2)]
    except ValueError as e:
        print(f'tail_repeat: {e}', file=sys.stderr)
        return 2
    out = compare(*runs)
    if args.json:
        print(json.dumps(out, indent=1))
        return 0
    for i, r in enumerate(out['runs']):
        print(f'run {i + 1}: median {r["median_us"]:.0f} us, p99 {r["p99_us"]:.0f} us, '
              f'p99.9 {r["p999_us"]:.0f} us')
    print(f'rank correlation of the step times: {out["rank_correlation"]:.3f}')
    for name in ('p99', 'p999'):
        s = out[f'above_{name}']
        print(f'steps above {name.replace("999", "99.9")} in both runs: {s["in_both"]} of '
              f'{s["steps"]} (by chance {s["by_chance"]:.1f})')
    return 0


if __name__ == '__main__':
    sys.exit(main())
