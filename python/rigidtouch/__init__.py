"""rigidtouch from Python: haptic rendering of rigid contact (penalty feedback plus passive
collision impulses), the simulated hand and device, the tap experiment, sweeps and studies.

The engine's C++ API in snake_case::

    import rigidtouch as rt
    model = rt.load_model("scenes/stack.xml")
    data = rt.make_data(model)
    command = rt.tick(model, data)            # one haptic tick; command["force_N"] in N
    rt.kinetic_energy(model, data)            # J

Articulated scenes: every tree's joints as numpy arrays, and scenes without a tool::

    model = rt.load_model("scenes/arm.xml", tool=None)
    data = rt.make_data(model)
    rt.run(model, data, 100)
    rt.joint_state(model, data)["position"]  # rad (hinges), m (slides)

The tap experiment, with the ``rigidtouch tap`` flags as keywords (``stiffness=3000`` is
``--stiffness 3000``), so every name the CLI takes (renderers, devices, materials, config files)
works here unchanged::

    result = rt.tap(renderer="train", stiffness=2000, speed=0.2, taps=1)
    result.metrics["taps"][0]["peak_force_N"]
    result.trace["device_fz_N"]               # numpy structured array, the trace CSV's columns
    result.frame()                            # the same as a pandas DataFrame

SI units throughout, the unit in every name. Errors in what you pass raise ValueError naming the
file, field or value.
"""

from ._rigidtouch import (  # noqa: F401  (re-exported)
    ContactParams,
    Data,
    DeviceParams,
    LoadOptions,
    Model,
    OutputError,
    RenderParams,
    SimulatedDevice,
    analyze_logs,
    contact_dtype,
    joint_state,
    kinetic_energy,
    load_model,
    make_data,
    reset_data,
    run,
    simulate_cohort,
    tick,
    trace_dtype,
)
from . import _rigidtouch

__all__ = [
    "ContactParams", "Data", "DeviceParams", "LoadOptions", "Model", "OutputError",
    "RenderParams", "SimulatedDevice", "TapResult", "analyze_logs", "configure", "contact_dtype",
    "fit_material", "joint_state", "kinetic_energy", "load_model", "make_data", "prepare_tap",
    "reset_data", "run", "simulate_cohort", "sweep", "tap", "tap_args", "tick", "trace_dtype",
]

_SECTIONS = {"contact": ContactParams, "render": RenderParams, "device": DeviceParams}


def _section(model, name, value):
    """A copy of the model's section `name` with the fields of `value` (a params object or a
    dict of field: value) applied; an unknown field or a value of the wrong type is a ValueError
    naming it."""
    if value is None or isinstance(value, _SECTIONS[name]):
        return value
    if not isinstance(value, dict):
        raise ValueError(f"{name}: expected {_SECTIONS[name].__name__} or a dict of fields, got "
                         f"{type(value).__name__}")
    params = getattr(model, name)
    valid = sorted(k for k in dir(params) if not k.startswith("_"))
    for field, v in value.items():
        if field not in valid:
            raise ValueError(f"{name}.{field}: unknown field; valid: {', '.join(valid)}")
        try:
            setattr(params, field, v)
        except (TypeError, ValueError) as e:
            raise ValueError(f"{name}.{field} = {v!r}: {e}") from None
    return params


def configure(model, *, contact=None, render=None, device=None):
    """Changes the contact law, the rendering or the device settings of `model` and validates
    them (the C++ Configure: derives the impulse schedule, Eq. 6 and Eq. 7).

    Each section is a ContactParams / RenderParams / DeviceParams or a dict of its fields, e.g.
    ``configure(model, contact={"stiffness_N_per_m": 3000.0}, render={"renderer": "impulse"})``
    (stiffness in N/m, damping in N s/m, times in s, frequencies in Hz, forces in N). A bad value
    raises ValueError naming the field and its valid range; the model is then unchanged."""
    _rigidtouch.configure(model, contact=_section(model, "contact", contact),
                          render=_section(model, "render", render),
                          device=_section(model, "device", device))


def tap_args(**params):
    """The ``rigidtouch tap`` command line of keyword parameters: ``name=value`` becomes
    ``--name value`` (underscores as dashes), True a bare flag, False and None nothing, a list or
    tuple its values in turn (``wall_point=(0, 0, 0)``). Floats are written exactly (repr)."""
    args = []
    for key, value in params.items():
        flag = "--" + key.replace("_", "-")
        if value is None or value is False:
            continue
        if value is True:
            args.append(flag)
            continue
        values = value if isinstance(value, (list, tuple)) else [value]
        args.append(flag)
        for v in values:
            args.append(repr(float(v)) if isinstance(v, float) else str(v))
    return args


