#include "util/data_files.h"

#include <cstdlib>
#include <filesystem>
#include <vector>

namespace penumbra {
namespace fs = std::filesystem;

std::string executable_folder() {
  if (const char* dir = std::getenv("PENUMBRA_EXECUTABLE_DIR"); dir && *dir) return dir;
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

std::string data_file(const std::string& relative) {
  std::vector<fs::path> candidates;
  if (const char* dir = std::getenv("PENUMBRA_DATA_DIR"); dir && *dir)
    candidates.push_back(fs::path(dir) / relative);
  const fs::path exe_dir = executable_folder();
  candidates.push_back(exe_dir / "share" / "penumbra" / relative);
  candidates.push_back(exe_dir.parent_path() / "share" / "penumbra" / relative);
  for (const fs::path& p : candidates) {
    std::error_code ec;
    if (fs::exists(p, ec)) return p.lexically_normal().string();
  }
  return candidates.front().lexically_normal().string();
}

}  // namespace penumbra
