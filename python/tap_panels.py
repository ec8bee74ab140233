"""Panels shared by the tap figures (plot_tap.py, plot_walls.py): the force the device displayed
against the force limit, a zoom on contact onset, penetration and velocity, and the spectrum of
the displayed force and of its transient part. The spectrum is computed as rigidtouch's metrics
compute it (src/analysis/spectrum.cc): over the collision window from onset, mean removed, flat
window with a half-cosine over its last quarter, zero-padded to a power of two, one-sided power.
"""

import json
import math

import trace_io

BAND_EDGES_HZ = (40.0, 100.0, 400.0)


def tap_series(columns, tap, before_ms, after_ms):
    """The rows of one tap from before_ms before contact onset to after_ms after it, as lists,
    plus the whole tap's collision-window samples for the spectrum."""
    rows = trace_io.tap_rows(columns, tap)
    time_s = columns["time_s"]
    penalty = trace_io.normal_component(columns, "penalty_f", "N")
    impulsive = trace_io.normal_component(columns, "impulsive_f", "N")
    displayed = trace_io.normal_component(columns, "device_f", "N")
    velocity = trace_io.normal_component(columns, "tool_v", "mps")
    onset = next((i for i in rows if columns["tool_contacts"][i] > 0), rows[0])
    t0 = time_s[onset]
    # the tolerance keeps both end ticks despite the rounding of times in the trace
    shown = [i for i in rows if -before_ms - 1e-6 <= (time_s[i] - t0) * 1e3 <= after_ms + 1e-6]
    s = {
        "t_ms": [(time_s[i] - t0) * 1e3 for i in shown],
        "displayed_N": [displayed[i] for i in shown],
        "requested_N": [penalty[i] + impulsive[i] for i in shown],
        "penalty_N": [penalty[i] for i in shown],
        "impulsive_N": [impulsive[i] for i in shown],
        "penetration_mm": [columns["penetration_m"][i] * 1e3 for i in shown],
        # along the outward normal: negative while approaching the wall
        "velocity_mm_per_s": [velocity[i] * 1e3 for i in shown],
        "impulse_ms": [(time_s[i] - t0) * 1e3 for i in shown if columns["impulses"][i] > 0],
        "requested_peak_N": max(penalty[i] + impulsive[i] for i in rows),
        "displayed_peak_N": max(displayed[i] for i in rows),
        "onset_s": t0,
    }
    # as the metrics: 100 ms from onset, with a tolerance for the rounding of trace times
    window = [i for i in rows if i >= onset and time_s[i] - t0 < 0.1 - 1e-9]
    s["window_displayed_N"] = [displayed[i] for i in window]
    s["window_transient_N"] = [displayed[i] - penalty[i] for i in window]
    s["sample_rate_hz"] = ((len(window) - 1) / (time_s[window[-1]] - t0)
                           if len(window) > 1 and time_s[window[-1]] > t0 else 0.0)
    return s


def power_spectrum(signal, sample_rate_hz):
    """(frequencies [Hz], one-sided power [N^2]) as rigidtouch's PowerSpectrum with the
    tapered-end window the tap metrics use."""
    import numpy as np
    n = len(signal)
    if n < 2 or sample_rate_hz <= 0:
        return [], []
    x = np.asarray(signal, dtype=float)
    x = x - x.mean()
    i = np.arange(n)
    w = np.ones(n)
    start = 0.75 * (n - 1)
    tail = i > start
    w[tail] = 0.5 * (1.0 + np.cos(np.pi * (i[tail] - start) / (n - 1 - start)))
    length = 1
    while length < n:
        length *= 2
    power = np.abs(np.fft.rfft(w * x, length)) ** 2
    power[1:-1] *= 2.0  # fold the negative frequencies (not DC or Nyquist)
    return list(np.arange(len(power)) * sample_rate_hz / length), list(power)


def _limit_line(ax, s, limit_n):
    if limit_n > 0:
        line = ax.axhline(limit_n, color="tab:red", linestyle=":", linewidth=1.2,
                          label=f"device limit {limit_n:g} N")
        s["limit_line_N"] = line.get_ydata()[0]  # what was drawn, for the dump


