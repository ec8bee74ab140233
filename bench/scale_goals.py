#!/usr/bin/env python3
"""Judges the large scenes' time goals on this machine, with the machine's own tail beside them.

Usage: scale_goals.py [--cli build/rigidtouch] [--scenes scenes] [--threads 2] [--steps 5000]
                      [--warmup 2000] [--serve-seconds 10] [--serve-cpu 1] [--json]

The goals (docs/performance.md, "Large scenes"):
  pile1000: median step at most 0.5 ms and p99.9 at most 1 ms;
  pile2000: median step at most 1 ms;
  the 10 kHz loop (`rigidtouch serve --device sim --rate 10000 --realtime`): p99 period error
  under 20 us.
Each scene runs `rigidtouch bench --reference --json` (a tool force of 2 N down, as in the
benchmarks): after every step the same fixed job, sized to the median step, is timed too. A tail
goal that the fixed job itself misses is "not judgeable here": the machine alone gives work of
that length a longer tail than the goal allows, whatever the step does. A median is met or
missed; on a machine shared with other work, missed may be the machine (the ratio to Bullet in
`rigidtouch_bench --rigidtouch_large` does not depend on it).

Exit status: 0 every goal met; 1 some goal missed; 3 none missed, some not judgeable;
2 a run failed (its command and error output are printed; nothing is judged).
"""
import argparse
import json
import os
import subprocess
import sys

MET, MISSED, NOT_JUDGEABLE = 'met', 'missed', 'not judgeable here'


class RunFailed(Exception):
    pass


def run_json(cmd):
    """Runs cmd and returns its standard output parsed as one JSON object."""
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RunFailed(f'{" ".join(cmd)} exited with {proc.returncode}:\n{proc.stderr.strip()}')
    try:
        return json.loads(proc.stdout)
    except json.JSONDecodeError as e:
        raise RunFailed(f'{" ".join(cmd)} printed no JSON object ({e})') from e


def judge(value_us, goal_us, floor_us=None):
    """The verdict on one measured value against its goal (both in microseconds). floor_us is
    what the machine alone gives the same fixed work (its own tail), if known."""
    if value_us <= goal_us:
        return MET
    if floor_us is not None and floor_us > goal_us:
        return NOT_JUDGEABLE
    return MISSED


def scene_goals(name, report, median_goal_us, p999_goal_us=None):
    """The goal rows of one `bench --reference --json` report."""
    # a median has no floor: the fixed job is sized to it
    rows = [{'goal': f'{name} median <= {median_goal_us:g} us',
             'measured_us': report['median_ns'] / 1e3, 'machine_us': None,
             'verdict': judge(report['median_ns'] / 1e3, median_goal_us)}]
    if p999_goal_us is not None:
        floor = report['reference']['p999_ns'] / 1e3
        tails = report['reference']['tail_over_median']
        rows.append({'goal': f'{name} p99.9 <= {p999_goal_us:g} us',
                     'measured_us': report['p999_ns'] / 1e3, 'machine_us': floor,
                     'verdict': judge(report['p999_ns'] / 1e3, p999_goal_us, floor),
                     'p999_over_median': {'steps': tails['steps']['p999'],
                                          'fixed_job': tails['job']['p999']}})
    return rows


def loop_goal(report, goal_us=20.0):
    """The goal row of one `serve --json` report, with what the machine allowed."""
    loop = report['loop']
    allowed = {k: loop[k] for k in ('realtime_priority_active', 'memory_locked', 'pinned_cpu')}
    return {'goal': f'10 kHz loop p99 period error < {goal_us:g} us',
            'measured_us': loop['period_error_p99_s'] * 1e6, 'machine_us': None,
            'verdict': MET if loop['period_error_p99_s'] * 1e6 < goal_us else MISSED,
            'allowed': allowed}


def status(rows):
    verdicts = {r['verdict'] for r in rows}
    if MISSED in verdicts:
        return 1
    return 3 if NOT_JUDGEABLE in verdicts else 0


def measure(args):
    rows = []
    for name, median_goal, p999_goal in (('pile1000', 500.0, 1000.0), ('pile2000', 1000.0, None)):
        scene = os.path.join(args.scenes, f'{name}.xml')
        report = run_json([args.cli, 'bench', '--scene', scene, '--threads', str(args.threads),
                           '--steps', str(args.steps), '--warmup', str(args.warmup),
                           '--tool-force', '0', '0', '-2', '--reference', '--json'])
        rows += scene_goals(name, report, median_goal, p999_goal)
    if args.serve_seconds > 0:
        cmd = [args.cli, 'serve', '--device', 'sim', '--rate', '10000', '--duration',
               str(args.serve_seconds), '--taps', str(max(1, round(args.serve_seconds))),
               '--realtime', '--spin-us', '20', '--json']
        if args.serve_cpu >= 0:
            cmd += ['--cpu', str(args.serve_cpu)]
        rows.append(loop_goal(run_json(cmd)))
    return rows


def print_table(rows, threads):
    print(f'the scenes stepped on {threads} thread{"s" if threads > 1 else ""}')
    print(f'{"goal":<40} {"measured [us]":>14} {"fixed job p99.9 [us]":>21}  verdict')
    for r in rows:
        machine = '' if r['machine_us'] is None else f'{r["machine_us"]:.1f}'
        print(f'{r["goal"]:<40} {r["measured_us"]:>14.1f} {machine:>21}  {r["verdict"]}')
        if 'p999_over_median' in r:
            t = r['p999_over_median']
            print(f'  p99.9 / median: steps {t["steps"]:.2f}, fixed job {t["fixed_job"]:.2f}')
        if 'allowed' in r:
            print('  the machine allowed: ' +
                  ', '.join(f'{k} {v}' for k, v in r['allowed'].items()))
    print('fixed job: the same work timed after every step, sized to the median step; its p99.9 '
          'is the tail the machine alone gives work of that length')


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    p.add_argument('--cli', default=os.path.join('build', 'rigidtouch'),
                   help='the rigidtouch binary (default build/rigidtouch)')
    p.add_argument('--scenes', default='scenes',
                   help='folder with pile1000.xml and pile2000.xml (default scenes)')
    p.add_argument('--threads', type=int, default=2, choices=(1, 2))
    p.add_argument('--steps', type=int, default=5000, help='measured steps per scene')
    p.add_argument('--warmup', type=int, default=2000,
                   help='warm-up steps per scene, at least 200 (the fixed job is sized to the '
                   'median of the last 200)')
    p.add_argument('--serve-seconds', type=float, default=10.0,
                   help='length of the 10 kHz loop run [s]; 0 leaves the loop out')
    p.add_argument('--serve-cpu', type=int, default=1,
                   help='CPU the loop thread is pinned to; -1 leaves it unpinned')
    p.add_argument('--json', action='store_true', help='print the rows as one JSON object')
    args = p.parse_args(argv)
    if args.steps < 1 or args.warmup < 200 or args.serve_seconds < 0:
        p.error(f'--steps must be at least 1, --warmup at least 200, --serve-seconds at least 0 '
                f'(got {args.steps}, {args.warmup}, {args.serve_seconds})')
    try:
        rows = measure(args)
    except (RunFailed, OSError) as e:
        print(f'scale_goals: {e}', file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps({'threads': args.threads, 'goals': rows, 'status': status(rows)},
                         indent=1))
    else:
        print_table(rows, args.threads)
    return status(rows)


if __name__ == '__main__':
    sys.exit(main())
