"""Sweeps of the tap experiment over a grid of parameters, on Dask.

A spec (JSON file or dict)::

    {"base": {"taps": 1, "device": "touch", "speed": 0.2},
     "grid": {"renderer": ["penalty", "train"],
              "stiffness": {"logspace": [2, 4, 40]},
              "damping": {"linspace": [0, 4, 25]}}}

Every point is ``base`` plus one combination of the ``grid`` values (the product, in the spec's
key order; a value is a list, or ``{"linspace": [lo, hi, n]}`` / ``{"logspace": [lo, hi, n]}``
as numpy makes them). The keys are the ``rigidtouch tap`` flags (``stiffness`` is
``--stiffness``, ``device`` takes a preset name or a device file, ``config`` a config file), so
a point means what the same flags mean on the command line and a new renderer, material or device
name needs no change here.

Each point runs as one Dask task: on a LocalCluster of worker processes by default, or on an
existing cluster given its scheduler address (``tcp://HOST:8786``): the same code either way.
Each finished point is appended to the output as one JSON line and flushed, so an interrupted
sweep resumes where it stopped: points already in the file (done or failed) are skipped, a torn
last line is dropped, no point is run twice into the file. A point whose run fails is recorded
with its error.

Command line: ``python3 -m rigidtouch.sweeps --spec grid.json --out results.jsonl
[--scheduler tcp://HOST:8786 | --workers N]`` (also ``rigidtouch sweep ...``).
"""

import argparse
import itertools
import json
import math
import os
import sys
import time

# a run is passive when the energy it delivered to the user never rose above this [J]
PASSIVE_TOLERANCE_J = 1e-9


class SpecError(ValueError):
    """A bad sweep spec; the message names the field."""


def _values(key, value):
    if isinstance(value, list):
        if not value:
            raise SpecError(f"grid.{key}: an empty list")
        return value
    if isinstance(value, dict) and len(value) == 1:
        (kind, args), = value.items()
        if kind in ("linspace", "logspace"):
            if (not isinstance(args, list) or len(args) != 3
                    or not all(isinstance(a, (int, float)) for a in args)
                    or int(args[2]) != args[2] or args[2] < 1):
                raise SpecError(f"grid.{key}.{kind}: expected [lo, hi, n] with n a positive "
                                f"integer, got {args!r}")
            import numpy
            f = numpy.linspace if kind == "linspace" else numpy.logspace
            return [float(v) for v in f(args[0], args[1], int(args[2]))]
    raise SpecError(f"grid.{key}: expected a list of values or {{\"linspace\"|\"logspace\": "
                    f"[lo, hi, n]}}, got {value!r}")


def load_spec(spec):
    """The spec as a dict: `spec` itself, or the JSON file it names."""
    if isinstance(spec, dict):
        return spec
    try:
        with open(spec) as f:
            data = json.load(f)
    except OSError as e:
        raise SpecError(f"cannot read the sweep spec '{spec}': {e.strerror}") from None
    except json.JSONDecodeError as e:
        raise SpecError(f"sweep spec '{spec}' is not JSON: {e}") from None
    if not isinstance(data, dict):
        raise SpecError(f"sweep spec '{spec}': expected a JSON object")
    return data


def points(spec):
    """The sweep's points in order: a list of dicts of tap flags."""
    where = f"sweep spec '{spec}'" if isinstance(spec, (str, os.PathLike)) else "sweep spec"
    spec = load_spec(spec)
    unknown = set(spec) - {"base", "grid", "description"}
    if unknown:
        raise SpecError(f"{where}: unknown field(s) {', '.join(sorted(unknown))}; valid: "
                        "base, grid, description")
    base = spec.get("base", {})
    grid = spec.get("grid", {})
    if not isinstance(base, dict) or not isinstance(grid, dict):
        raise SpecError(f"{where}: base and grid must be objects")
    for key in list(base) + list(grid):
        if key in ("trace", "plot", "json", "compare_walls", "out_dir"):
            raise SpecError(f"{where}: '{key}' writes files or prints; a sweep records "
                            "metrics only")
    from rigidtouch import _rigidtouch
    flags = set(_rigidtouch._tap_flag_names())
    for part, section in (("base", base), ("grid", grid)):
        for key in section:
            flag = key.replace("_", "-")
            if flag not in flags:
                raise SpecError(f"{where}: {part}.{key} is not a flag of tap (--{flag}); "
                                "see `rigidtouch tap --help`")
    both = set(base) & set(grid)
    if both:
        raise SpecError(f"{where}: {', '.join(sorted(both))} in both base and grid")
    keys = list(grid)
    axes = [_values(k, grid[k]) for k in keys]
    return [dict(base, **dict(zip(keys, combo))) for combo in itertools.product(*axes)]


def point_key(params):
    """Canonical text of a point's parameters: how the output file names a point."""
    return json.dumps(params, sort_keys=True, separators=(",", ":"))


def _mean(values):
    finite = [v for v in values if v is not None and not (isinstance(v, float) and math.isnan(v))]
    return sum(finite) / len(finite) if finite else None