def _force_ylim(ax, s, limit_n, parts=False):
    top = max(max(s["displayed_N"], default=0.0), limit_n) * 1.15 or 1.0
    # every drawn curve's negative lobe is inside (an event transient swings below zero)
    drawn = s["displayed_N"] + (s["impulsive_N"] + s["requested_N"] if parts else [])
    bottom = min(0.0, min(drawn, default=0.0)) * 1.15 - 0.03 * top
    ax.set_ylim(bottom, top)
    if s["requested_peak_N"] > top:
        ax.annotate(f"requested peak {s['requested_peak_N']:.1f} N (off scale)",
                    xy=(0.98, 0.97), xycoords="axes fraction", ha="right", va="top",
                    fontsize=7, color="tab:orange")


def draw_force(ax, s, limit_n, parts=False, zoom_ms=None, legend=True,
               parts_label="impulses (Eq. 9 force)"):
    """Displayed force (always), requested force, optionally its parts (the penalty part and
    `parts_label`, what the renderer adds: impulses, or an event transient), the device limit."""
    t, d = s["t_ms"], s["displayed_N"]
    if zoom_ms is not None:
        keep = [k for k, x in enumerate(t) if x <= zoom_ms]
        t = [t[k] for k in keep]
        d = [d[k] for k in keep]
        sub = {key: [s[key][k] for k in keep]
               for key in ("requested_N", "penalty_N", "impulsive_N")}
    else:
        sub = s
    # forces are held over each tick (zero-order hold): steps
    ax.step(t, sub["requested_N"], where="post", color="tab:orange", linewidth=1.0,
            linestyle="--", label="requested (before limit)")
    if parts:
        ax.step(t, sub["penalty_N"], where="post", color="tab:blue", linewidth=0.9,
                label="penalty part")
        ax.step(t, sub["impulsive_N"], where="post", color="tab:green", linewidth=0.9,
                label=parts_label)
    ax.step(t, d, where="post", color="black", linewidth=1.3, label="displayed")
    _limit_line(ax, s, limit_n)
    if zoom_ms is not None:
        for k, x in enumerate(m for m in s["impulse_ms"] if m <= zoom_ms):
            ax.axvline(x, color="0.6", linestyle=":", linewidth=0.7,
                       label="impulse instant" if k == 0 else None)
        ax.set_xlim(min(t, default=-5.0), zoom_ms)
    _force_ylim(ax, s, limit_n, parts)
    ax.set_ylabel("force along normal [N]")
    ax.grid(True, alpha=0.3)
    if legend:
        # the force is back at zero between the first contact and a re-contact
        ax.legend(loc="upper right" if zoom_ms is not None else "center right", fontsize=7)


def draw_material_model(ax, model, zoom_ms, samples=800):
    """The material's decaying sinusoid, Q(t) = A v e^(-B t) sin(2 pi f t) from the contact onset
    over `zoom_ms`, dashed over the rendered force, with its own legend; returns what it drew."""
    a, b = model["amplitude_Ns_per_m"], model["decay_per_s"]
    f, v = model["frequency_hz"], model["impact_speed_mps"]
    t_ms = [zoom_ms * k / (samples - 1) for k in range(samples)]
    q = [a * v * math.exp(-b * t / 1e3) * math.sin(2.0 * math.pi * f * t / 1e3) for t in t_ms]
    label = (f"material model {model['name']}: A v e^(-Bt) sin(2\u03c0ft), "
             f"A v = {a * v:.3g} N, B = {b:.3g} 1/s, f = {f:.3g} Hz")
    line, = ax.plot(t_ms, q, color="tab:red", linestyle="--", linewidth=1.0, label=label)
    low, high = ax.get_ylim()
    ax.set_ylim(min(low, 1.1 * min(q)), max(high, 1.1 * max(q)))
    ax.legend(handles=[line], loc="lower right", fontsize=6)
    return dict(model, t_ms=t_ms, force_N=q)


def draw_motion(ax, s, legend=True):
    """Penetration (left axis) and velocity along the outward normal (right axis)."""
    ax.plot(s["t_ms"], s["penetration_mm"], color="tab:purple", linewidth=1.2,
            label="penetration")
    ax.set_ylabel("penetration [mm]", color="tab:purple")
    ax.grid(True, alpha=0.3)
    right = ax.twinx()
    right.plot(s["t_ms"], s["velocity_mm_per_s"], color="tab:cyan", linewidth=1.0,
               label="velocity along normal")
    right.axhline(0.0, color="0.7", linewidth=0.6)
    right.set_ylabel("velocity along normal [mm/s]", color="tab:cyan")
    if legend:
        lines = ax.get_lines()[:1] + right.get_lines()[:1]
        # where the curves leave room: before onset the penetration is 0, the velocity at its lowest
        ax.legend(lines, [line.get_label() for line in lines], loc="upper left", fontsize=7)
    return right


