// Files Penumbra ships beside its binary: the Blender script and the report
// script (harness/), the scenes (scenes/). They are found relative to the
// running executable, never through a path compiled in, so a build folder
// and a `cmake --install` prefix both work:
//   <dir of the executable>/share/penumbra/RELATIVE      (build folder)
//   <dir of the executable>/../share/penumbra/RELATIVE   (installed: bin/, share/)
// PENUMBRA_DATA_DIR, when set, is looked in first. A process that is not
// the penumbra binary (the Python module, python/) sets
// PENUMBRA_EXECUTABLE_DIR to the folder the binary lies in.
#pragma once

#include <string>

namespace penumbra {

// The absolute path of a shipped file ("harness/report.py"), or the first
// candidate when none exists (the caller reports it as missing).
std::string data_file(const std::string& relative);

// The folder of the running executable (from /proc/self/exe), or
// PENUMBRA_EXECUTABLE_DIR when set.
std::string executable_folder();

}  // namespace penumbra
