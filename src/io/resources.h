// Files shipped with rigidtouch (scenes, plot scripts), found at run time.
#pragma once

#include <string>

namespace rigidtouch::io {

/// Path of a shipped file given relative to the project root, e.g. "scenes/wall.xml". Looks in
/// $RIGIDTOUCH_DATA_DIR, then the installed data directory, then the source tree the binary was
/// built from. Throws Error naming the places it looked.
std::string ShippedFile(const std::string& relative);

}  // namespace rigidtouch::io
