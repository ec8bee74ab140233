// Output files (traces, tables, study logs): checked before a run starts, so that a bad path costs
// nothing, and written so that a failure (disk full, file size limit) leaves no partial or
// temporary file and never replaces anything but a regular file.
#pragma once

#include <string>
#include <string_view>

#include "rigidtouch/types.h"

namespace rigidtouch::io {

/// An output file could not be written after the work started: disk full (ENOSPC), the file size
/// limit (`ulimit -f`, EFBIG), an I/O error. The command-line tool exits with code 4 for it; a
/// bad output path found before the run is a plain Error (exit code 2).
class OutputError : public Error {
 public:
  using Error::Error;
};

/// Throws Error "cannot write <what> '<path>': <reason>" unless a file can be written at `path`:
/// its folder exists and is writable, and `path` is absent or a regular file that is writable. A
/// symbolic link (even to a regular file), FIFO, device, socket or folder is refused, so that
/// writing never replaces one or writes through one. `what` names the file ("trace file").
void CheckOutputPath(const std::string& path, std::string_view what);

/// Throws Error naming `dir` unless files can be written into it: it is a writable folder, or it
/// is absent and its nearest existing ancestor is a writable folder (it will be created).
void CheckOutputDir(const std::string& dir, std::string_view what);

/// Writes `bytes` to `path` atomically: into a temporary file in the same folder, every write
/// checked, fsync and close checked, then renamed over `path`. `path` is checked again as
/// CheckOutputPath does (a bad path throws Error). A failed write throws OutputError naming the
/// path and the reason (EFBIG says the file size limit was reached, ENOSPC that the disk is full)
/// and removes the temporary file; `path` is left as it was.
void WriteFileAtomically(const std::string& path, std::string_view bytes, std::string_view what);

/// The system's reason for a failed write, with a hint for the file size limit and a full disk.
std::string WriteFailureReason(int error_number);

/// Makes a write past the file size limit (`ulimit -f`) fail with EFBIG, which the writers
/// report, instead of killing the process with SIGXFSZ. For programs (the command-line tool calls
/// it first thing); a library does not change signal dispositions on its own.
void IgnoreFileSizeSignal();

}  // namespace rigidtouch::io