def draw_spectrum(ax, s, legend=True, repetition=None):
    """Power of the displayed force and of its transient part (displayed minus penalty) over
    the collision window, in dB relative to the displayed force's largest bin. `repetition` is
    the transient's repetition rate as rigidtouch's tap metrics give it ("250 Hz", "none" or
    "-"): the figure states it, it does not estimate its own."""
    f_d, p_d = power_spectrum(s["window_displayed_N"], s["sample_rate_hz"])
    f_t, p_t = power_spectrum(s["window_transient_N"], s["sample_rate_hz"])
    ref = max(p_d[1:], default=0.0) or 1.0
    floor = -60.0

    def db(p):
        return [max(floor, 10.0 * math.log10(x / ref)) if x > 0 else floor for x in p]

    s["spectrum"] = {"freq_hz": f_d, "displayed_power": p_d, "transient_power": p_t,
                     "transient_repetition": repetition}
    ax.plot(f_d[1:], db(p_d[1:]), color="black", linewidth=1.2, label="displayed")
    if any(x > 0 for x in p_t[1:]):
        label = "transient part"
        if repetition is not None:
            label += f" (repetition: {repetition})"
        ax.plot(f_t[1:], db(p_t[1:]), color="tab:orange", linewidth=1.0, label=label)
    else:
        ax.text(0.97, 0.95, "no transient part (no impulses)", transform=ax.transAxes,
                ha="right", va="top", fontsize=7)
    for edge in BAND_EDGES_HZ:
        ax.axvline(edge, color="0.8", linewidth=0.6)
    ax.set_ylim(floor, 5.0)
    ax.set_xlim(0.0, max(f_d, default=500.0))
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("power [dB re displayed peak]")
    ax.grid(True, alpha=0.3)
    if legend:
        ax.legend(loc="lower left", fontsize=7)


def joint_series(path, tap, onset_s):
    """A moving wall's joint over one tap from rigidtouch's joint CSV (time_s, tap, position,
    velocity, impulse; a hinge in rad, a slide in m): time from contact onset [ms], position and
    velocity in degrees (hinge) or millimetres (slide)."""
    import csv
    try:
        with open(path, newline="") as handle:
            reader = csv.reader(handle)
            header = next(reader)
            rows = [[float(x) for x in row] for row in reader if row]
    except (OSError, StopIteration, ValueError) as error:
        raise SystemExit(f"error: cannot read joint trace '{path}': {error}")
    hinge = header[2] == "position_rad"
    scale = 180.0 / math.pi if hinge else 1e3
    unit = "deg" if hinge else "mm"
    mine = [r for r in rows if int(r[1]) == tap]
    return {
        "t_ms": [(r[0] - onset_s) * 1e3 for r in mine],
        "position": [r[2] * scale for r in mine],
        "velocity": [r[3] * scale for r in mine],
        "position_unit": unit,
        "velocity_unit": unit + "/s",
        "hinge": hinge,
    }


def draw_joint(ax, j, legend=True):
    """A moving wall's joint: its position (left axis) and velocity (right axis) over the tap."""
    what = "angle" if j["hinge"] else "position"
    ax.plot(j["t_ms"], j["position"], color="tab:brown", linewidth=1.2, label=f"joint {what}")
    ax.set_ylabel(f"joint {what} [{j['position_unit']}]", color="tab:brown")
    ax.set_xlabel("time from contact onset [ms]")
    ax.grid(True, alpha=0.3)
    right = ax.twinx()
    right.plot(j["t_ms"], j["velocity"], color="tab:olive", linewidth=1.0,
               label="joint velocity")
    right.axhline(0.0, color="0.7", linewidth=0.6)
    right.set_ylabel(f"joint velocity [{j['velocity_unit']}]", color="tab:olive")
    if legend:
        lines = ax.get_lines()[:1] + right.get_lines()[:1]
        ax.legend(lines, [line.get_label() for line in lines], loc="best", fontsize=7)
    return right


def spectrum_title(window_ms, resolution_hz):
    """The spectrum panel's title: the window and resolution the tap metrics used."""
    if window_ms is None:
        return "spectrum from contact onset"
    return f"spectrum, {window_ms} ms from onset ({resolution_hz} Hz resolution)"


def dump(path, panels, limit_n):
    """Writes what the figure shows (for tests and for re-plotting elsewhere) as JSON."""
    with open(path, "w") as handle:
        json.dump({"limit_N": limit_n, "panels": panels}, handle)
