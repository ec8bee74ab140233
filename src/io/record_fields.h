// The field tables of the records that leave the program: a device state, a device command and a
// trace row. Each is written once here, in file order, and read by every format that carries the
// record: the device record (io/device_record.cc, a state and a command per row), the trace CSV
// (io/trace_csv.cc) and the device protocol's datagrams (device/udp_protocol.cc), which send the
// fields that carry a wire offset. A field added here reaches every format; a format whose layout
// is fixed (the datagrams) takes it only with an offset.
//
// A visitor is called as visit(field, member) for each field in order, with the record's member
// (const when the record is); member types: bool, int, std::int64_t, std::uint32_t,
// std::uint64_t, double, Vec3, Quat.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "rigidtouch/trace.h"
#include "rigidtouch/types.h"

namespace rigidtouch::io {

struct RecordField {
  // a scalar's column name; a vector's columns are name + x, y, z and a quaternion's name + w, x,
  // y, z, each followed by "_" + unit when the unit is not empty
  std::string_view name;
  std::string_view unit;
  // byte offset of the value in the device protocol's datagram (little-endian: u64, u32, f64,
  // 3 f64, 4 f64 w x y z); -1: not sent. A bool is bit `wire_bit` of the u32 at the offset
  int wire_offset = -1;
  std::uint32_t wire_bit = 0;
};

/// The device protocol's command flags (docs/device-protocol.md, "Command").
inline constexpr std::uint32_t kWireFlagSafeFallback = 1u << 0;
inline constexpr std::uint32_t kWireFlagClipped = 1u << 1;

/// DeviceState (or const DeviceState).
template <class State, class Visit>
void VisitStateFields(State& s, Visit&& visit) {
  visit(RecordField{"sequence", "", 40}, s.sequence);
  visit(RecordField{"time", "s", 48}, s.time_s);
  visit(RecordField{"valid", ""}, s.valid);
  visit(RecordField{"fresh", ""}, s.fresh);
  visit(RecordField{"buttons", "", 160}, s.buttons);
  visit(RecordField{"", "m", 56}, s.position_m);
  visit(RecordField{"q", "", 80}, s.orientation);
  visit(RecordField{"v", "mps", 112}, s.velocity_mps);
  visit(RecordField{"w", "radps", 136}, s.angular_velocity_radps);
}

/// DeviceCommand (or const DeviceCommand).
template <class Command, class Visit>
void VisitCommandFields(Command& c, Visit&& visit) {
  visit(RecordField{"command_sequence", "", 40}, c.sequence);
  visit(RecordField{"f", "N", 48}, c.force_N);
  visit(RecordField{"t", "Nm", 72}, c.torque_Nm);
  visit(RecordField{"penalty_f", "N"}, c.penalty_force_N);
  visit(RecordField{"impulsive_f", "N"}, c.impulsive_force_N);
  visit(RecordField{"clipped", "", 96, kWireFlagClipped}, c.clipped);
  visit(RecordField{"safe_fallback", "", 96, kWireFlagSafeFallback}, c.safe_fallback);
}

/// TraceSample (or const TraceSample): the trace CSV's columns.
template <class Sample, class Visit>
void VisitTraceFields(Sample& s, Visit&& visit) {
  visit(RecordField{"time", "s"}, s.time_s);
  visit(RecordField{"tool_", "m"}, s.tool_position_m);
  visit(RecordField{"tool_v", "mps"}, s.tool_velocity_mps);
  visit(RecordField{"penalty_f", "N"}, s.penalty_force_N);
  visit(RecordField{"impulsive_f", "N"}, s.impulsive_force_N);
  visit(RecordField{"device_f", "N"}, s.device_force_N);
  visit(RecordField{"hand_f", "N"}, s.hand_force_N);
  visit(RecordField{"wall_n", ""}, s.wall_normal);
  visit(RecordField{"penetration", "m"}, s.penetration_m);
  visit(RecordField{"tool_contacts", ""}, s.tool_contacts);
  visit(RecordField{"impulses", ""}, s.impulses);
  visit(RecordField{"kinetic_energy_before", "J"}, s.kinetic_energy_before_J);
  visit(RecordField{"kinetic_energy_after", "J"}, s.kinetic_energy_after_J);
  visit(RecordField{"clipped", ""}, s.clipped);
  visit(RecordField{"tap", ""}, s.tap);
  visit(RecordField{"step", ""}, s.step);
}

/// Appends the column names of one field (three for a Vec3, four for a Quat, else one).
template <class T>
void AppendColumnNames(const RecordField& f, const T&, std::vector<std::string>& out) {
  const auto column = [&](std::string_view component) {
    std::string name(f.name);
    name += component;
    if (!f.unit.empty()) (name += '_') += f.unit;
    out.push_back(std::move(name));
  };
  if constexpr (std::is_same_v<T, Vec3>) {
    for (const char* axis : {"x", "y", "z"}) column(axis);
  } else if constexpr (std::is_same_v<T, Quat>) {
    for (const char* axis : {"w", "x", "y", "z"}) column(axis);
  } else {
    column("");
  }
}

/// Column names kept for the program's lifetime, with views into them (what RecordColumns and
/// TraceColumns return).
struct ColumnNames {
  std::vector<std::string> names;
  std::vector<std::string_view> views;
};

/// The column names of a record, from the function that visits its fields (called as
/// visit_fields(record, visitor)).
template <class Record, class VisitFields>
ColumnNames MakeColumnNames(VisitFields visit_fields) {
  ColumnNames c;
  const Record record{};
  visit_fields(record, [&c](const RecordField& f, const auto& value) {
    AppendColumnNames(f, value, c.names);
  });
  // a moved vector keeps its elements where they are, so the views stay valid in the result
  c.views.assign(c.names.begin(), c.names.end());
  return c;
}

}  // namespace rigidtouch::io
