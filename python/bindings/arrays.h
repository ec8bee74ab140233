// numpy views of the engine's arrays: body states, contacts and trace samples, with structured
// dtypes whose field offsets are those of the C++ structs, so no element is copied.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <vector>

#include "rigidtouch/rigidtouch.h"

namespace rigidtouch::python {

namespace py = pybind11;

/// Field `member` (3 or 4 doubles) of every BodyState in `bodies`, as an (n, width) view that
/// keeps `owner` alive. Writable: the state can be set from Python between ticks.
py::array BodyStateView(std::vector<BodyState>& bodies, int member, py::handle owner);

/// The first `count` contacts as a read-only structured view (dtype ContactDtype()).
py::array ContactView(const std::vector<Contact>& contacts, int count, py::handle owner);

/// The structured dtype of a contact: id, geom_a, geom_b, body_a, body_b, p_W (3), n_W (3),
/// depth_m, pair_points, phase (0 colliding, 1 resting), is_new, sticking, normal_force_N,
/// friction_force_N_W (3), impulse_Ns, group.
py::dtype ContactDtype();

/// The structured dtype of a trace sample: the trace CSV's columns, same names and units.
py::dtype TraceDtype();

/// Takes `samples` over and returns them as a read-only structured array (TraceDtype()) that
/// owns them: no copy.
py::array TraceArray(std::vector<TraceSample>&& samples);

/// Adds _fit_material (python/bindings/material.cc): `material fit` on numpy arrays.
void DefineMaterial(py::module_& m);

}  // namespace rigidtouch::python