class TapResult:
    """A tap run: ``metrics`` is the object ``rigidtouch tap --json`` prints (renderer,
    stiffness_N_per_m, damping_Ns_per_m, timestep_s, device, energy_to_user_J, one entry per tap
    in ``taps`` with peak_force_N, rate_hardness_N_per_m, max_penetration_m, time_to_stop_s,
    energy_to_user_J, ...) plus ``max_cumulative_energy_to_user_J`` [J], the largest running
    energy delivered to the user (<= 0 for a passive run). ``trace`` is a read-only numpy
    structured array, one row per tick, with the trace CSV's columns (units in the names)."""

    def __init__(self, metrics, trace):
        self.metrics = metrics
        self.trace = trace

    @property
    def taps(self):
        """Per-tap metrics, a list of dicts (units in the keys)."""
        return self.metrics["taps"]

    def frame(self):
        """The trace as a pandas DataFrame (a copy); raises ImportError without pandas."""
        import pandas
        return pandas.DataFrame(self.trace)

    def taps_frame(self):
        """The per-tap metrics as a pandas DataFrame (without the impulse lists)."""
        import pandas
        rows = [{k: v for k, v in t.items() if k not in ("impulses", "band_energy_fraction")}
                for t in self.taps]
        return pandas.DataFrame(rows)

    def __repr__(self):
        m = self.metrics
        return (f"TapResult(renderer={m['renderer']!r}, taps={len(m['taps'])}, "
                f"samples={len(self.trace)})")


def tap(*, check_finite=True, **params):
    """Runs the tap experiment in process with the ``rigidtouch tap`` flags as keywords (see
    tap_args): scene, renderer, wall, rate [Hz], device, coupling, speed [m/s], spread, taps,
    seed, stiffness [N/m], damping [N s/m], config, ... Settings resolve exactly as on the
    command line (flag > config > device preset > default). Releases the GIL while it runs.
    Returns a TapResult. Raises ValueError naming a bad flag or value; with check_finite, also
    when the simulated state went non-finite (else metrics["non_finite_state"] says so)."""
    native = _rigidtouch._tap(tap_args(**params))
    if check_finite and native.result.get("non_finite_state") is not None:
        raise ValueError("the simulated state became non-finite: "
                         f"{native.result['non_finite_state']}")
    return TapResult(native.result, native.trace)


def prepare_tap(**params):
    """The model and the simulated hand and device that ``tap(**params)`` would run, for a loop
    written in Python: ``(model, device, limits)``. Each tick: ``state = device.read()``,
    ``command = tick(model, data, state)``, ``device.write(command)``,
    ``device.end_period(model.timestep_s)``."""
    return _rigidtouch._prepare_tap(tap_args(**params))


def sweep(spec, out, *, scheduler=None, workers=None, progress=None):
    """Runs a sweep of tap experiments (see rigidtouch.sweeps.run_sweep)."""
    from .sweeps import run_sweep
    return run_sweep(spec, out, scheduler=scheduler, workers=workers, progress=progress)


def fit_material(taps, *, name="fitted", device="touch", rate_hz=1000.0, effective_mass_kg=0.0):
    """Fits a material to recorded taps, as ``rigidtouch material fit`` does (docs/materials.md).

    ``taps`` is a list of dicts, one per tap, of 1-D arrays (numpy or sequences) named like the
    recording's columns: ``time_s`` and one of ``acceleration_mps2`` and ``force_N``, with
    ``velocity_mps``, ``position_m`` or ``impact_speed_mps`` (an array or one number) for the
    impact speed. ``device``, ``rate_hz`` and ``effective_mass_kg`` are the CLI's ``--device``,
    ``--rate`` and ``--effective-mass-kg``. Returns the material file's content as a dict (write
    it with ``json.dump`` and any ``--material FILE.json`` reads it); the same numbers as the CLI
    on the same samples. A tap that cannot support a fit raises ValueError naming the tap and the
    sample ("NAME:SAMPLE: tap K: ...", samples counted from 1).
    """
    return _rigidtouch._fit_material(list(taps), name=name, device=device, rate_hz=rate_hz,
                                     effective_mass_kg=effective_mass_kg)