def run_point(index, params):
    """Runs one point in this process; returns its record (never raises)."""
    import rigidtouch
    record = {"point": index, "key": point_key(params), "params": params}
    start = time.perf_counter()
    try:
        result = rigidtouch.tap(check_finite=False, **params)
    except Exception as e:  # a failing point is recorded with its error, the sweep goes on
        record.update(ok=False, error=f"{type(e).__name__}: {e}",
                      seconds=time.perf_counter() - start)
        return record
    m = result.metrics
    taps = m["taps"]
    non_finite = m.get("non_finite_state")
    keep = ("renderer", "restitution", "frequency_hz", "t_collision_s", "impulses_per_window",
            "timestep_s", "device", "max_force_N", "coupling", "stiffness_N_per_m",
            "damping_Ns_per_m", "tool_mass_kg", "energy_to_user_J",
            "max_cumulative_energy_to_user_J", "clipped_ticks", "clipped_impulse_ticks",
            "warnings")
    record.update({k: m[k] for k in keep if k in m})
    record.update(
        ok=True,
        non_finite_state=non_finite,
        passive=(non_finite is None
                 and m["max_cumulative_energy_to_user_J"] <= PASSIVE_TOLERANCE_J),
        taps=len(taps),
        contact=all(t["contact"] for t in taps),
        peak_force_N=_mean([t["peak_force_N"] for t in taps]),
        rate_hardness_N_per_m=_mean([t["rate_hardness_N_per_m"] for t in taps]),
        extended_rate_hardness_N_per_m=_mean([t["extended_rate_hardness_N_per_m"] for t in taps]),
        max_penetration_m=_mean([t["max_penetration_m"] for t in taps]),
        approach_speed_mps=_mean([t["approach_speed_mps"] for t in taps]),
        bounces=sum(t["bounces"] for t in taps),
        tap_energy_to_user_J=[t["energy_to_user_J"] for t in taps],
        seconds=time.perf_counter() - start)
    return record


def _run_batch(batch):
    return [run_point(i, p) for i, p in batch]


def read_done(out):
    """Keys of the points already recorded in `out`; a torn last line (an interrupted write) is
    cut off the file first."""
    done = set()
    if not os.path.exists(out):
        return done
    with open(out, "rb+") as f:
        data = f.read()
        good = data.rfind(b"\n") + 1  # whole lines end with a newline
        if good < len(data):
            f.truncate(good)
        for n, line in enumerate(data[:good].splitlines(), 1):
            try:
                done.add(json.loads(line)["key"])
            except (ValueError, KeyError):
                raise SpecError(f"{out}: line {n} is not a sweep record; not a results file of "
                                "a sweep?") from None
    return done


def _client(scheduler, workers):
    # the workers' start-up chatter stays out of the sweep's output (set before dask loads;
    # local workers inherit it)
    os.environ.setdefault("DASK_LOGGING__DISTRIBUTED", "warning")
    from dask.distributed import Client, LocalCluster
    if scheduler:
        return Client(scheduler, timeout="30s"), None
    cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1,
                           processes=True, dashboard_address=None)
    return Client(cluster), cluster


