// MuJoCo's and Qhull's messages about a scene, in rigidtouch's words (issue 51): MuJoCo's
// compiler reports "Error: ..." with an "Object name = N, id = I, line = L" or "Element 'E',
// line L" trailer, and Qhull, which MuJoCo runs for every mesh's convex hull, prints its own
// report (QH codes, its options, a request to mail qhull_bug@) straight to stderr.
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace rigidtouch::io {

/// The reason for a failed compile, as rigidtouch says it: MuJoCo's `error` without its
/// "Error:" prefix and trailer, with the element and line it names; a Qhull failure (`error`
/// "qhull error") names the mesh and says why its convex hull cannot be built, with the QH code of
/// `qhull_report` (what Qhull printed) for reference. Never quotes Qhull's report itself.
std::string TranslateCompileError(std::string_view error, std::string_view qhull_report);

/// Runs `compile` with the process's stderr (file descriptor 2) sent to a temporary file, and
/// returns what was written there (at most 4 KiB): Qhull's report, kept from the terminal. When
/// stderr cannot be redirected, runs `compile` as it is and returns an empty string.
std::string WithStderrCaptured(const std::function<void()>& compile);

}  // namespace rigidtouch::io
