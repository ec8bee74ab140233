// Compiling an MJCF file with MuJoCo without MuJoCo's run-time sizes (issue 19).
//
// MuJoCo 2.2's compiler allocates an mjData to finish the model, sized by the file's <size>
// element: nconmax contacts, njmax constraint rows (njmax x nv and njmax x njmax dense arrays)
// and a stack of nstack numbers, by default 5 (njmax + nv)^2. rigidtouch uses none of them (it
// sizes its own buffers from the scene), yet they made a 1000-box pile fail to compile ("could
// not create mjData") and took about 1.1 GB for the 100-box pile. So the file is compiled from
// memory with one more <size> element at the end of its root, which MuJoCo reads last: no
// contacts, no constraint rows, and a stack linear in the file's size (enough for the compiler's
// own use: about 12 numbers per degree of freedom), doubled while the compiler reports a stack
// overflow.
#pragma once

#include <mujoco/mujoco.h>

#include <cstddef>
#include <string>
#include <vector>

namespace rigidtouch::io {

/// Offset in `xml` of the root's end tag `</mujoco` (the last one outside comments, CDATA and
/// processing instructions), or std::string::npos when there is none.
std::size_t RootEndTag(const std::string& xml);

/// `xml` with `<size nconmax="0" njmax="0" nstack="N"/>` inserted before the root's end tag, or
/// an empty string when the text has no `</mujoco>` end tag (then it is compiled as it is).
std::string WithMinimalSolverSizes(const std::string& xml, long nstack);

/// The initial stack size for a file of this text: linear in its number of elements.
long InitialStackSize(const std::string& xml);

/// A number attribute of an MJCF text whose value holds a number that is not finite.
struct NonFiniteValue {
  std::string element;    // "geom"
  std::string attribute;  // "mass"
  std::string value;      // "nan", "0 inf 0", "1e999"
  int line = 0;           // 1-based line of the attribute
};

/// The first attribute of `xml` (outside comments, CDATA and processing instructions) whose value
/// is a list of numbers with one that is not finite (nan, inf, infinity with any sign or case, or
/// a number beyond a double's range such as 1e999), or an empty `element` when there is none.
/// Names and references to other elements (name, class, body, joint, mesh, file ...) are text and
/// are not checked. MuJoCo 2.2.2 warns about a NaN and then uses its default for the value, and
/// takes an infinity as it is: rigidtouch refuses both before compiling.
NonFiniteValue FindNonFiniteValue(const std::string& xml);

/// The `file` attribute of every <include> element of `xml`, in order.
std::vector<std::string> IncludedFiles(const std::string& xml);

/// Compiles the MJCF file at `path` with MuJoCo (includes and assets resolved relative to it, as
/// mj_loadXML does) with the minimal solver sizes above. Returns nullptr and MuJoCo's message in
/// `error` on failure. The returned model has nconmax = njmax = 0, so an mj_makeData on it holds
/// only the model's own per-object arrays and the small stack.
mjModel* CompileWithoutSolverSizes(const std::string& path, char* error, int error_size);

}  // namespace rigidtouch::io