def run_sweep(spec, out, *, scheduler=None, workers=None, batch=None, progress=None):
    """Runs every point of `spec` not yet in `out` (JSON lines, appended and flushed per point)
    on Dask: the cluster at `scheduler` ("tcp://HOST:8786"), else a LocalCluster of `workers`
    processes (default: one per core). Points go out in batches of `batch` (default: about 8 per
    worker, at most 20 points) to keep the scheduler's per-task overhead small. `progress(done,
    total)` is called after each point. Returns a summary dict."""
    todo_all = points(spec)
    keys = [point_key(p) for p in todo_all]
    if len(set(keys)) != len(keys):
        raise SpecError("sweep spec: two points have the same parameters")
    done = read_done(out)
    open(out, "a").close()  # an output that cannot be written fails now, before the cluster starts
    todo = [(i, p) for i, (p, k) in enumerate(zip(todo_all, keys)) if k not in done]
    summary = {"points": len(todo_all), "already_done": len(todo_all) - len(todo), "ran": 0,
               "failed": 0, "out": out}
    if not todo:
        return summary
    from dask.distributed import as_completed
    try:
        client, cluster = _client(scheduler, workers)
    except OSError as e:
        if not scheduler:
            raise
        raise SpecError(f"--scheduler {scheduler}: cannot reach the Dask scheduler ({e})") from None
    start = time.perf_counter()
    try:
        nworkers = max(1, len(client.scheduler_info()["workers"]))
        size = batch or max(1, min(20, len(todo) // (8 * nworkers)))
        batches = [todo[k:k + size] for k in range(0, len(todo), size)]
        futures = client.map(_run_batch, batches, pure=False)
        with open(out, "a") as f:
            for future in as_completed(futures):
                for record in future.result():
                    f.write(json.dumps(record) + "\n")
                    f.flush()
                    summary["ran"] += 1
                    summary["failed"] += 0 if record["ok"] else 1
                    if progress:
                        progress(summary["already_done"] + summary["ran"], len(todo_all))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    summary["wall_time_s"] = time.perf_counter() - start
    summary["workers"] = nworkers
    return summary


def read_results(out):
    """The records of a results file, as a list of dicts (a pandas DataFrame: pandas.DataFrame
    of it)."""
    with open(out) as f:
        return [json.loads(line) for line in f if line.endswith("\n")]


def _duration(seconds):
    """A duration for people, as the C++ tool writes it ("0.4 s", "12 s", "3 min 05 s")."""
    seconds = max(0.0, seconds)
    if seconds < 9.95:
        return f"{seconds:.1f} s"
    if seconds < 59.5:
        return f"{seconds:.0f} s"
    if seconds < 3599.5:
        s = round(seconds)
        return f"{s // 60} min {s % 60:02d} s"
    m = round(seconds / 60)
    return f"{m // 60} h {m % 60:02d} min"


class Progress:
    """Progress of a sweep on stderr, as the C++ subcommands report theirs: nothing in the first
    2 s, then a bar redrawn in place on a terminal, else a line at most every 2 s. Call it with
    (done, total) after each point (run_sweep's `progress`)."""

    def __init__(self, stream=None, clock=time.monotonic, first_after_s=2.0, every_s=2.0):
        self.stream = stream or sys.stderr
        self.clock = clock
        self.start = clock()
        self.first_after_s = first_after_s
        self.every_s = 0.1 if self._terminal() else every_s
        self.origin = None  # (time, done) of the first report: the rate's origin
        self.last = None
        self.printed = 0
        self.bar_open = False

    def _terminal(self):
        try:
            return self.stream.isatty()
        except (AttributeError, ValueError):
            return False

    def text(self, done, total, now):
        fraction = done / total if total else 1.0
        text = (f"{int(100 * fraction)}% ({done} of {total} points), "
                f"{_duration(now - self.start)} elapsed")
        t0, d0 = self.origin
        if done > d0 and now > t0:
            text += f", about {_duration((total - done) * (now - t0) / (done - d0))} left"
        else:
            text += ", estimating the time left"
        return text

    def __call__(self, done, total):
        now = self.clock()
        if self.origin is None:
            # the rate counts from the start and the points before this run's first one (those
            # already in the results file do not count as fast)
            self.origin = (self.start, done - 1 if done > 0 else 0)
        if now - self.start < self.first_after_s:
            return
        if self.last is not None and now - self.last < self.every_s:
            return
        self.last = now
        self.printed += 1
        if self._terminal():
            width = 24
            filled = int(width * done / total) if total else width
            self.stream.write(f"\r\033[Ksweep [{'#' * filled}{'.' * (width - filled)}] "
                              f"{self.text(done, total, now)}")
            self.bar_open = True
        else:
            self.stream.write(f"rigidtouch: progress: sweep: {self.text(done, total, now)}\n")
        self.stream.flush()

    def finish(self):
        if self.bar_open:
            self.stream.write("\n")
            self.stream.flush()
            self.bar_open = False


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        # the project's one voice for errors: prefix, status 2
        self.exit(2, f"rigidtouch: error: {message}\nRun `{self.prog} --help` for the options.\n")


def main(argv=None):
    parser = _Parser(
        prog="rigidtouch sweep",
        description="Sweep the tap experiment over a grid of parameters on Dask; results are "
                    "appended per point (JSON lines), so a rerun resumes where it stopped.")
    parser.add_argument("--spec", required=True, help="sweep spec (JSON)")
    parser.add_argument("--out", required=True, help="results file (JSON lines), appended")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--scheduler", help="an existing Dask scheduler, tcp://HOST:8786")
    where.add_argument("--workers", type=int,
                       help="local worker processes (default: one per core)")
    parser.add_argument("--batch", type=int, help="points per Dask task")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--quiet", action="store_true", help="print no progress on stderr")
    args = parser.parse_args(argv)
    if args.workers is not None and args.workers < 1:
        parser.error(f"--workers {args.workers}: valid 1 or more")
    progress = None if args.quiet else Progress()
    try:
        summary = run_sweep(args.spec, args.out, scheduler=args.scheduler,
                            workers=args.workers, batch=args.batch, progress=progress)
    except KeyboardInterrupt:
        # Ctrl-C: every point finished so far is in the results file; a rerun resumes
        if progress:
            progress.finish()
        print(f"rigidtouch: interrupted: sweep stopped; the points finished are in {args.out}: "
              "run the same command again to continue", file=sys.stderr)
        return 130
    except SpecError as e:
        print(f"rigidtouch: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:
        print(f"rigidtouch: error: {args.out}: {e.strerror or e}", file=sys.stderr)
        return 2
    except Exception as e:  # the README's status 3: an internal error (e.g. the cluster failed)
        print(f"rigidtouch: internal error: {type(e).__name__}: {e}", file=sys.stderr)
        return 3
    if progress:
        progress.finish()
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{summary['ran']} point(s) run ({summary['failed']} failed), "
              f"{summary['already_done']} already in {args.out}, of {summary['points']}"
              + (f"; {summary['wall_time_s']:.1f} s on {summary['workers']} worker(s)"
                 if "wall_time_s" in summary else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
