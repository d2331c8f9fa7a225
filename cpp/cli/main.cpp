#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

#include "cli/cli.h"
#include "cli/exit_codes.h"
#include "util/data_files.h"

namespace {

bool wants_python(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    const std::string_view a = argv[k];
    if (a == "--methods-from" || a.starts_with("--methods-from=")) return true;
  }
  return false;
}

// User methods are Python functions (docs/python.md): a command that names
// a file of them runs as `python3 -m penumbra ARGS`, which registers them
// and runs the same command line in its process. The package is found
// beside this binary (<build>/python) or where Debian's Python looks.
int exec_python(int argc, char** argv) {
  const std::filesystem::path package =
      std::filesystem::path(penumbra::executable_folder()) / "python";
  if (std::filesystem::exists(package / "penumbra")) {
    const char* old = std::getenv("PYTHONPATH");
    const std::string path = package.string() + (old && *old ? ":" + std::string(old) : "");
    ::setenv("PYTHONPATH", path.c_str(), 1);
  }
  std::vector<char*> args{const_cast<char*>(PENUMBRA_PYTHON_EXECUTABLE), const_cast<char*>("-m"),
                          const_cast<char*>("penumbra")};
  for (int k = 1; k < argc; ++k) args.push_back(argv[k]);
  args.push_back(nullptr);
  ::execv(PENUMBRA_PYTHON_EXECUTABLE, args.data());
  std::cerr << "penumbra: --methods-from runs " << PENUMBRA_PYTHON_EXECUTABLE
            << " -m penumbra, which failed to start: " << std::strerror(errno) << "\n";
  return penumbra::kExitBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  // A closed standard stream (a job scheduler, `<&-`) would hand fd 0-2 to
  // the next file opened, and output meant for a terminal would land in it.
  for (int fd = 0; fd <= 2; ++fd)
    if (::fcntl(fd, F_GETFD) == -1) ::open("/dev/null", fd == 0 ? O_RDONLY : O_WRONLY);
  if (wants_python(argc, argv)) return exec_python(argc, argv);
  return penumbra::run_cli(argc, argv, std::cout, std::cerr);
}
