#include "arrays.h"

#include <cstddef>
#include <span>
#include <string>
#include <string_view>

#include "io/trace_csv.h"

namespace rigidtouch::python {

namespace {

// byte offset of a member, from an instance (the structs hold Eigen types, so offsetof is not
// guaranteed to be defined)
template <typename S, typename M>
py::ssize_t OffsetOf(const S& s, const M& m) {
  return reinterpret_cast<const char*>(&m) - reinterpret_cast<const char*>(&s);
}

struct Field {
  std::string name;
  std::string format;  // numpy type string
  py::ssize_t offset;
};

py::dtype MakeDtype(const std::vector<Field>& fields, py::ssize_t itemsize) {
  py::list names, formats, offsets;
  for (const Field& f : fields) {
    names.append(f.name);
    formats.append(f.format);
    offsets.append(f.offset);
  }
  py::dict spec;
  spec["names"] = names;
  spec["formats"] = formats;
  spec["offsets"] = offsets;
  spec["itemsize"] = itemsize;
  return py::dtype::from_args(spec);
}

}  // namespace

py::array BodyStateView(std::vector<BodyState>& bodies, int member, py::handle owner) {
  const BodyState probe;
  const double* first = nullptr;
  py::ssize_t width = 3;
  py::ssize_t offset = 0;
  switch (member) {
    case 0:
      offset = OffsetOf(probe, probe.x_W);
      break;
    case 1:
      offset = OffsetOf(probe, probe.q_WB);
      width = 4;
      break;
    case 2:
      offset = OffsetOf(probe, probe.v_W);
      break;
    default:
      offset = OffsetOf(probe, probe.w_W);
      break;
  }
  static_assert(sizeof(Quat) == 4 * sizeof(double), "a quaternion is 4 packed doubles");
  if (!bodies.empty()) {
    first = reinterpret_cast<const double*>(reinterpret_cast<const char*>(bodies.data()) + offset);
  }
  const auto n = static_cast<py::ssize_t>(bodies.size());
  return py::array(
      py::dtype::of<double>(), {n, width},
      {static_cast<py::ssize_t>(sizeof(BodyState)), static_cast<py::ssize_t>(sizeof(double))},
      first, owner);
}

py::dtype ContactDtype() {
  const Contact c;
  const std::vector<Field> fields = {
      {"id", "i4", OffsetOf(c, c.id)},
      {"geom_a", "i4", OffsetOf(c, c.geom_a)},
      {"geom_b", "i4", OffsetOf(c, c.geom_b)},
      {"body_a", "i4", OffsetOf(c, c.body_a)},
      {"body_b", "i4", OffsetOf(c, c.body_b)},
      {"p_W", "(3,)f8", OffsetOf(c, c.p_W)},
      {"n_W", "(3,)f8", OffsetOf(c, c.n_W)},
      {"depth_m", "f8", OffsetOf(c, c.depth_m)},
      {"pair_points", "i4", OffsetOf(c, c.pair_points)},
      {"phase", "i4", OffsetOf(c, c.phase)},
      {"is_new", "?", OffsetOf(c, c.is_new)},
      {"sticking", "?", OffsetOf(c, c.sticking)},
      {"normal_force_N", "f8", OffsetOf(c, c.normal_force_N)},
      {"friction_force_N_W", "(3,)f8", OffsetOf(c, c.friction_force_N_W)},
      {"impulse_Ns", "f8", OffsetOf(c, c.impulse_Ns)},
      {"group", "i4", OffsetOf(c, c.group)},
  };
  static_assert(sizeof(ContactPhase) == 4, "phase is viewed as int32");
  static_assert(sizeof(bool) == 1, "flags are viewed as numpy bool");
  return MakeDtype(fields, sizeof(Contact));
}

py::array ContactView(const std::vector<Contact>& contacts, int count, py::handle owner) {
  py::array view(ContactDtype(), {static_cast<py::ssize_t>(count)},
                 {static_cast<py::ssize_t>(sizeof(Contact))}, contacts.data(), owner);
  // the next tick rewrites them: a view to read, not a place to write
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

py::dtype TraceDtype() {
  const TraceSample s;
  const auto vec = [&s](const Vec3& v, int k) {
    return OffsetOf(s, v) + static_cast<py::ssize_t>(k * sizeof(double));
  };
  // the trace CSV's columns, in its order (io::TraceColumns); checked against it below
  const std::vector<Field> fields = {
      {"time_s", "f8", OffsetOf(s, s.time_s)},
      {"tool_x_m", "f8", vec(s.tool_position_m, 0)},
      {"tool_y_m", "f8", vec(s.tool_position_m, 1)},
      {"tool_z_m", "f8", vec(s.tool_position_m, 2)},
      {"tool_vx_mps", "f8", vec(s.tool_velocity_mps, 0)},
      {"tool_vy_mps", "f8", vec(s.tool_velocity_mps, 1)},
      {"tool_vz_mps", "f8", vec(s.tool_velocity_mps, 2)},
      {"penalty_fx_N", "f8", vec(s.penalty_force_N, 0)},
      {"penalty_fy_N", "f8", vec(s.penalty_force_N, 1)},
      {"penalty_fz_N", "f8", vec(s.penalty_force_N, 2)},
      {"impulsive_fx_N", "f8", vec(s.impulsive_force_N, 0)},
      {"impulsive_fy_N", "f8", vec(s.impulsive_force_N, 1)},
      {"impulsive_fz_N", "f8", vec(s.impulsive_force_N, 2)},
      {"device_fx_N", "f8", vec(s.device_force_N, 0)},
      {"device_fy_N", "f8", vec(s.device_force_N, 1)},
      {"device_fz_N", "f8", vec(s.device_force_N, 2)},
      {"hand_fx_N", "f8", vec(s.hand_force_N, 0)},
      {"hand_fy_N", "f8", vec(s.hand_force_N, 1)},
      {"hand_fz_N", "f8", vec(s.hand_force_N, 2)},
      {"wall_nx", "f8", vec(s.wall_normal, 0)},
      {"wall_ny", "f8", vec(s.wall_normal, 1)},
      {"wall_nz", "f8", vec(s.wall_normal, 2)},
      {"penetration_m", "f8", OffsetOf(s, s.penetration_m)},
      {"tool_contacts", "i4", OffsetOf(s, s.tool_contacts)},
      {"impulses", "i4", OffsetOf(s, s.impulses)},
      {"kinetic_energy_before_J", "f8", OffsetOf(s, s.kinetic_energy_before_J)},
      {"kinetic_energy_after_J", "f8", OffsetOf(s, s.kinetic_energy_after_J)},
      {"clipped", "?", OffsetOf(s, s.clipped)},
      {"tap", "i4", OffsetOf(s, s.tap)},
      {"step", "i8", OffsetOf(s, s.step)},
  };
  static_assert(sizeof(s.tap) == 4 && sizeof(s.tool_contacts) == 4 && sizeof(s.step) == 8);
  const std::span<const std::string_view> columns = io::TraceColumns();
  bool same = columns.size() == fields.size();
  for (std::size_t k = 0; same && k < fields.size(); ++k) same = columns[k] == fields[k].name;
  if (!same) throw std::logic_error("the trace dtype no longer matches the trace CSV's columns");
  return MakeDtype(fields, sizeof(TraceSample));
}

py::array TraceArray(std::vector<TraceSample>&& samples) {
  auto* owned = new std::vector<TraceSample>(std::move(samples));
  py::capsule owner(owned, [](void* p) { delete static_cast<std::vector<TraceSample>*>(p); });
  py::array view(TraceDtype(), {static_cast<py::ssize_t>(owned->size())},
                 {static_cast<py::ssize_t>(sizeof(TraceSample))}, owned->data(), owner);
  view.attr("setflags")(py::arg("write") = false);
  return view;
}

}  // namespace rigidtouch::python
